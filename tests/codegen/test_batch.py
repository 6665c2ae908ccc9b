"""The batch entry points (qd_NAME_batch through CompiledFunction.batch): every state's outputs and return code equal
one scalar call's to the bit, for every function of the paper library; bad arrays are refused with one line."""

from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

from quadruped_dyn.codegen.library import QD_NONFINITE, CompiledFunction, compiled_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import full_q
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close

#: states per batch: not a multiple of any chunk size, a few per function (the scalar loop runs them again one by one)
N_STATES = 7
#: the row given a NaN input
NAN_ROW = 3


def _inputs(fn: CompiledFunction, n: int, rng: np.random.Generator) -> list[np.ndarray]:
    """(n, nnz) inputs of ``fn``: random entries of order 1, each quaternion unit (a random orientation)."""
    arrays = []
    for name, size in zip(fn.names_in, fn.sizes_in):
        x = rng.uniform(-1.0, 1.0, (n, size))
        quat = x[:, 3:7] if name == "q" else x if name == "quat" else None
        if quat is not None:
            quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        arrays.append(x)
    return arrays


def _one_call(fn: CompiledFunction, row: list[np.ndarray]) -> tuple[list[np.ndarray], int]:
    """One scalar call of the C function on ``row`` (no checks): its output nonzeros and return code."""
    for buf, x in zip(fn._in, row):
        buf[:] = x
    for buf in fn._out:
        buf[:] = np.nan  # an output the call does not write stays NaN here, and compares as not written
    flag = fn._fn(fn._arg, fn._res, fn._iw, fn._w, 0)
    return [buf.copy() for buf in fn._out], int(flag)


def test_batch_equals_one_call_for_every_function(paper):
    """Every function of the paper library, 7 states (one with a NaN input), equal to the bit where a call writes."""
    library = compiled_library(paper)
    names = re.findall(r"int qd_(\w+)_batch\(", (library.path.parent / "qd_paper.h").read_text())
    assert len(names) > 100, "the header declares a batch entry point per function"
    rng = np.random.default_rng(55)
    for name in names:
        fn = CompiledFunction(library, name)
        arrays = _inputs(fn, N_STATES, rng)
        arrays[0][NAN_ROW, 0] = np.nan
        out = [np.full((N_STATES, buf.size), np.nan) for buf in fn._out]
        _, status = fn.batch(*arrays, out=out)
        assert status[NAN_ROW] != 0, f"{name}: a NaN input is the row's status"
        for s in range(N_STATES):
            expected, flag = _one_call(fn, [x[s] for x in arrays])
            if s != NAN_ROW:
                assert status[s] == flag, f"{name} row {s}: status {status[s]}, one call returned {flag}"
            for y, e in zip(out, expected):
                assert y[s].tobytes() == e.tobytes(), f"{name} row {s}: not the one call's bits"


def test_batch_float_library_equals_one_call(paper):
    """The float build: M_full and id_full over the same states, bit for bit (float32 arrays)."""
    library = compiled_library(paper, "float")
    rng = np.random.default_rng(5)
    for name in ("M_full", "id_full"):
        fn = CompiledFunction(library, name)
        arrays = [x.astype(np.float32) for x in _inputs(fn, N_STATES, rng)]
        out, status = fn.batch(*arrays)
        assert not status.any() and out[0].dtype == np.float32
        for s in range(N_STATES):
            expected, _ = _one_call(fn, [x[s] for x in arrays])
            assert all(y[s].tobytes() == e.tobytes() for y, e in zip(out, expected)), f"{name} row {s}"


def test_batch_mass_matrix_against_pinocchio(paper):
    """One batch of M_full against Pinocchio's crba, state by state."""
    fn = CompiledFunction(compiled_library(paper), "M_full")
    ref = PinocchioReference(paper)
    rng = np.random.default_rng(1)
    q = np.array([full_q(np.eye(3), rng.normal(size=3), paper.standing_q + rng.normal(0, 0.3, 12)) for _ in range(5)])
    (M,), status = fn.batch(q)
    assert not status.any()
    for s in range(len(q)):
        assert_close(_dense(fn, M[s]), ref.mass_matrix(q[s]), what=f"M_full batch row {s}")


def _dense(fn: CompiledFunction, nonzeros: np.ndarray) -> np.ndarray:
    """M's nonzeros (compressed column) as the dense matrix."""
    dense = np.zeros(fn._shapes[0][0] * fn._shapes[0][1])
    dense[fn._index[0]] = nonzeros
    return dense.reshape(fn._shapes[0], order="F")


def test_batch_sizes_bad_arrays_and_strict(paper):
    """N = 0 and 1; wrong shape, dtype, layout, count and out refused with one line; strict names the first bad row."""
    fn = CompiledFunction(compiled_library(paper), "id_full")
    rng = np.random.default_rng(2)
    for n in (0, 1):
        out, status = fn.batch(*_inputs(fn, n, rng))
        assert [y.shape for y in out] == [(n, 6), (n, 12)] and status.shape == (n,)
    q, v, a, f = _inputs(fn, 4, rng)
    bad_calls = [
        (lambda: fn.batch(q[:, :18], v, a, f), r"input q: expected an \(4, 19\) array"),
        (lambda: fn.batch(q, v[:3], a, f), r"input v: expected an \(4, 18\) array"),
        (lambda: fn.batch(q[0], v, a, f), r"expected an \(N, 19\) array"),
        (lambda: fn.batch(q.astype(np.float32), v, a, f), "float64 array"),
        (lambda: fn.batch(np.asfortranarray(q), v, a, f), "not C-contiguous"),
        (lambda: fn.batch(q, v, a), "takes inputs"),
        (lambda: fn.batch(q, v, a, f, out=[np.empty((4, 6))]), "out has 1 arrays"),
        (lambda: fn.batch(q, v, a, f, out=[np.empty((4, 6)), np.empty((3, 12))]), r"output 1: expected an \(4, 12\)"),
    ]
    for call, match in bad_calls:
        with pytest.raises(InputError, match=match):
            call()
    v[2, 5] = np.inf
    _, status = fn.batch(q, v, a, f)
    assert status.tolist() == [0, 0, QD_NONFINITE, 0]
    with pytest.raises(InputError, match="row 2: "):
        fn.batch(q, v, a, f, strict=True)


def test_batch_c_status_is_per_row(paper):
    """A reduced function's QD_DEGENERATE row (zero quaternion) does not stop the rows after it: the C's own codes."""
    fn = CompiledFunction(compiled_library(paper), "fd_r_FL_BR")
    arrays = _inputs(fn, 3, np.random.default_rng(3))
    arrays[3][1] = 0.0  # quat of row 1
    out, status = fn.batch(*arrays)
    assert status[1] != 0 and status[0] == status[2] == 0
    assert ctypes.sizeof(ctypes.c_int) == status.itemsize
