"""What the generated header promises a C caller: a null work pointer, and which inputs are read."""

from __future__ import annotations

import re

import numpy as np
import pytest

from quadruped_dyn.codegen.emit import REDUCED_NAMES, REDUCED_STANCE_SETS, reduced_symbol
from quadruped_dyn.codegen.emit_derivatives import GRF_DERIVATIVE_STANCE_SETS
from quadruped_dyn.codegen.file_names import feet_suffix
from quadruped_dyn.codegen.library import QD_NO_WORK, QD_NONFINITE, CompiledFunction, compiled_library, work_sizes_of

#: The functions the header says need caller work memory (their _SZ_W > 0).
NEEDS_WORK = ["dfd_full", *(f"dgrf_{feet_suffix(s)}" for s in GRF_DERIVATIVE_STANCE_SETS),
              *(reduced_symbol("dfd_r", s) for s in REDUCED_STANCE_SETS)]


@pytest.fixture(scope="module")
def paper_library(paper):
    return compiled_library(paper)


def _inputs(f: CompiledFunction) -> list[np.ndarray]:
    """A regular state near standing for every input of ``f`` (a tilted unit quaternion, bent legs)."""
    out = []
    for name, n in zip(f.names_in, f.sizes_in):
        if name == "quat":
            x = np.array([0.05, 0.1, 0.02, 1.0])
            out.append(x / np.linalg.norm(x))
        elif name == "q":
            out.append(np.r_[0.0, 0.0, 0.3, 0.05, 0.1, 0.02, 0.99, np.tile([0.1, 0.7, -1.4], 4)])
        elif name == "q_r":
            out.append(np.r_[np.tile([0.1, 0.7, -1.4], 4), np.zeros(n - 12)])
        else:
            out.append(np.linspace(0.1, 0.5, n))
    return out


def _call(f: CompiledFunction, args: list[np.ndarray], null_work: bool = False) -> int:
    for buf, x in zip(f._in, args):
        buf[:] = x
    return int(f._fn(f._arg, f._res, None if null_work else f._iw, None if null_work else f._w, 0))


@pytest.mark.parametrize("name", NEEDS_WORK)
def test_null_work_memory_is_refused_not_dereferenced(paper_library, name):
    """A function that needs w returns QD_NO_WORK for a null w (no crash) and writes no output; with w it works."""
    f = CompiledFunction(paper_library, name)
    assert work_sizes_of(f._lib, f.name)[3] > 0
    for out in f._out:
        out[:] = 7.0
    assert _call(f, _inputs(f), null_work=True) == QD_NO_WORK
    assert all(np.all(out == 7.0) for out in f._out)
    assert _call(f, _inputs(f)) == 0


@pytest.mark.parametrize("name", ["M_full", "id_full", "grf_FL_BR", "did_full", reduced_symbol("fd_r", REDUCED_STANCE_SETS[0]),
                                  reduced_symbol("M_r", REDUCED_STANCE_SETS[-1])])
def test_functions_without_work_memory_accept_a_null_w(paper_library, name):
    """The others never read iw or w: the same outputs with null ones."""
    f = CompiledFunction(paper_library, name)
    assert work_sizes_of(f._lib, f.name)[2:] == (0, 0)
    assert _call(f, _inputs(f)) == 0
    with_w = [o.copy() for o in f._out]
    assert _call(f, _inputs(f), null_work=True) == 0
    assert all(np.array_equal(a, b) for a, b in zip(with_w, f._out))


def _unread(f: CompiledFunction) -> list[str]:
    """The input entries a NaN in which ``f`` does not report as QD_NONFINITE."""
    base, unread = _inputs(f), []
    for i, (name, n) in enumerate(zip(f.names_in, f.sizes_in)):
        for j in range(n):
            args = [x.copy() for x in base]
            args[i][j] = np.nan
            if _call(f, args) != QD_NONFINITE:
                unread.append(f"{name}[{j}]")
    return unread


@pytest.mark.parametrize("stance", REDUCED_STANCE_SETS, ids=lambda s: s.name)
def test_reduced_functions_report_a_nan_in_every_input_they_read(paper_library, stance):
    """As the header states: every input entry is read and a NaN there returns QD_NONFINITE, except q_r's 13th with
    two feet (the roll, taken from quat) and quat in M_r with three or four feet; a value there changes no output."""
    header = re.sub(r"\s*\n \*\s*", " ", (paper_library.path.parent / "qd_paper.h").read_text())
    assert ("every entry of its inputs except q_r's 13th with two feet (the roll: taken from quat) and quat in M_r "
            "with three or four feet: a NaN there is not read and not reported") in header
    for kind in (*REDUCED_NAMES, "dfd_r"):
        f = CompiledFunction(paper_library, reduced_symbol(kind, stance))
        if len(stance.feet) == 2:
            unread = ["q_r[12]"]
        else:
            unread = ["quat[0]", "quat[1]", "quat[2]", "quat[3]"] if kind == "M_r" else []
        assert _unread(f) == unread, f.name
        base = _inputs(f)
        assert _call(f, base) == 0
        expected = [o.copy() for o in f._out]
        for entry in unread:  # not read: any value there gives the same outputs to the bit
            i = f.names_in.index(entry.split("[")[0])
            args = [x.copy() for x in base]
            args[i][int(entry[:-1].split("[")[1])] = 1e3
            assert _call(f, args) == 0
            assert all(np.array_equal(a, b) for a, b in zip(expected, f._out)), (f.name, entry)

