"""Peers in the benchmark (adam's generated CasADi functions): checked against Pinocchio, then timed."""

from __future__ import annotations

import importlib.util
import subprocess

import casadi as ca
import pytest
from click.testing import CliRunner

from quadruped_dyn.bench.peers import _harness
from quadruped_dyn.cli import main
from quadruped_dyn.codegen.library import C_FLAGS


def test_unknown_peer_is_bad_input():
    result = CliRunner().invoke(main, ["bench", "--peers", "adam,pinocchio_cg"])
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert ("unknown peer(s) pinocchio_cg; expected a comma-separated list of: pinocchio-cppadcodegen, adam (or none)"
            in result.stderr)


def test_none_beside_a_peer_is_bad_input():
    """Found by a review: ``--peers none,adam`` was read as adam."""
    result = CliRunner().invoke(main, ["bench", "--peers", "none,adam"])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1, result.output
    assert "--peers 'none,adam' names none and a peer; expected none alone, or peers without it" in result.stderr


@pytest.mark.parametrize("peers", [",", " , ", "adam,", ",none"])
def test_an_empty_peer_name_is_bad_input(peers, monkeypatch):
    """Found by a review: ``--peers ,`` was read as no peers (and the benchmark ran)."""
    from quadruped_dyn.bench import timing

    def tripwire(*a, **k):
        raise AssertionError("the benchmark started")

    monkeypatch.setattr(timing, "run_bench", tripwire)
    result = CliRunner().invoke(main, ["bench", "--peers", peers])
    assert result.exit_code == 2 and "Traceback" not in result.output and result.stderr.count("\n") == 1, result.output
    assert (f"--peers '{peers}' has an empty name; expected a comma-separated list of: pinocchio-cppadcodegen, adam "
            "(or none)") in result.stderr


@pytest.mark.slow
@pytest.mark.skipif(importlib.util.find_spec("adam") is None, reason="adam-robotics not installed")
@pytest.mark.parametrize("name", ["solo12", "go2"])
def test_adam_checked_then_timed(name):
    """adam's M and C + G equal Pinocchio's (else run_peers raises before timing); times positive."""
    from quadruped_dyn.bench.peers import ADAM_PAIRS, run_peers
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.tolerances import REL_TOL_TERMS

    entries = run_peers(load_robot(name), calls=200, reps=3, rounds=1)
    assert [(e.ours, e.peer) for e in entries] == list(ADAM_PAIRS.items())
    for e in entries:
        assert e.checked_rel_error <= REL_TOL_TERMS
        assert e.ours_ns > 0 and e.peer_ns > 0 and e.ours_operations > 0 and e.peer_operations > 0


def test_harness_builds_casadis_c_unedited_and_times_each_function():
    """CasADi's C as it writes it (its unused parameters not cast) builds under the project's warnings."""
    x = ca.SX.sym("x", 3)
    functions = [ca.Function("qd_sin3", [x], [ca.sin(x)]), ca.Function("qd_sq3", [x], [x * x])]
    exe = _harness(functions, tuple(f for f in C_FLAGS if f != "-fPIC"), "gcc")
    out = subprocess.run([str(exe), "10", "1"], capture_output=True, text=True, check=True).stdout.split()
    assert out[0::2] == ["qd_sin3", "qd_sq3"] and all(float(t) > 0 for t in out[1::2]), out
