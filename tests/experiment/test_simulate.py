"""Forward simulation: reduced dynamics along the gaits (both backends), the stance-closure
projection, and the rigid-contact dynamics of the physics check. Horizons are short: the
CasADi graph costs ~1 ms per call."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.experiment.gait import TROT, WALK, gait_plan
from quadruped_dyn.experiment.paper_experiment import percent_errors
from quadruped_dyn.experiment.rigid_contact import simulate_rigid
from quadruped_dyn.experiment.simulate import (
    CasadiReducedDynamics,
    IkTorques,
    TorqueLaw,
    project_on_stance,
    reduced_dynamics,
    simulate_reduced,
)
from tests.conftest import assert_close

PAPER = TorqueLaw("paper", roll_applied=True)
#: Over 0.1 s from the IK state, the paper's inverse/forward pair reproduces IK to DOP853's
#: tolerance (1e-13) amplified at most ~10x: 1e-9 % of signals of order 1 leaves a margin.
SHORT_RUN_PCT = 1e-9
#: Closure of the stance feet on the projected runs: round-off of a few FK evaluations, m.
CLOSURE_M = 1e-12


def _errors(run, ik, plan):
    refs = [ik(float(t), plan.stance(float(t)))[0] for t in run.t]
    return {s: max(e for e in percent_errors(getattr(run, s)[:, :12], np.array([getattr(r, s + "_r") for r in refs])[:, :12])
                   if e is not None) for s in ("q", "qd", "qdd")}


@pytest.mark.parametrize("gait", [TROT, WALK], ids=["trot", "walk"])
def test_forward_dynamics_reproduce_ik_with_dop853(paper, gait):
    plan = gait_plan(paper, gait)
    dyn = CasadiReducedDynamics(paper)
    ik = IkTorques(plan, dyn)
    run = simulate_reduced(plan, dyn, PAPER, horizon=0.1, dt=1e-2, ik=ik)
    assert run.stopped_at is None and run.q.shape == (11, gait.n_coords)
    errors = _errors(run, ik, plan)
    assert max(errors.values()) < SHORT_RUN_PCT, errors
    assert run.closure_m.max() < CLOSURE_M


def test_rk4_converges_at_fourth_order(paper):
    """Halving RK4's step divides its error by ~16 (the truncation error dominates at 5 ms)."""
    plan = gait_plan(paper, WALK)
    dyn = CasadiReducedDynamics(paper)
    ik = IkTorques(plan, dyn)
    coarse, fine = (_errors(simulate_reduced(plan, dyn, PAPER, 0.1, dt, "rk4", ik=ik), ik, plan)["q"] for dt in (1e-2, 5e-3))
    assert 8 < coarse / fine < 32, (coarse, fine)


def test_projection_puts_a_perturbed_state_back_on_the_stance_closure(paper):
    plan = gait_plan(paper, TROT)
    ik = IkTorques(plan, CasadiReducedDynamics(paper))
    ref, _ = ik(0.1, plan.stance(0.1))
    y = np.concatenate([ref.q_r, ref.qd_r])
    rng = np.random.default_rng(0)
    stance = plan.stance(0.1)
    holds = plan.footholds(0.1, stance)
    assert_close(project_on_stance(paper, stance, holds, y), y, what="a consistent state stays")
    moved = project_on_stance(paper, stance, holds, y + rng.normal(scale=1e-6, size=y.size))
    again = project_on_stance(paper, stance, holds, moved)
    assert_close(again, moved, what="projection is idempotent")


def test_backends_agree_to_round_off(paper):
    """The generated C and the CasADi graph give the same motion (to round-off, which the
    gait's instability barely grows over 0.05 s)."""
    plan = gait_plan(paper, TROT)
    runs = [simulate_reduced(plan, reduced_dynamics(paper, b), PAPER, horizon=0.05, dt=1e-2) for b in ("c", "casadi")]
    assert_close(runs[0].q, runs[1].q, rel=1e-12, what="q, C vs CasADi")
    assert_close(runs[0].qdd, runs[1].qdd, rel=1e-9, what="qdd, C vs CasADi")


