"""Ground reaction forces: ranks, minimum-norm solutions, residuals, and Pinocchio consistency."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from quadruped_dyn.dynamics.grf import friction_cone, grf_solve, grf_solves
from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.math.linalg import least_squares, min_norm
from quadruped_dyn.model.stance import GRF_MODELS, STANCE_SETS, stance_set
from quadruped_dyn.model.state import FullState, full_q, random_state, rotation
from quadruped_dyn.tolerances import COND_ERR_FACTOR, RANK_RTOL, REL_TOL_TERMS
from tests.conftest import assert_close

EXPECTED_RANK = {  # (number of feet, model) -> rank, docs/formulation.md §4
    (4, "paper"): 5, (3, "paper"): 6, (2, "paper"): 5, (1, "paper"): 3, (0, "paper"): 0,
    (4, "min_norm"): 6, (3, "min_norm"): 6, (2, "min_norm"): 5, (1, "min_norm"): 3, (0, "min_norm"): 0,
}


def _solve(robot, s: FullState, stance: str, model: str) -> list[np.ndarray]:
    return [np.asarray(x, dtype=float).ravel() for x in grf_solve(robot, stance, model).function(s.q, s.v, s.a)]


def test_sixteen_stance_sets_with_names():
    names = [s.name for s in STANCE_SETS]
    assert len(set(names)) == 16
    assert names[0] == "FL+FR+BL+BR" and names[-1] == "none"
    assert stance_set("BR+FL").name == "FL+BR" and stance_set("FL+BR").kind == "trot (diagonal)"
    assert stance_set("FL+BL").kind == "pace (lateral)" and stance_set("FR+BL+BR").kind == "walk (lifted FL)"


def test_paper_three_foot_selection():
    """Lifted FL (left): the stance foot on the left, BL, has its own fy; FR and BR share one."""
    P = stance_set("FR+BL+BR").selection("paper")  # feet FR, BL, BR; lifted FL (left side)
    fy_columns = [int(np.flatnonzero(P[3 * j + 1])[0]) for j in range(3)]
    assert fy_columns == [5, 4, 5]  # FR and BR share fy_opp, BL has fy_same
    assert all(np.flatnonzero(P[3 * j])[0] == 3 for j in range(3))  # common fx


@pytest.mark.parametrize("seed", [0, 1])
def test_every_solve_against_pinocchio(robot, ref, seed):
    """rnea - sum Jc^T f: base rows = reported residual, joint rows = tau; lambda = SVD min-norm."""
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    R = rotation(s.q)
    rnea = ref.rnea(s.q, s.v, s.a)
    for stance in STANCE_SETS:
        for model in GRF_MODELS:
            lam, f, residual, tau = _solve(robot, s, stance.name, model)
            contact = ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ fi for fi in f.reshape(4, 3)])
            # relative to the two terms whose difference is compared
            scale = max(np.abs(rnea).max(), np.abs(contact).max())
            what = f"{stance.name} {model}"
            assert np.abs(residual - (rnea - contact)[:6]).max() <= REL_TOL_TERMS * scale, what
            assert np.abs(tau - (rnea - contact)[6:]).max() <= REL_TOL_TERMS * scale, what
            r = ref.grf_solve(s.q, s.v, s.a, stance.feet, stance.selection(model))
            assert r.rank == EXPECTED_RANK[(len(stance.feet), model)] == grf_solve(robot, stance, model).rank, what
            if lam.size:
                cond = r.singular_values[0] / r.singular_values[r.rank - 1]
                assert_close(lam, r.lam, rel=max(REL_TOL_TERMS, COND_ERR_FACTOR * cond * np.finfo(float).eps), what=what)


def test_min_norm_four_feet_is_the_contact_jacobian_pseudo_inverse(robot, ref):
    """As Pinocchio's static-contact example: f = pinv(base rows of Jc^T) (rnea base rows)."""
    s = random_state(robot.lower, robot.upper, np.random.default_rng(7))
    Jc = ref.contact_jacobian(s.q, (0, 1, 2, 3))
    f_world = np.linalg.pinv(Jc[:, :6].T) @ ref.rnea(s.q, s.v, s.a)[:6]
    _, f, residual, _ = _solve(robot, s, "FL+FR+BL+BR", "min_norm")
    R = rotation(s.q)
    assert_close(np.concatenate([R @ fi for fi in f.reshape(4, 3)]), f_world, what="min-norm forces")
    assert np.abs(residual).max() < 1e-9 * np.abs(ref.rnea(s.q, s.v, s.a)[:6]).max()


