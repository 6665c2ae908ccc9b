"""A check never passes on NaN or inf (docs/reliability.md §1): the one comparison module, the check
report built on it, and its JSON."""

from __future__ import annotations

import json

import numpy as np
import pytest

from quadruped_dyn.checks.terms import CheckReport, GrfResult, TermResult
from quadruped_dyn.math.compare import max_abs_error, relative_error, scale_of, within

NON_FINITE = [np.nan, np.inf, -np.inf]


@pytest.mark.parametrize("bad", NON_FINITE)
@pytest.mark.parametrize("side", ["ours", "reference", "both"])
def test_non_finite_is_an_infinite_error(bad, side):
    good = np.array([1.0, 2.0, 3.0])
    broken = good.copy()
    broken[1] = bad
    ours = broken if side in ("ours", "both") else good
    ref = broken if side in ("reference", "both") else good
    assert max_abs_error(ours, ref) == np.inf
    assert relative_error(ours, ref) == np.inf
    assert not within(relative_error(ours, ref), 1e300)


def test_ordinary_errors():
    assert max_abs_error([1.0, 2.0], [1.0, 2.5]) == 0.5
    assert relative_error([1.0, 2.0], [1.0, 2.5]) == pytest.approx(0.2)
    assert relative_error([1e-3], [0.0]) == 1e-3, "an all-zero reference leaves the error absolute"
    assert max_abs_error([1.0, 2.0], [1.0, 2.0, 3.0]) == np.inf, "shapes differ"
    assert scale_of([np.nan]) == np.inf
    assert within(0.0, 0.0) and not within(np.nan, 1.0)


@pytest.mark.parametrize("bad", NON_FINITE)
def test_term_with_non_finite_values_fails(bad):
    """The issue's case: NaN on both sides used to print 0.00e+00 ... pass."""
    term = TermResult("M_full")
    term.add(np.ones(3), np.ones(3))
    assert term.passed
    term.add(np.full(3, bad), np.full(3, bad))
    assert not term.passed and term.max_rel_err == np.inf
    term.add(np.ones(3), np.ones(3))
    assert not term.passed, "a later good sample does not hide it"


def test_report_json_is_strict_and_says_fail():
    term = TermResult("G_full")
    term.add([np.nan], [np.nan])
    grf = GrfResult("FL+BR", "paper", 5, max_residual=np.float64(np.inf), passed=np.bool_(False))  # type: ignore[arg-type]
    report = CheckReport("paper", 1, 0, terms=[term], grf=[grf])
    text = json.dumps(report.as_dict(), allow_nan=False)
    data = json.loads(text)
    assert data["passed"] is False
    assert data["terms"][0]["max_rel_err"] is None and data["terms"][0]["passed"] is False
    assert data["grf"][0]["max_residual"] is None and data["grf"][0]["passed"] is False
    assert "FAIL" in report.table()


@pytest.mark.slow  # compiles casadi_gen's library: ~1 min
def test_c_check_program_fails_on_nan(tmp_path):
    """check_qd.c compared with `if (d > err)`, which skips a NaN: a NaN reference value now
    fails its function (built from a copy of casadi_gen with one reference entry set to NAN)."""
    import shutil
    import subprocess
    from pathlib import Path

    work = tmp_path / "casadi_gen"
    shutil.copytree(Path(__file__).resolve().parents[2] / "casadi_gen", work, ignore=shutil.ignore_patterns("build"))
    reference = work / "qd_paper-reference.h"
    text = reference.read_text()
    head = "qd_M_full_out0[210] = {"
    assert head in text
    reference.write_text(text.replace(head, head + "NAN + ", 1))
    subprocess.run(["make", "-C", str(work), "build/check_qd"], capture_output=True, check=True)
    proc = subprocess.run([str(work / "build" / "check_qd")], capture_output=True, text=True, check=False)
    assert proc.returncode != 0
    lines = {line.split()[0]: line for line in proc.stdout.splitlines() if line.startswith("qd_")}
    assert "FAIL" in lines["qd_M_full"], lines["qd_M_full"]
    assert "1 failed" in proc.stdout
