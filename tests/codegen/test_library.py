"""CompiledFunction called from Python: its inputs are checked as the symbolic functions' are."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import full_q


def test_compiled_function_checks_its_inputs(paper):
    """It returned NaN for a NaN or None entry, dropped an imaginary part with a warning, took a
    (1, 19) row as q, raised ValueError for a string and AttributeError for an unknown name."""
    library = compiled_library(paper)
    M_full, id_full = CompiledFunction(library, "M_full"), CompiledFunction(library, "id_full")
    q = full_q(np.eye(3), np.zeros(3), paper.standing_q)
    zero_quat = q.copy()
    zero_quat[3:7] = 0.0
    v = np.zeros(18)
    bad_calls = [
        (lambda: M_full(np.full(19, np.nan)), "NaN"),
        (lambda: M_full(np.array([None] * 19)), "object"),
        (lambda: M_full(q + 1j), "complex"),
        (lambda: M_full(q[None, :]), r"shape \(1, 19\)"),
        (lambda: M_full("abc"), "string"),
        (lambda: M_full(q[:18]), "shape"),
        (lambda: M_full(), "takes inputs"),
        (lambda: id_full(zero_quat, v, v, np.zeros(12)), "zero quaternion"),
        (lambda: CompiledFunction(library, "nope"), "no function qd_nope"),
    ]
    for call, match in bad_calls:
        with pytest.raises(InputError, match=match):
            call()
    (M,) = M_full(list(q))
    assert M.shape == (18, 18) and np.all(np.isfinite(M))
