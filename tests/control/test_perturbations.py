"""The plant's perturbations (control/perturbations.py) against independent derivations: masses and a
payload against Pinocchio's inertia algebra, a push against the momentum it must add, the IMU delay
against the unperturbed plant; and the warning signs read from a run's log (control/thresholds.py)."""

from __future__ import annotations

import numpy as np
import pytest

import quadruped_dyn.control  # noqa: F401  (sets MUJOCO_GL before MuJoCo is imported)

mujoco = pytest.importorskip("mujoco", reason="MuJoCo is in the 'xlib' extra: pip install 'quadruped_dyn[xlib]'")

import pinocchio as pin  # noqa: E402

from quadruped_dyn.control.perturbations import Perturbation, perturbed  # noqa: E402
from quadruped_dyn.control.plant import PUSH_DURATION_S, Command, PlantOptions, build_plant  # noqa: E402
from quadruped_dyn.control.run import Trace  # noqa: E402
from quadruped_dyn.control.thresholds import PERSIST_S, first_crossings  # noqa: E402
from quadruped_dyn.errors import InputError  # noqa: E402
from quadruped_dyn.experiment.gait import GAITS, gait_plan  # noqa: E402
from quadruped_dyn.model.state import GRAVITY_W  # noqa: E402
from quadruped_dyn.tolerances import REL_TOL_TERMS  # noqa: E402

#: With RK4 (explicit: implicitfast and Euler treat the joints' damping implicitly, which moves the trunk's
#: momentum by ~2e-4 of it here) the external forces add to the momentum to round-off over 100 steps.
MOMENTUM_REL_TOL = 1e-9


@pytest.fixture(scope="module")
def plant(paper):
    return build_plant(paper, gait_plan(paper, GAITS["walk"]))


def test_mass_scales_change_the_plant_not_the_original(plant, paper):
    p = perturbed(plant, Perturbation(trunk_mass_scale=1.2, link_mass_scale=0.8))
    expected = 1.2 * paper.trunk.mass + 0.8 * (paper.total_mass - paper.trunk.mass)
    assert mujoco.mj_getTotalmass(p.model) == pytest.approx(expected, rel=REL_TOL_TERMS)
    assert mujoco.mj_getTotalmass(plant.model) == pytest.approx(paper.total_mass, rel=REL_TOL_TERMS)


def test_payload_is_pinocchios_sum_of_inertias(plant, paper):
    r = np.array([0.1, -0.05, 0.02])
    p = perturbed(plant, Perturbation(payload_kg=2.0, payload_offset_m=tuple(r)))
    expected = paper.model.inertias[1] + pin.Inertia(2.0, r, np.zeros((3, 3)))
    b = int(p.model.jnt_bodyid[0])
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, p.model.body_iquat[b])
    R = R.reshape(3, 3)
    assert p.model.body_mass[b] == pytest.approx(expected.mass, rel=REL_TOL_TERMS)
    np.testing.assert_allclose(p.model.body_ipos[b], expected.lever, atol=REL_TOL_TERMS)
    np.testing.assert_allclose(R @ np.diag(p.model.body_inertia[b]) @ R.T, expected.inertia,
                               atol=REL_TOL_TERMS * np.abs(expected.inertia).max())


def test_push_adds_its_impulse_to_the_momentum(paper):
    """Robot in the air (no contact), joints free: M v_com(t) = M g t + J once the push (``Plant.push``, as the
    loop applies ``LoopOptions.push`` at each tick) is over."""
    J = np.array([3.0, -2.0, 1.0])
    p = build_plant(paper, gait_plan(paper, GAITS["walk"]), PlantOptions(integrator="rk4"))
    q = np.concatenate([[0, 0, 1.0], [0, 0, 0, 1.0], paper.standing_q])
    p.set_state(q, np.zeros(18))
    steps = 100
    for k in range(steps):
        p.push(J, 0.005, k * p.options.timestep)
        p.step(Command(np.zeros(12)), 1)
    mujoco.mj_forward(p.model, p.data)  # the velocity stage at the final state
    mujoco.mj_subtreeVel(p.model, p.data)
    assert not p.data.ncon
    M = p.model.body_subtreemass[1]
    assert M == pytest.approx(paper.total_mass, rel=REL_TOL_TERMS)
    momentum = M * p.data.subtree_linvel[1]
    expected = M * np.asarray(GRAVITY_W) * steps * p.options.timestep + J
    assert steps * p.options.timestep > 0.005 + PUSH_DURATION_S
    np.testing.assert_allclose(momentum, expected, rtol=0, atol=MOMENTUM_REL_TOL * np.linalg.norm(expected))


#: The same configuration over a step's ground and over the flat one, shifted by its height: the same penetration,
#: so the contact points differ by the height to the round-off of positions of ~1 m.
CONTACT_HEIGHT_TOL_M = 1e-12
#: How far the lowest foot sphere reaches into the ground (m): a contact, far less than the sphere.
PENETRATION_M = 1e-4


def _contacts(plant, q: np.ndarray) -> dict[int, tuple[float, str]]:
    """Per foot in contact: (the contact point's z, the ground geom's name) at configuration q."""
    plant.set_state(q, np.zeros(18))
    out = {}
    for c in plant.data.contact[: plant.data.ncon]:
        for foot, ground in ((c.geom1, c.geom2), (c.geom2, c.geom1)):
            hit = np.nonzero(plant.foot_geoms == foot)[0]
            if hit.size:
                out[int(hit[0])] = (float(c.pos[2]), plant.model.geom(ground).name)
    return out