def _standing(robot, alpha_b=(0.0, 0.0, 0.0)) -> FullState:
    a = np.zeros(18)
    a[3:6] = alpha_b
    return FullState(full_q(np.eye(3), np.zeros(3), robot.standing_q), np.zeros(18), a, np.zeros((4, 3)))


def test_four_feet_cannot_balance_a_yaw_moment(paper):
    """A yaw acceleration needs a yaw moment off the line x_mean Fy - y_mean Fx: the paper's
    4-foot model reports it as residual (min_norm balances it)."""
    s = _standing(paper, alpha_b=(0.0, 0.0, 2.0))
    _, f, residual, _ = _solve(paper, s, "FL+FR+BL+BR", "paper")
    feet = np.array([leg.foot_position(q) for leg, q in zip(paper.legs, paper.standing_q.reshape(4, 3))])
    xm, ym = feet[:, 0].mean(), feet[:, 1].mean()
    u = np.array([ym, -xm, 0, 0, 0, 1.0]) / np.linalg.norm([ym, -xm, 1.0])
    assert np.abs(residual[5]) > 1e-3, "no yaw residual"
    assert_close(residual, u * (u @ residual), what="residual along the unbalanced direction")
    _, _, residual_mn, _ = _solve(paper, s, "FL+FR+BL+BR", "min_norm")
    assert np.abs(residual_mn).max() < 1e-10


def test_two_feet_residual_is_the_moment_about_the_foot_line(paper):
    s = _standing(paper, alpha_b=(1.0, 0.5, 0.3))
    _, f, residual, _ = _solve(paper, s, "FL+BR", "paper")
    r1, r2 = (paper.legs[i].foot_position(paper.standing_q[3 * i : 3 * i + 3]) for i in (0, 3))
    e = (r1 - r2) / np.linalg.norm(r1 - r2)
    u = np.concatenate([np.cross(r1, e), e])
    u /= np.linalg.norm(u)
    assert abs(u @ residual) > 1e-3
    assert_close(residual, u * (u @ residual), what="residual = moment about the FL-BR line")
    # the squeeze along the foot line is free; the minimum-norm solution has none
    assert abs(e @ (f[0:3] - f[9:12])) < 1e-10 * np.abs(f).max()


def test_friction_cone():
    ok, margin = friction_cone(np.array([[1.0, 0.0, 10.0], [6.0, 0.0, 10.0], [0.0, 0.0, -1.0]]), mu=0.5)
    assert ok.tolist() == [True, False, False]
    assert_close(margin, [4.0, -1.0, -0.5])


