"""Full-coordinate rigid-contact dynamics along a gait plan: the physics check (docs/experiment.md §5).

Nothing here uses the paper's model: the robot is Pinocchio's free-flyer model (q = (p, quat x
y z w, 12 joints), v = (v_b, omega_b, qd), project order) with the stance feet as rigid point
contacts, a = vdot from the KKT system of ``PinocchioReference.constrained_forward_dynamics``
(``crba``, ``nonLinearEffects``, contact Jacobians, classical foot accelerations). The stance
switches at the plan's phases: a foot lifts when its phase says so, whatever its force, and a
foot that lands is stopped by a plastic impact (v+ = v- - M^-1 Jc^T (Jc M^-1 Jc^T)^-1 Jc v-, all
stance feet), then held where it landed. Integrated with the same method and tolerances as the
reduced model (``simulate``), under the same torque law on the 12 joints; the trunk roll has
no actuator here.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.simulate import (
    FALLEN_TRUNK_M,
    RTOL,
    IkTorques,
    Progress,
    Run,
    TorqueLaw,
    check_times,
    integrate_phases,
)
from quadruped_dyn.model.state import quaternion_rotation
from quadruped_dyn.references.pinocchio import PinocchioReference


def _derivative(q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """d/dt of (q (19,), v (18,)): pdot = R v_b, quaternion rate 1/2 quat (x) (omega, 0), qd."""
    quat = q[3:7] / np.linalg.norm(q[3:7])
    x, y, z, w = quat
    omega = v[3:6]
    quat_dot = 0.5 * np.array([[w, -z, y], [z, w, -x], [-y, x, w], [-x, -y, -z]]) @ omega
    return np.concatenate([quaternion_rotation(q[3:7]) @ v[:3], quat_dot, v[6:], a])


def _impact(ref: PinocchioReference, q: np.ndarray, v: np.ndarray, stance: tuple[int, ...]) -> np.ndarray:
    """Velocity after a plastic impact of all stance feet (their velocities go to zero)."""
    M = ref.mass_matrix(q)
    Jc = ref.contact_jacobian(q, stance)
    MinvJt = np.linalg.solve(M, Jc.T)
    return v - MinvJt @ np.linalg.solve(Jc @ MinvJt, Jc @ v)


def touch_down(ref: PinocchioReference, stance: tuple[int, ...], y: np.ndarray) -> np.ndarray:
    """The state (q (19,), v (18,)) after a stance switch: the quaternion normalised, the
    velocity after the plastic impact of the new stance (``_impact``)."""
    q = y[:19].copy()
    q[3:7] /= np.linalg.norm(q[3:7])
    return np.concatenate([q, _impact(ref, q, y[19:], stance)])


def initial_state(plan: Plan, ik: IkTorques, ref: PinocchioReference,
                  initial: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """(q (19,), v (18,)) at t = 0: the IK state of the plan's first stance with the plan's
    trunk position, or ``initial``."""
    if initial is not None:
        return np.concatenate([np.asarray(initial[0], dtype=float), np.asarray(initial[1], dtype=float)])
    stance0 = plan.gait.stance(0.0)
    ref0, _ = ik(0.0, stance0)
    q0, v0, _ = ref.reduced_motion(stance0, ref0.q_r, ref0.qd_r, ref0.qdd_r, np.array([0.0, 0.0, 0.0, 1.0]))
    q0[:3] = plan.trunk(0.0)[0]
    return np.concatenate([q0, v0])


def _kkt_accelerations(ref: PinocchioReference, q: np.ndarray, v: np.ndarray, tau: np.ndarray,
                       stance: tuple[int, ...]) -> np.ndarray:
    """a = vdot (18,) of ``PinocchioReference.constrained_forward_dynamics``: the same Pinocchio
    calls in the same order on the same inputs (so the same values, bit for bit), with q and v
    converted to Pinocchio's order once instead of once per quantity -- this runs at every
    right-hand-side evaluation of the physics check."""
    import pinocchio as pin

    from quadruped_dyn.references.pinocchio import LWA

    model, data, robot = ref.model, ref.data, ref.robot
    qp, vp = ref.pin_q(q), ref.pin_v(v)
    perm = ref.perm
    M = np.asarray(pin.crba(model, data, qp))[np.ix_(perm, perm)]
    h = np.asarray(pin.nonLinearEffects(model, data, qp, vp))[perm]
    pin.computeJointJacobians(model, data, qp)
    pin.framesForwardKinematics(model, data, qp)
    ids = robot.foot_frame_ids
    rows = [pin.getFrameJacobian(model, data, ids[i], LWA)[:3] for i in stance]
    Jc = np.vstack(rows)[:, perm] if rows else np.zeros((0, 18))
    if stance:
        pin.forwardKinematics(model, data, qp, vp, np.zeros(model.nv))
        pin.updateFramePlacements(model, data)
        Rb = data.oMi[1].rotation
        R = quaternion_rotation(q[3:7])
        drift = np.concatenate([R @ (Rb.T @ pin.getFrameClassicalAcceleration(model, data, ids[i], LWA).linear)
                                for i in stance])
    else:
        drift = np.zeros(0)
    k = Jc.shape[0]
    K = np.block([[M, Jc.T], [Jc, np.zeros((k, k))]])
    rhs = np.concatenate([np.concatenate([np.zeros(6), tau]) - h, -drift])
    return np.linalg.solve(K, rhs)[:18]


def simulate_rigid(plan: Plan, ik: IkTorques, law: TorqueLaw, horizon: float, dt: float,
                   integrator: str = "dop853", rtol: float = RTOL, progress: Progress | None = None,
                   initial: tuple[np.ndarray, np.ndarray] | None = None,
                   trunk: Callable[[float], np.ndarray] | None = None) -> Run:
    """Integrate the rigid-contact dynamics from the IK state at t = 0 under ``law``; the
    returned ``Run`` holds the 12 joint angles, rates and accelerations, and as closure the
    trunk's distance from the plan's trunk position (m). ``initial`` = (q (19,), v (18,))
    replaces the IK state, ``trunk(t)`` (world position, m) the plan's trunk, for a target
    that is not the plan's (e.g. an optimised gait with the plan's phases)."""
    check_times(plan.gait, horizon, dt, integrator)
    ref = PinocchioReference(plan.robot)
    y = initial_state(plan, ik, ref, initial)
    trunk_at = trunk if trunk is not None else (lambda t: plan.trunk(t)[0])
    evaluations = [0]

    def accel(t: float, y: np.ndarray, stance: tuple[int, ...]) -> np.ndarray:
        evaluations[0] += 1
        q, v = y[:19], y[19:]
        target_t, tau_ik = ik(t, stance)
        tau = law.joints(target_t, tau_ik, q[7:], v[6:])
        a = _kkt_accelerations(ref, q, v, tau, stance)
        if not np.all(np.isfinite(a)):
            raise NumericalError(f"the rigid-contact dynamics are singular at t = {t:.4f} s")
        return a

    def rhs(stance: tuple[int, ...], t: float, y: np.ndarray) -> np.ndarray:
        return _derivative(y[:19], y[19:], accel(t, y, stance))

    out: list[tuple[float, np.ndarray, np.ndarray, float]] = []
    stopped_at = None

    class Fallen(Exception):
        pass

    def record(stance: tuple[int, ...], t: float, y: np.ndarray) -> None:
        a = accel(t, y, stance)
        off = float(np.linalg.norm(y[:3] - trunk_at(t)))
        out.append((t, y.copy(), a, off))
        if off > FALLEN_TRUNK_M:
            raise Fallen

    try:
        integrate_phases(plan, y, horizon, dt, integrator, rtol, rhs, record, switch=partial(touch_down, ref),
                         progress=progress)
    except (Fallen, NumericalError, InputError, np.linalg.LinAlgError):
        stopped_at = float(out[-1][0]) if out else 0.0
    t = np.array([o[0] for o in out])
    Y = np.array([o[1] for o in out]).reshape(-1, 37)
    A = np.array([o[2] for o in out]).reshape(-1, 18)
    return Run(t, Y[:, 7:19], Y[:, 25:], A[:, 6:], np.array([o[3] for o in out]), stopped_at, evaluations[0])
