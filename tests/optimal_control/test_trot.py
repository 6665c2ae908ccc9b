"""The coarse trot on the paper robot: IPOPT converges, and the optimised motion is one the robot
can make -- checked against Pinocchio, not against the transcription's own graphs."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.experiment.gait import TROT
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import rotation
from quadruped_dyn.optimal_control.node import trunk_quaternion
from quadruped_dyn.optimal_control.solve import MAX_CONSTRAINT_VIOLATION, Solution, solve
from quadruped_dyn.optimal_control.transcription import Options, transcribe
from quadruped_dyn.references.pinocchio import PinocchioReference

#: Coarse: 3 nodes per phase (6 per cycle), collocated at the quarter points too (the default).
COARSE = Options(nodes_per_phase=3)

#: Pinocchio's reduced inverse dynamics and ours are different derivations: they agree to the
#: round-off of ~1e3 operations on torques of ~10 N m, and on the roll moment.
ROLL_TOL_NM = 1e-8
TAU_TOL_NM = 1e-8


@pytest.fixture(scope="module")
def coarse_trot(paper: Robot) -> Solution:
    return solve(transcribe(paper, TROT, COARSE))


def test_coarse_trot_converges(coarse_trot: Solution) -> None:
    assert coarse_trot.status == "Solve_Succeeded", coarse_trot.status
    assert coarse_trot.constraint_violation <= MAX_CONSTRAINT_VIOLATION
    assert coarse_trot.converged


def test_roll_moment_is_zero_by_pinocchio(coarse_trot: Solution, paper: Robot) -> None:
    """At every node, Pinocchio's reduced inverse dynamics (its own Jacobians, rnea, SVD GRF)
    of the optimised motion has no roll moment about the stance feet's line, and its joint
    torques are the optimiser's; the plan's motion needs a roll moment of order 1 N m."""
    tr = coarse_trot.transcription
    X, Xd, Xdd, _ = tr.unpack(coarse_trot.w)
    X0, _, _, _ = tr.unpack(tr.w0)
    pin_ref = PinocchioReference(paper)
    taus = np.asarray(tr.outputs(coarse_trot.w)[0])
    plan_roll = []
    col = 0
    for k in range(tr.n_nodes):
        for p in tr.phase_of(k):
            stance = TROT.phases[p]
            P = StanceSet(stance).selection("paper")
            x, xd, xdd = X[:, k], Xd[:, k], Xdd[:, k]
            tau_r = pin_ref.reduced_inverse_dynamics(stance, P, x[:13], xd[:13], xdd[:13], trunk_quaternion(x[12:15]))
            assert np.all(np.isfinite(tau_r))
            assert abs(tau_r[12]) <= ROLL_TOL_NM, (k, stance, tau_r[12])
            assert np.abs(tau_r[:12] - taus[:, col]).max() <= TAU_TOL_NM
            plan = tr.unpack(tr.w0)
            plan_roll.append(pin_ref.reduced_inverse_dynamics(stance, P, plan[0][:13, k], plan[1][:13, k], plan[2][:13, k],
                                                              trunk_quaternion(X0[12:15, k]))[12])
            col += 1
    assert max(abs(r) for r in plan_roll) > 0.1  # the plan needs the roll moment that the optimum does without


def test_stance_feet_stay_on_their_footholds_by_pinocchio(coarse_trot: Solution, paper: Robot) -> None:
    """Pinocchio's foot positions of the optimised nodes: stance feet on the ground (z of the
    plan's footholds) and not moving within a phase."""
    tr = coarse_trot.transcription
    X, _, _, _ = tr.unpack(coarse_trot.w)
    pin_ref = PinocchioReference(paper)
    ground = tr.plan.foot(0, 0.0)[0][2]
    N = tr.options.nodes_per_phase
    for p, stance in enumerate(TROT.phases):
        held = []
        for k in range(p * N, (p + 1) * N):
            x = X[:, k]
            q = np.concatenate([x[15:18], trunk_quaternion(x[12:15]), x[:12]])
            r = pin_ref.foot_positions(q)
            world = r @ rotation(q).T + x[15:18]
            held.append(world[list(stance)])
        held = np.array(held)
        assert np.abs(held[:, :, 2] - ground).max() <= 1e-9
        assert np.abs(held - held[0]).max() <= 1e-9


@pytest.mark.parametrize("signum", ["SIGINT", "SIGTERM"])
def test_an_interrupt_during_the_solve_is_raised_not_a_failed_solve(paper: Robot, monkeypatch, signum) -> None:
    """CasADi swallowed the KeyboardInterrupt (or cli.entry.Terminated) of Ctrl-C or SIGTERM during IPOPT's
    iterations: the solve came back 'NonIpopt_Exception_Thrown' and the command said 'did not converge', exit 1."""
    import os
    import signal
    import threading

    import casadi as ca

    from quadruped_dyn.cli.entry import Terminated, _terminate

    number = getattr(signal, signum)
    nlpsol = ca.nlpsol

    def nlpsol_then_signal(*args, **kwargs):
        solver = nlpsol(*args, **kwargs)

        def solve_signalled(**given):
            threading.Timer(0.02, os.kill, (os.getpid(), number)).start()  # into IPOPT's iterations
            return solver(**given)
        return solve_signalled

    monkeypatch.setattr(ca, "nlpsol", nlpsol_then_signal)
    previous = signal.signal(signal.SIGTERM, _terminate)  # as cli.entry sets it
    try:
        with pytest.raises(Terminated if number == signal.SIGTERM else KeyboardInterrupt):
            solve(transcribe(paper, TROT, COARSE))
        assert signal.getsignal(signal.SIGTERM) is _terminate
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGTERM, previous)