def test_pseudo_inverse_identity_for_rank_deficient_square_matrices():
    """The identity min_norm_solve relies on: A+ = (A + U N^T)^-1 - N U^T (orthonormal bases)."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(6, 5)) @ rng.normal(size=(5, 6))
    U_, _, Vt = np.linalg.svd(A)
    N, U = Vt[-1:].T, U_[:, -1:]
    assert_close(np.linalg.inv(A + U @ N.T) - N @ U.T, np.linalg.pinv(A))


@pytest.mark.parametrize("shape", [(6, 6), (6, 9), (6, 3)])
def test_householder_solvers_match_lapack(shape):
    rng = np.random.default_rng(1)
    A, b = rng.normal(size=shape), rng.normal(size=6)
    As, bs = ca.SX.sym("A", *shape), ca.SX.sym("b", 6)
    solver = min_norm if shape[1] > 6 else least_squares
    x = np.asarray(ca.Function("x", [As, bs], [solver(As, bs)])(A, b)).ravel()
    assert_close(x, np.linalg.lstsq(A, b, rcond=None)[0])


def test_bad_stance_and_model_names(paper):
    with pytest.raises(InputError, match="unknown stance set"):
        stance_set("FL+XX")
    with pytest.raises(InputError, match="unknown GRF model"):
        grf_solve(paper, "FL+BR", "lsq")


def test_solves_are_built_once(paper):
    assert grf_solves(paper) is grf_solves(paper)


def test_solve_refuses_coincident_or_collinear_feet(paper):
    """FL and FR feet placed on the same point (reachable: both under the trunk's centre line)."""
    from quadruped_dyn.experiment.ik import analytic_ik

    target = np.array([0.19, 0.0, -0.25])
    qj = paper.standing_q.copy()
    qj[0:3], qj[3:6] = analytic_ik("FL", target), analytic_ik("FR", target)
    q, zero = full_q(np.eye(3), np.zeros(3), qj), np.zeros(18)
    with pytest.raises(NumericalError, match="rank 3 at this configuration, 5 expected"):
        grf_solve(paper, "FL+FR").solve(q, zero, zero)
    with pytest.raises(NumericalError, match="rank 5 at this configuration, 6 expected"):
        grf_solve(paper, "FL+FR+BL").solve(q, zero, zero)  # FL, FR coincide: three feet on a line
    assert grf_solve(paper, "FL+BR").solve(q, zero, zero).rank == 5  # still a proper pair


def test_solve_reports_world_forces_and_friction(paper):
    q, zero = full_q(np.eye(3), np.zeros(3), paper.standing_q), np.zeros(18)
    sol = grf_solve(paper, "FL+FR+BL+BR").solve(q, zero, zero, mu=0.6)
    assert_close(sol.f_world.sum(axis=0), [0, 0, paper.total_mass * 9.81], what="feet carry the weight")
    assert sol.in_friction_cone.all() and np.abs(sol.residual).max() < 1e-10


@pytest.mark.parametrize(
    ("q", "match"),
    [(np.full(19, np.nan), "NaN"), (np.zeros(19), "zero quaternion"), (np.zeros(5), "shape")],
)
def test_solve_rejects_bad_state(paper, q, match):
    with pytest.raises(InputError, match=match):
        grf_solve(paper, "FL+BR").solve(q, np.zeros(18), np.zeros(18))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), stance=st.sampled_from(STANCE_SETS), model=st.sampled_from(GRF_MODELS))
def test_minimum_norm_least_squares_optimality(paper, seed, stance, model):
    """Without any reference solver: the residual is orthogonal to range(A) (least squares) and
    lambda lies in range(A^T) (minimum norm), for any state the sampler draws."""
    s = random_state(paper.lower, paper.upper, np.random.default_rng(seed))
    solve = grf_solve(paper, stance, model)
    (A,) = guarded_call(solve.system, s.q)
    lam, _, residual, _ = _solve(paper, s, stance.name, model)
    if not lam.size:
        return
    U, sv, Vt = np.linalg.svd(A)
    rank = int(np.sum(sv > RANK_RTOL * sv[0]))
    assume(rank == solve.rank and sv[0] / sv[rank - 1] < 1e6)  # skip near-singular draws
    allowed = COND_ERR_FACTOR * (sv[0] / sv[rank - 1]) * np.finfo(float).eps  # relative, as in checks/terms.py
    scale = np.abs(A).max() * (np.abs(residual).max() + np.abs(A @ lam).max())
    assert np.abs(A.T @ residual).max() <= allowed * scale, "residual not orthogonal to range(A)"
    assert np.abs(Vt[rank:] @ lam).max(initial=0.0) <= allowed * np.abs(lam).max(), "lambda has a null-space part"
