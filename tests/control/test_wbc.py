"""The whole-body QP controller ``wbc``: its model terms (the generated C) against Pinocchio at
the states it estimated along a run, its leg odometry against MuJoCo's trunk velocity, one walk
cycle (default suite), an infeasible QP (exit 1, one line), and the long runs (slow)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

import quadruped_dyn.control  # noqa: F401  (sets MUJOCO_GL before MuJoCo is imported)

pytest.importorskip("mujoco", reason="MuJoCo is in the 'xlib' extra: pip install 'quadruped_dyn[xlib]'")
pytest.importorskip("proxsuite", reason="proxsuite is in the 'xlib' extra: pip install 'quadruped_dyn[xlib]'")

from quadruped_dyn.cli import main  # noqa: E402
from quadruped_dyn.control import wbc  # noqa: E402
from quadruped_dyn.control.closed_loop import prepare, run_all  # noqa: E402
from quadruped_dyn.control.controllers import GeneratedC, make_controller  # noqa: E402
from quadruped_dyn.control.plan import target_cycle  # noqa: E402
from quadruped_dyn.control.run import LoopOptions, settled_state  # noqa: E402
from quadruped_dyn.math.compare import relative_error  # noqa: E402
from quadruped_dyn.model.robot import load_robot  # noqa: E402
from quadruped_dyn.model.stance import StanceSet  # noqa: E402
from quadruped_dyn.model.state import rotation  # noqa: E402
from quadruped_dyn.references.pinocchio import PinocchioReference  # noqa: E402
from quadruped_dyn.tolerances import REL_TOL_TERMS  # noqa: E402

#: Leg odometry against MuJoCo's trunk velocity (m/s): the feet are soft spheres that roll (a
#: foot's centre moves by radius x its rolling rate) and sink (MuJoCo's soft contact), which the
#: odometry's still-foot assumption ignores; measured on the paper robot's walk: 0.01-0.02 m/s.
ODOMETRY_TOL_M_S = 0.05

@cache  # one run serves the model-term and the MPC checks
def _drive(robot_name: str, gait: str, ticks: int, every: int):
    """The wbc controller driven by hand on the settled plant: its estimated (q, v) and model terms
    every ``every`` ticks, with MuJoCo's true trunk velocity v_b."""
    study = prepare(load_robot(robot_name), gait, ["wbc"], loop=LoopOptions(cycles=1))
    c = GeneratedC(study.robot)
    initial, _ = settled_state(study.plant, study.plan, study.gains, c, study.loop.rate_hz, study.substeps,
                               study.loop.settle_s)
    study.plant.set_state(*initial)
    controller = make_controller("wbc", study.robot, study.gains, c, study.plant.options.mu, study.loop.rate_hz)
    cycle = target_cycle(study.plan, study.loop.rate_hz)
    samples = []
    for k in range(ticks):
        meas = study.plant.measure()
        ref = cycle[k % len(cycle)]
        command = controller.command(ref, StanceSet(ref.stance), meas)
        if k % every == 0:
            samples.append((controller.q.copy(), controller.v.copy(), controller.terms, study.plant.full_state()[1][:3]))
        study.plant.step(command, study.substeps)
    return study, samples

def test_qp_model_terms_are_pinocchios_at_the_estimated_states() -> None:
    study, samples = _drive("paper", "walk", 300, 30)
    ref = PinocchioReference(study.robot)
    for q, v, terms, v_true in samples:
        R = rotation(q)
        J = np.kron(np.eye(4), R.T) @ ref.contact_jacobian(q, (0, 1, 2, 3))
        expected = {"M": ref.mass_matrix(q), "h": ref.nonlinear_effects(q, v), "r": ref.foot_positions(q),
                    "J": J, "Jdv": ref.foot_accelerations(q, v, np.zeros(18)).ravel()}
        for name, value in expected.items():
            got = getattr(terms, name)
            assert np.all(np.isfinite(got)), name
            assert relative_error(got, value) <= REL_TOL_TERMS, name
        assert np.all(np.abs(v[:3] - v_true) < ODOMETRY_TOL_M_S), (v[:3], v_true)

