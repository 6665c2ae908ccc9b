"""``codegen.printer``'s reciprocals: quotients by a shared or constant denominator become products
with one reciprocal, compiled C agrees with CasADi's own evaluation to a few ulps, non-finite stays non-finite, and
the committed C has no such quotient left."""

from __future__ import annotations

import ctypes
import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.codegen.c_file import casadi_c
from quadruped_dyn.codegen.library import C_FLAGS, run_tool

CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"

#: x * fl(1/d) against fl(x / d): two roundings instead of one, so within ~2 ulps of CasADi's quotient
ULPS = 2


def _quotients() -> ca.Function:
    x, d, e = ca.SX.sym("x", 3), ca.SX.sym("d"), ca.SX.sym("e")
    return ca.Function("q", [x, d, e], [ca.vertcat(x[0] / d, x[1] / d, (x[2] + d) / d, x[0] / e, x[1] / 3, x[2] / 4)])


def test_a_shared_or_constant_denominator_gets_one_reciprocal():
    """d divides three times and 3, 4 are constants: three reciprocals; e divides once and stays a quotient."""
    c_text, _ = casadi_c("q", [_quotients()], "double")
    body = re.search(r"static int casadi_f0\(.*?\n\}\n", c_text, re.S).group(0)
    assert len(re.findall(r"rcp\d+=\(1\./a\d+\);", body)) == 3
    assert len(re.findall(r"\(a\d+\*rcp\d+\)", body)) == 5
    assert len(re.findall(r"\(a\d+/a\d+\)", body)) == 1  # x[0] / e


def _compiled(tmp_path: Path) -> ctypes.CDLL:
    c_text, _ = casadi_c("q", [_quotients()], "double")
    (tmp_path / "q.c").write_text(c_text)
    run_tool(["gcc", *C_FLAGS, "-shared", str(tmp_path / "q.c"), "-o", str(tmp_path / "q.so")])
    return ctypes.CDLL(str(tmp_path / "q.so"))


def _call(lib: ctypes.CDLL, x: np.ndarray, d: float, e: float) -> np.ndarray:
    real = ctypes.c_double
    xs, ds, es, out = (real * 3)(*x), (real * 1)(d), (real * 1)(e), (real * 6)()
    args = (ctypes.POINTER(real) * 3)(ctypes.cast(xs, ctypes.POINTER(real)), ctypes.cast(ds, ctypes.POINTER(real)),
                                      ctypes.cast(es, ctypes.POINTER(real)))
    res = (ctypes.POINTER(real) * 1)(ctypes.cast(out, ctypes.POINTER(real)))
    assert lib.q(args, res, None, None, 0) == 0
    return np.array(out[:])


def test_compiled_quotients_agree_with_casadi_and_stay_non_finite(tmp_path):
    lib, f = _compiled(tmp_path), _quotients()
    rng = np.random.default_rng(5)
    for _ in range(200):
        x, d, e = rng.uniform(-1e3, 1e3, 3), rng.uniform(1e-6, 10) * rng.choice([-1, 1]), rng.uniform(1e-6, 10)
        want = np.asarray(f(x, d, e)).ravel()
        got = _call(lib, x, d, e)
        assert np.all(np.isfinite(got)) and np.all(np.abs(got - want) <= ULPS * np.spacing(np.abs(want)))
    for d in (0.0, -0.0, np.inf, np.nan):  # a degenerate denominator gives what the quotient gives
        x = np.array([1.5, 0.0, -2.0])
        want, got = np.asarray(f(x, d, 1.0)).ravel()[:3], _call(lib, x, d, 1.0)[:3]
        assert np.array_equal(np.isfinite(got), np.isfinite(want)) and np.array_equal(np.isnan(got), np.isnan(want)), d


def _shared_quotients(text: str) -> list[str]:
    """The quotients ``aX=(aY/aZ);`` of ``text`` whose denominator (that value of aZ) divides more than once or is a
    constant, read line by line."""
    written: dict[str, int] = {}  # variable -> the line that last wrote it
    constant: set[int] = set()
    uses: dict[tuple[str, int], list[str]] = {}
    for k, line in enumerate(text.split("\n")):
        assign = re.fullmatch(r"  (a\d+)=(.*);", line)
        if not assign:
            continue
        quotient = re.fullmatch(r"\((a\d+)/(a\d+)\)", assign.group(2))
        if quotient and quotient.group(2) in written:
            uses.setdefault((quotient.group(2), written[quotient.group(2)]), []).append(line)
        if re.fullmatch(r"-?\d+\.\d*(e[-+]?\d+)?", assign.group(2)):
            constant.add(k)
        written[assign.group(1)] = k
    return [q for (_, at), lines in uses.items() if len(lines) > 1 or at in constant for q in lines]


@pytest.mark.parametrize("path", sorted(CASADI_GEN.glob("qd_paper*.c")), ids=lambda p: p.name)
def test_committed_c_divides_once_per_denominator(path):
    """No evaluation function of the committed C divides twice by one value of a variable, or by a constant."""
    assert not _shared_quotients(path.read_text())
    assert _shared_quotients("  a1=2.;\n  a2=(a0/a1);\n") and _shared_quotients("  a1=arg[0][0];\n  a2=(a0/a1);\n  a3=(a4/a1);\n")
