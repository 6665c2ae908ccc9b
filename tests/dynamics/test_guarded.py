"""Property test of the public API (the README's layer) on malformed numbers: NaN, inf, huge,
tiny, wrong lengths, zero quaternions. Every call either raises InputError (or NumericalError, for
finite inputs where the model is singular) or returns finite numbers -- never another exception,
a crash, or a NaN."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from quadruped_dyn.dynamics.grf import grf_solve
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import full_q

HOSTILE = st.sampled_from([np.nan, np.inf, -np.inf, 1e300, -1e300, 1e155, 1e-300, 5e-324, 0.0])
ORDINARY = st.floats(-3.0, 3.0, allow_nan=False)
SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@st.composite
def vectors(draw: st.DrawFn, n: int, quaternion_at: int | None = None) -> np.ndarray:
    """Mostly the right length and ordinary, with hostile entries, a wrong length or a
    zero quaternion mixed in."""
    length = draw(st.sampled_from([n] * 6 + [n - 1, n + 1, 0]))
    x = np.array(draw(st.lists(ORDINARY, min_size=length, max_size=length)), dtype=float)
    if length and draw(st.booleans()):
        for i in draw(st.lists(st.integers(0, length - 1), min_size=1, max_size=3)):
            x[i] = draw(HOSTILE)
    if quaternion_at is not None and length == n:
        quat = x[quaternion_at : quaternion_at + 4]
        choice = draw(st.sampled_from(["keep", "zero", "unit"]))
        if choice == "zero":
            quat[:] = 0.0
        elif choice == "unit" and np.all(np.isfinite(quat)) and np.linalg.norm(quat) > 0:
            quat /= np.linalg.norm(quat)
    return x


def _finite_or_input_error(call) -> None:
    try:
        out = call()
    except (InputError, NumericalError) as e:
        assert "\n" not in str(e), "one line"
        return
    values = out.values() if isinstance(out, dict) else (out if isinstance(out, tuple | list) else [out])
    for value in values:
        if value is None:
            continue
        arr = np.asarray(value, dtype=float)
        assert np.all(np.isfinite(arr)), f"non-finite answer {arr}"


@pytest.fixture(scope="module")
def paper():
    return load_robot("paper")


@SETTINGS
@given(q=vectors(19, quaternion_at=3), v=vectors(18), a=vectors(18), f=vectors(12))
def test_full_dynamics(paper, q, v, a, f):
    fd = full_dynamics(paper)
    _finite_or_input_error(lambda: fd.M_full_walker_orin(q))
    _finite_or_input_error(lambda: fd.G_full_newton_euler(q))
    _finite_or_input_error(lambda: fd.C_full(q, v))
    _finite_or_input_error(lambda: fd.coriolis(q, v))
    _finite_or_input_error(lambda: fd.id_full(q, v, a, f))
    _finite_or_input_error(lambda: fd.M_full_walker_orin(q=q))


@SETTINGS
@given(q=vectors(19, quaternion_at=3), v=vectors(18), a=vectors(18),
       stance=st.sampled_from(["FL+BR", "FR+BL+BR", "FL+FR+BL+BR", "FL+FR"]),
       mu=st.one_of(st.none(), st.sampled_from([0.6, 0.0, -0.6, np.nan, np.inf, 1e300])))
def test_grf_solve(paper, q, v, a, stance, mu):
    def solve():
        s = grf_solve(paper, stance).solve(q, v, a, mu=mu)
        return [s.lam, s.f_world, s.residual, s.tau, s.friction_margin]

    _finite_or_input_error(solve)


@SETTINGS
@given(q_r=vectors(13), qd_r=vectors(13), tau=vectors(13), quat=vectors(4, quaternion_at=0))
def test_reduced_forward_dynamics(paper, q_r, qd_r, tau, quat):
    model = reduced_model(paper, "FL+BR")
    _finite_or_input_error(lambda: model.forward_dynamics(q_r, qd_r, tau, quat))
    _finite_or_input_error(lambda: model.id_r(q_r, qd_r, tau, quat))


@SETTINGS
@given(R=st.lists(st.one_of(ORDINARY, HOSTILE), min_size=9, max_size=9), p=vectors(3), qj=vectors(12))
def test_full_q(R, p, qj):
    _finite_or_input_error(lambda: full_q(np.reshape(R, (3, 3)), p, qj))


def _q(paper, quat=(0.0, 0.0, 0.0, 1.0)) -> np.ndarray:
    return np.concatenate([np.zeros(3), quat, paper.standing_q])


#: The issue's cases at the README's layer, each with the message it gets.
API_CASES = [
    ("M_full(NaN q)", lambda r: full_dynamics(r).M_full_walker_orin(np.r_[np.nan, _q(r)[1:]]), r"q contains NaN or inf"),
    ("M_full(zero quaternion)", lambda r: full_dynamics(r).M_full_walker_orin(_q(r, (0, 0, 0, 0))), r"q has a zero quaternion"),
    ("M_full(18 entries)", lambda r: full_dynamics(r).M_full_walker_orin(_q(r)[:18]), r"q has shape \(18,\); expected \(19,\)"),
    ("M_full(text)", lambda r: full_dynamics(r).M_full_walker_orin("q"),
     r"q is (not numeric|a string; expected a numeric array)"),
    ("id_full(2 inputs)", lambda r: full_dynamics(r).id_full(_q(r), np.zeros(18)), r"id_full takes 4 inputs"),
    ("id_full(v = 1e300)", lambda r: full_dynamics(r).id_full(_q(r), np.full(18, 1e300), np.zeros(18), np.zeros(12)),
     r"id_full gives a non-finite .* inputs too large"),
    ("solve(mu=-0.6)", lambda r: grf_solve(r, "FL+BR").solve(_q(r), np.zeros(18), np.zeros(18), mu=-0.6),
     r"mu = -0.6 is not a friction coefficient"),
    ("solve(mu=nan)", lambda r: grf_solve(r, "FL+BR").solve(_q(r), np.zeros(18), np.zeros(18), mu=np.nan),
     r"mu = nan is not a friction coefficient"),
    ("solve(mu=inf)", lambda r: grf_solve(r, "FL+BR").solve(_q(r), np.zeros(18), np.zeros(18), mu=np.inf),
     r"mu = inf is not a friction coefficient"),
]


@pytest.mark.parametrize(("case", "call", "expected"), API_CASES, ids=[c[0] for c in API_CASES])
def test_api_bad_input(paper, case, call, expected):
    with pytest.raises(InputError, match=expected):
        call(paper)