def test_wbc_walks_one_cycle_of_the_paper_robot() -> None:
    study = run_all(prepare(load_robot("paper"), "walk", ["wbc", "pd-diag"], loop=LoopOptions(cycles=1)))
    r = study.results["wbc"]
    assert not r["fell"] and r["stopped"] is None and r["cycles_up"] == 1
    assert np.isfinite(r["tracking"]["rms_rad"]) and r["tracking"]["rms_rad"] < 0.05
    assert r["compute"]["qp_median_us"] > 0 and r["compute"]["c_calls_median_us"] > 0
    # the robot stood on its feet: MuJoCo carried its weight through the foot contacts
    fz = study.traces["wbc"].contact_f[:, :, 2].sum(axis=1)
    weight = study.robot.total_mass * 9.81
    assert abs(np.median(fz) - weight) < 0.1 * weight

def test_infeasible_qp_is_named_and_exits_1(monkeypatch, tmp_path: Path) -> None:
    """Torque limits of 1 mN m (the QP's, not the plant's): no force distribution holds the robot;
    the run stops at the first tick, the files are written, the command exits 1 with one line."""
    monkeypatch.setattr(wbc, "actuator_limit", lambda robot, kind: np.full(12, 1e-3))
    result = CliRunner().invoke(main, ["control", "paper", "--controller", "wbc", "--cycles", "1", "--no-animation",
                                       "--out", str(tmp_path)])
    assert result.exit_code == 1, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in result.output, result.output
    assert "whole-body QP not solved" in errors[0] and "t = 0.000 s" in errors[0], errors[0]

@pytest.mark.parametrize("args", [["--controller", "wbcc"], ["--controller", "wbc", "--kp-per-kg", "-1"]])
def test_bad_controller_or_gains_exit_2(args: list[str], tmp_path: Path) -> None:
    result = CliRunner().invoke(main, ["control", "paper", *args, "--cycles", "1", "--out", str(tmp_path)])
    assert result.exit_code == 2 and len(result.output.strip().splitlines()) == 1, result.output

#: The MPC's force-to-acceleration map composed with the generated dgrf's d lambda / d a against the
#: identity it should give: round-off of two rigid-body evaluations (REL_TOL_TERMS' reason) through one
#: 6 x 6 QR solve of the GRF model (well conditioned on a walking posture); measured on the paper robot's
#: walk: 2e-14; a 1 % error in the MPC's mass gives 1e-2.
MPC_VS_DGRF_TOL = 1e-10


def test_mpc_linearisation_inverts_the_generated_dgrf_at_the_states_of_a_run() -> None:
    """The MPC's input matrix B (forces -> the trunk's angular and the centre of mass's linear
    acceleration, world; from M_full's trunk block at the state) against the generated GRF
    solve's derivative d lambda / d a (``dgrf_<feet>``, C): at the states of a wbc walk, for every
    3-feet stance set (rank 6: the paper's forces f = P lambda balance any trunk wrench), the forces
    d f / d a_b that the GRF model needs for a trunk acceleration a_b (joints' accelerations 0), put
    through B, must give back that acceleration: B R P dlambda/da_b = d(alpha_w, a_com)/d a_b =
    [[0, R], [R, -R [c]x]]. Two independent derivations of the locked-joint dynamics: the MPC's
    composite rigid body and the paper's six body equations, differentiated by CasADi."""
    from quadruped_dyn.codegen.library import CompiledFunction
    from quadruped_dyn.control.mpc import continuous_model, rigid_body
    from quadruped_dyn.math.rigid import skew
    from quadruped_dyn.model.stance import stance_set

    study, samples = _drive("paper", "walk", 300, 30)
    library = GeneratedC(study.robot).library
    stances = [stance_set(name) for name in ("FR+BL+BR", "FL+BL+BR", "FL+FR+BR", "FL+FR+BL")]
    dgrf = {s: CompiledFunction(library, "dgrf_" + s.name.replace("+", "_")) for s in stances}
    worst = 0.0
    for q, v, terms, _ in samples:
        R = rotation(q)
        m, c, I_c = rigid_body(terms.M[:6, :6])
        expected = np.block([[np.zeros((3, 3)), R], [R, -R @ skew(c)]])
        for s in stances:
            _, _, dlam_da = dgrf[s](q, v, np.zeros(18))
            dF_w = np.kron(np.eye(3), R) @ s.selection("paper") @ dlam_da[:, :6]  # world forces per a_b
            _, B = continuous_model(m, R @ I_c @ R.T, [R @ (terms.r[i] - c) for i in s.feet])
            got = B[6:12] @ dF_w
            assert np.all(np.isfinite(got)), s.name
            worst = max(worst, relative_error(got, expected))
    assert worst <= MPC_VS_DGRF_TOL, worst