def test_rigid_contact_dynamics_follow_the_walk_under_its_torques(paper):
    """Three stance feet: the paper's GRF model has rank 6, so id_r's torques of the IK motion
    are torques a rigid robot makes that motion with; the rigid-contact dynamics (Pinocchio
    quantities only) follow it."""
    plan = gait_plan(paper, WALK)
    ik = IkTorques(plan, CasadiReducedDynamics(paper))
    run = simulate_rigid(plan, ik, TorqueLaw("ik"), horizon=0.1, dt=1e-2)
    refs = np.array([ik(float(t), plan.stance(float(t)))[0].q_r for t in run.t])
    assert run.stopped_at is None
    assert np.abs(run.q - refs).max() < 1e-9, "rigid-contact dynamics vs IK, rad"


def test_trot_with_the_roll_unactuated_departs_under_rigid_contacts(paper):
    """Two feet: the paper's model asks for a moment about the support line that no joint
    makes; without it the rigid-contact robot leaves the target."""
    plan = gait_plan(paper, TROT)
    ik = IkTorques(plan, CasadiReducedDynamics(paper))
    run = simulate_rigid(plan, ik, TorqueLaw("ik"), horizon=0.1, dt=1e-2)
    refs = np.array([ik(float(t), plan.stance(float(t)))[0].q_r[:12] for t in run.t])
    assert np.abs(run.q - refs).max() > 1e-4


@pytest.mark.parametrize(("horizon", "dt", "integrator", "message"), [
    (float("nan"), 1e-3, "dop853", "^horizon nan is not a positive finite number"),
    (0.0, 1e-3, "dop853", "^horizon 0.0 is not a positive finite number"),
    (0.05, 0.0, "dop853", "^dt 0.0 is not a positive finite number"),
    (0.05, -1e-3, "dop853", "^dt -0.001 is not a positive finite number"),
    (1e9, 1e-3, "dop853", r"^horizon 1e\+09 s at dt 0.001 s is 1e\+12 samples per run; expected at most 200,000 samples "
                          r"\(horizon / dt\) per run; a larger dt or a shorter horizon$"),
    (0.01, 0.05, "dop853", r"^horizon 0.01 s is shorter than one step \(dt 0.05 s\); expected horizon >= dt$"),
    ("0.05", 1e-3, "dop853", "^horizon is '0.05', a str; expected a real number"),
    (0.05, 7e-4, "rk4", "^dt 0.0007 does not divide the gait's phase"),
    (0.05, 1e-3, "euler", "unknown integrator 'euler'; expected dop853 or rk4"),
])
def test_every_run_checks_its_times_before_the_work(paper, horizon, dt, integrator, message, monkeypatch):
    """Found by a review: the CLI checked these, the API did not: run_experiment and the
    simulations raised ValueError (a NaN horizon), ZeroDivisionError (dt 0), IndexError (dt < 0), a
    7 TiB MemoryError (1e9 s) or a TypeError (a str), after building the IK table. The messages name the
    parameters (they named the CLI's --horizon and --dt, which the API has not; the CLI passes its own names)."""
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.experiment import paper_experiment
    from quadruped_dyn.experiment.paper_experiment import run_experiment

    def tripwire(*a, **k):
        raise AssertionError("the work started before the times were checked")

    monkeypatch.setattr(paper_experiment, "IkTorqueTable", tripwire)
    plan = gait_plan(paper, TROT)
    for run in (lambda: run_experiment(paper, TROT, None, horizon, dt, integrator),  # type: ignore[arg-type]
                lambda: simulate_reduced(plan, None, PAPER, horizon, dt, integrator),  # type: ignore[arg-type]
                lambda: simulate_rigid(plan, None, PAPER, horizon, dt, integrator)):  # type: ignore[arg-type]
        with pytest.raises(InputError, match=message):
            run()
