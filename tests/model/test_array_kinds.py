"""NumPy inputs that are not plain numbers (model.state.check_array, arguments.real_number): masked and boolean arrays
and float16 are refused with one line; other precisions convert to double by the stated rule."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.dynamics.grf import grf_solve
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import check_array, full_q

MASKED = r"is a masked array; expected a plain array of shape \(\d+,\) \(the mask would be ignored"
BOOLEAN = r"is a boolean array; expected numbers of shape \(\d+,\) \(True and False would be taken as 1 and 0\)"
HALF = r"is float16 \(3 significant digits\); expected float32 or float64 of shape \(\d+,\): every computation is in double"


def _q(robot):
    return full_q(np.eye(3), np.zeros(3), robot.standing_q)


def _kinds(x: np.ndarray) -> list[tuple[object, str]]:
    hidden = np.ma.masked_array(x, mask=np.zeros(x.shape, bool))
    hidden.mask[0] = True
    return [(hidden, MASKED), ([np.ma.masked_array(e) for e in x], MASKED), (np.ones(x.shape, bool), BOOLEAN),
            (x.astype(np.float16), HALF)]


@pytest.mark.parametrize("call", ["full_q", "M_full", "grf solve", "id_r", "check_array"])
def test_masked_boolean_and_half_arrays_are_refused(paper, call):
    q = _q(paper)
    calls = {
        "full_q": (paper.standing_q, lambda x: full_q(np.eye(3), np.zeros(3), x)),
        "M_full": (q, lambda x: full_dynamics(paper).M_full_walker_orin(x)),
        "grf solve": (np.zeros(18), lambda x: grf_solve(paper, "FL+BR").solve(q, x, np.zeros(18))),
        "id_r": (np.zeros(12), lambda x: reduced_model(paper, "FL+FR+BL+BR").id_r(paper.standing_q, x, np.zeros(12),
                                                                                    np.array([0, 0, 0, 1.0]))),
        "check_array": (np.zeros(3), lambda x: check_array("x", x, (3,))),
    }
    value, function = calls[call]
    for bad, expected in _kinds(np.asarray(value, dtype=float)):
        with pytest.raises(InputError, match=expected) as raised:
            function(bad)
        assert "\n" not in str(raised.value)


def test_other_precisions_convert_to_double_by_the_stated_rule(paper):
    x = np.linspace(-1, 1, 12)
    for kind in (np.float32, np.int32, np.int64, np.uint8, np.longdouble):
        converted = check_array("x", x.astype(kind), (12,))
        assert converted.dtype == np.float64
        assert np.array_equal(converted, x.astype(kind).astype(np.float64))  # exact, or rounded to the nearest double
    M32 = np.asarray(full_dynamics(paper).M_full_walker_orin(_q(paper).astype(np.float32)))
    assert np.array_equal(M32, np.asarray(full_dynamics(paper).M_full_walker_orin(_q(paper).astype(np.float32).astype(float))))


def test_a_half_precision_or_boolean_friction_coefficient_is_refused(paper):
    q = _q(paper)
    for mu, kind in ((np.float16(0.6), "float16"), (np.bool_(True), "bool")):
        with pytest.raises(InputError, match=rf"a {kind}; expected a real number"):
            grf_solve(paper, "FL+BR").solve(q, np.zeros(18), np.zeros(18), mu=mu)