def test_mpc_rigid_body_is_pinocchios_locked_joint_dynamics() -> None:
    """The MPC's model from the generated M_full's trunk block (m, c, I_c) gives the centre of
    mass's acceleration and the trunk's angular acceleration under given foot forces exactly as
    Pinocchio's full dynamics with the joints' accelerations held at zero, at rest."""
    from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
    from quadruped_dyn.control.mpc import continuous_model, rigid_body
    from quadruped_dyn.model.state import GRAVITY_W, full_q

    robot = load_robot("paper")
    ref = PinocchioReference(robot)
    rng = np.random.default_rng(5)
    for _ in range(3):

        R = pin.rpy.rpyToMatrix(*rng.normal(scale=0.2, size=3))
        q = full_q(R, rng.normal(size=3), robot.standing_q + rng.normal(scale=0.1, size=12))
        f_w = rng.normal(scale=20.0, size=(4, 3)) + [0.0, 0.0, 30.0]
        (M_gen,) = CompiledFunction(compiled_library(robot), "M_full")(q)
        m, c, I_c = rigid_body(M_gen[:6, :6])
        r_w = ref.foot_positions(q) @ R.T - R @ c
        A, B = continuous_model(m, R @ I_c @ R.T, list(r_w))
        xdot = B @ f_w.ravel() + np.concatenate([np.zeros(9), GRAVITY_W])
        # Pinocchio: M_bb vdot_b = J_b^T f_b - G_b with the joints' accelerations 0 (v = 0)
        M, G = ref.mass_matrix(q), ref.gravity(q)
        J_b = np.kron(np.eye(4), R.T) @ ref.contact_jacobian(q, (0, 1, 2, 3))
        vdot_b = np.linalg.solve(M[:6, :6], J_b[:, :6].T @ (f_w @ R).ravel() - G[:6])
        alpha_w = R @ vdot_b[3:]
        a_com = R @ (vdot_b[:3] + np.cross(vdot_b[3:], c))
        assert relative_error(xdot[6:9], alpha_w) <= REL_TOL_TERMS
        assert relative_error(xdot[9:12], a_com) <= REL_TOL_TERMS


# ----------------------------------------------------------------------------- 10 cycles, every robot (slow)
BY_PATH = {"laikago": "laikago_description/urdf/laikago.urdf", "anymal_b": "anymal_b_simple_description/robots/anymal.urdf",
           "b1": "b1_description/urdf/b1.urdf"}


def _robot(name: str):
    from quadruped_dyn.model.registry import example_robot_data_dir

    return load_robot(str(example_robot_data_dir() / BY_PATH[name])) if name in BY_PATH else load_robot(name)


#: Runs where wbc holds but tracks the joints worse than pd-diag (docs/closed_loop.md).
TRACKS_WORSE = {("solo12", "trot"): "0.0129 against 0.0104 in the measured run",
                ("anymal_c", "trot"): "0.0098 against 0.0090 in the measured run: its drivers' PD capped (wbc.PD_LINEAR_RAD)"}