@pytest.mark.parametrize("h", [0.05, -0.03])
def test_a_ground_step_moves_the_feets_contact_by_its_height(paper, h):
    """From x0 on the ground is h higher: the feet touch it h higher than the flat floor, and before x0 as on it."""
    plan = gait_plan(paper, GAITS["walk"])
    flat, x0 = build_plant(paper, plan), 0.4
    step = build_plant(paper, plan, PlantOptions(ground_step=(x0, h)))
    q = np.concatenate([[x0 + 1.0, 0.0, 0.0], [0, 0, 0, 1.0], paper.standing_q])
    flat.set_state(q, np.zeros(18))
    q[2] = flat.floor_z - PENETRATION_M - (flat.foot_positions()[:, 2].min() - flat.foot_radius)
    on_flat = _contacts(flat, q)
    assert on_flat and {g for _, g in on_flat.values()} == {"quadruped_dyn_floor"}
    on_step = _contacts(step, q + np.r_[0, 0, h, np.zeros(16)])
    assert on_step.keys() == on_flat.keys()
    assert {g for _, g in on_step.values()} == {"quadruped_dyn_step" if h > 0 else "quadruped_dyn_floor"}
    for foot, (z, _) in on_flat.items():
        assert on_step[foot][0] - z == pytest.approx(h, abs=CONTACT_HEIGHT_TOL_M)
    before = q.copy()
    before[0] = x0 - 1.0  # the whole robot before the step: the start's ground
    assert {f: z for f, (z, _) in _contacts(step, before).items()} == pytest.approx({f: z for f, (z, _) in on_flat.items()},
                                                                                    abs=CONTACT_HEIGHT_TOL_M)


def test_imu_delay_is_the_reading_of_ticks_before_and_noise_its_spread(plant, paper):
    nominal, late = plant, perturbed(plant, Perturbation(imu_delay_ticks=3))
    exact = perturbed(plant, Perturbation())
    q = np.concatenate([[0, 0, 1.0], [0, 0, 0, 1.0], paper.standing_q])
    seen, truth = [], []
    tau = np.linspace(-1, 1, 12)
    for pl in (exact, late):
        pl.set_state(q, np.zeros(18))
    for _ in range(10):
        truth.append(exact.measure().omega_b)
        seen.append(late.measure().omega_b)
        for pl in (exact, late):
            pl.step(Command(tau), 1)
    assert np.abs(np.array(truth)).max() > 0  # the trunk turns: the comparison is not of zeros
    np.testing.assert_array_equal(np.array(seen[3:]), np.array(truth[:-3]))
    assert nominal.measure().omega_b is not None
    noisy = perturbed(plant, Perturbation(imu_noise_rad_s=0.05, seed=1))
    noisy.set_state(q, np.zeros(18))
    errors = np.array([noisy.measure().omega_b - noisy.data.qvel[3:6] for _ in range(2000)])
    assert errors.std() == pytest.approx(0.05, rel=0.1)


def test_bad_perturbation_is_input_error(plant):
    with pytest.raises(InputError, match="trunk_mass_scale"):
        perturbed(plant, Perturbation(trunk_mass_scale=0.0))
    with pytest.raises(InputError, match="payload_offset_m"):
        perturbed(plant, Perturbation(payload_offset_m=(0.0, 0.0)))  # type: ignore[arg-type]


def _trace(n: int = 100) -> Trace:
    weight = 100.0
    f = np.zeros((n, 4, 3))
    f[:, :, 2] = weight / 4
    R = np.tile(np.eye(3), (n, 1, 1))
    return Trace("x", np.arange(n) * 1e-3, *(np.zeros((n, 12)) for _ in range(5)), np.zeros((n, 3)), R,
                 np.zeros((n, 4, 3)), f, np.ones((n, 4), dtype=bool), [(0, 1, 2, 3)] * n, *(np.zeros(n) for _ in range(3)))


def test_first_sign_is_the_earliest_that_held():
    dt, effort, weight = 1e-3, np.full(12, 10.0), 100.0
    held = int(round(PERSIST_S / dt))
    t = _trace()
    t.tau[10 : 10 + held - 1, 4] = 11.0  # a saturation shorter than PERSIST_S: not a sign
    t.tau[60:, 4] = 11.0
    tilt = np.radians(25.0)
    t.trunk_R[30:] = [[1, 0, 0], [0, np.cos(tilt), -np.sin(tilt)], [0, np.sin(tilt), np.cos(tilt)]]
    out = first_crossings(t, effort, weight, dt)
    assert out["first"] == "trunk tilt" and out["first_at_s"] == pytest.approx(0.030)
    assert out["crossed"] == {"stance foot unloaded": None, "torque saturation": pytest.approx(0.060), "foot slip": None,
                              "trunk tilt": pytest.approx(0.030)}
    t.touching[5:, 2] = False  # a stance foot off the ground
    t.feet[40:, 1, 0] = np.arange(60) * 0.5 * dt  # a stance foot sliding at 0.5 m/s from 40 ms (the first step at 41 ms)
    out = first_crossings(t, effort, weight, dt)
    assert out["first"] == "stance foot unloaded" and out["first_at_s"] == pytest.approx(0.005)
    assert out["crossed"]["foot slip"] == pytest.approx(0.041)
