"""Pinocchio's CppADCodeGen code as bench's peer: it computes Pinocchio's crba and rnea, its check
catches a peer that does not, and bench names it in the JSON."""

from __future__ import annotations

import inspect
import json
import math

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from quadruped_dyn.bench import cppadcg
from quadruped_dyn.bench.timing import run_bench
from quadruped_dyn.cli import main
from quadruped_dyn.errors import NumericalError
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.tolerances import REL_TOL_TERMS

needs_headers = pytest.mark.skipif(
    not cppadcg.available(), reason=f"the CppADCodeGen headers are not installed ({cppadcg.INSTALL_HINT})")


def _eval(exe, q, v, a, tau) -> dict[str, np.ndarray]:
    from quadruped_dyn.codegen.library import run_tool

    args = [str(len(q)), str(len(v)), *(f"{x:.17g}" for vec in (q, v, a, tau) for x in vec)]
    return {name: np.array([float(x) for x in values])
            for name, *values in (line.split() for line in run_tool([str(exe), "eval", *args]).strip().splitlines())}


@pytest.mark.slow  # builds the CppADCodeGen generator: ~10 min cold (cc1plus, 4.4 GB)
@needs_headers
def test_peer_computes_pinocchio_crba_and_rnea():
    """On the paper robot, in Pinocchio's own order (no mapping of the module under test): the peer's
    crba is the upper triangle of pin.crba's M, its rnea pin.rnea's tau, at a random state."""
    paper = load_robot("paper")
    exe = cppadcg.harness(paper)
    model = pin.buildModelFromUrdf(str(paper.urdf), pin.JointModelFreeFlyer())
    data = model.createData()
    rng = np.random.default_rng(3)
    q = pin.integrate(model, pin.neutral(model), rng.normal(size=model.nv))
    v, a, tau = (rng.normal(size=model.nv) for _ in range(3))
    out = _eval(exe, q, v, a, tau)
    M = pin.crba(model, data, q)
    expected = {"crba": M[np.triu_indices(model.nv)], "rnea": pin.rnea(model, data, q, v, a)}
    for name, value in expected.items():
        assert out[name].shape == value.shape and np.all(np.isfinite(out[name]))
        err = np.max(np.abs(out[name] - value)) / np.max(np.abs(value))
        assert err <= REL_TOL_TERMS, (name, err)
    # and the module's own check (mapped to the project's order by joint name) agrees for every function
    errors = cppadcg.check(paper, exe)
    assert set(errors) == set(cppadcg.PAIRS) and all(e <= REL_TOL_TERMS for e in errors.values())


@pytest.mark.slow  # builds the CppADCodeGen generator: ~10 min cold (cc1plus, 4.4 GB)
@needs_headers
def test_check_rejects_a_peer_that_computes_something_else(monkeypatch):
    """One output entry moved by 1e-6 relative: NumericalError naming the function, before any timing."""
    paper = load_robot("paper")
    exe = cppadcg.harness(paper)
    real = cppadcg.run_tool

    def moved(cmd, *args, **kwargs):
        lines = real(cmd, *args, **kwargs).splitlines()
        name, first, *rest = lines[1].split()  # rnea
        lines[1] = " ".join([name, repr(float(first) * (1 + 1e-6) + 1e-6), *rest])
        return "\n".join(lines)

    monkeypatch.setattr(cppadcg, "run_tool", moved)
    with pytest.raises(NumericalError, match=r"differs from Pinocchio native \(rnea"):
        cppadcg.check(paper, exe)


def test_unknown_or_missing_peer_is_bad_input(monkeypatch):
    result = CliRunner().invoke(main, ["bench", "--peers", "cppadcg"])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1
    assert "unknown peer(s) cppadcg; expected a comma-separated list of: pinocchio-cppadcodegen, adam (or none)" in result.stderr
    monkeypatch.setattr(cppadcg, "available", lambda: False)
    result = CliRunner().invoke(main, ["bench", "--peers", "pinocchio-cppadcodegen"])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1
    assert "needs the CppADCodeGen headers; expected pip install 'quadruped_dyn[bench]'" in result.stderr


@pytest.mark.slow
@needs_headers
def test_bench_times_the_peer_in_the_same_run():
    """bench --json end to end: every full-term pair names the peer, ratios are the quotients of the
    times it reports, the peer was checked, and the flags are stated."""
    result = CliRunner().invoke(main, ["bench", "--robot", "paper", "--json", "--calls", "200", "--reps", "3"])
    assert result.exit_code == 0, result.output
    (report,) = json.loads(result.stdout)
    assert report["native"] is False and "-march=native" not in report["c_flags"]
    # medians over the rounds of fresh copies (bench/placement.py): each entry's spread over them is a finite max / min
    assert report["rounds"] == inspect.signature(run_bench).parameters["rounds"].default > 1
    for e in (e for e in report["entries"] if e["name"] != "C_full + G_full"):  # that one is a sum of two entries
        spreads = [e["generated_spread"], *([e["pinocchio_spread"]] if e["pinocchio"] else [])]
        assert all(math.isfinite(x) and x >= 1.0 for x in spreads), e
    peers = {p["peer_function"]: p for p in report["peers"]}
    assert set(peers) == set(cppadcg.PAIRS)
    for function, (name, target) in cppadcg.PAIRS.items():
        p = peers[function]
        assert p["peer"] == "pinocchio-cppadcodegen" and p["name"] == name and p["target"] == target
        assert p["peer_ns"] > 0 and p["pinocchio_ns"] > 0 and p["checked_rel_error"] <= REL_TOL_TERMS
        if name:
            assert p["ratio"] == pytest.approx(p["generated_ns"] / p["peer_ns"])