@pytest.mark.slow
@pytest.mark.parametrize("gait", ["walk", "trot"])
@pytest.mark.parametrize("name", ["paper", "solo12", "go2", "go1", "a1", "anymal_c", "hyq", *BY_PATH])
def test_wbc_ten_cycles_tracks_at_least_as_well_as_pd_diag(name: str, gait: str) -> None:
    """wbc holds 10 cycles and tracks the joints at least as well as pd-diag in the same study
    (RMS over the time both ran); docs/closed_loop.md has the numbers."""
    study = run_all(prepare(_robot(name), gait, ["wbc", "pd-diag"], loop=LoopOptions(cycles=10)))
    r = study.results["wbc"]
    assert not r["fell"] and r["stopped"] is None and r["cycles_up"] == 10, r["stopped"]
    a, b = study.traces["wbc"], study.traces["pd-diag"]
    n = min(a.t.size, b.t.size)
    rms = [float(np.sqrt(np.mean((t.q_ref[:n] - t.q[:n]) ** 2))) for t in (a, b)]
    if (name, gait) in TRACKS_WORSE and rms[0] > rms[1]:
        pytest.xfail(f"measured: wbc {rms[0]:.4f} rad against pd-diag's {rms[1]:.4f} ({TRACKS_WORSE[(name, gait)]})")
    assert rms[0] <= rms[1], rms


@pytest.mark.slow
@pytest.mark.parametrize("gait", ["walk", "trot"])
def test_mpc_wbc_ten_cycles_on_the_paper_robot(gait: str) -> None:
    study = run_all(prepare(load_robot("paper"), gait, ["mpc+wbc"], loop=LoopOptions(cycles=10)))
    r = study.results["mpc+wbc"]
    assert not r["fell"] and r["stopped"] is None and r["cycles_up"] == 10, r["stopped"]


#: The push-recovery sample (paper robot's trot, 4 cycles from the settled start): PUSHES pushes drawn with
#: numpy's default_rng(PUSH_SEED), each at a time uniform in 1.2-1.8 s (the third cycle on) with a horizontal
#: direction uniform in [0, 2 pi), the impulse over plant.PUSH_DURATION_S (10 ms).
PUSHES = 20
PUSH_SEED = 0
#: The target's impulse (N s): the smallest at which pd-diag falls in at least half of the pushes (docs/closed_loop.md:
#: it fell in 11/20 at 2.5 N s, 9/20 at 2 N s).
PUSH_IMPULSE_N_S = 2.5
#: The target: mpc+wbc survives 16 of the 20 pushes at that impulse.
PUSH_TARGET_UP = 16


def _pushes(impulse_n_s: float) -> list[tuple[float, float, float, float]]:
    """The sample's pushes: (time s, impulse x y z N s, world), at ``impulse_n_s``."""
    rng = np.random.default_rng(PUSH_SEED)
    out = []
    for _ in range(PUSHES):
        t, heading = float(rng.uniform(1.2, 1.8)), float(rng.uniform(0.0, 2 * np.pi))
        out.append((t, impulse_n_s * float(np.cos(heading)), impulse_n_s * float(np.sin(heading)), 0.0))
    return out


@pytest.mark.slow
def test_push_recovery_on_the_paper_trot() -> None:
    """At PUSH_IMPULSE_N_S pd-diag falls in at least half of the pushes (what makes it the target's impulse);
    mpc+wbc survives PUSH_TARGET_UP of them (xfail with the counts while the target is missed)."""
    up = {"pd-diag": 0, "wbc": 0, "mpc+wbc": 0}
    for push in _pushes(PUSH_IMPULSE_N_S):
        study = run_all(prepare(load_robot("paper"), "trot", list(up), loop=LoopOptions(cycles=4, push=push)))
        for name, r in study.results.items():
            up[name] += not r["fell"] and r["stopped"] is None
    assert up["pd-diag"] <= PUSHES // 2, up
    if up["mpc+wbc"] < PUSH_TARGET_UP:
        pytest.xfail(f"survived of {PUSHES}: {up}")
