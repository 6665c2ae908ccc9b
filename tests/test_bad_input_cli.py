"""Bad command-line input: exit 2 with one line naming the problem and what is expected, found
BEFORE any work starts (the work is replaced by a tripwire that fails the test if it runs)."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.bench import timing as bench
from quadruped_dyn.cli import main
from quadruped_dyn.codegen import emit as codegen
from quadruped_dyn.experiment import paper_experiment as validation
from quadruped_dyn.model import paper_robot, robot


def _fails_with(args: list[str], expected: str, env: dict[str, str] | None = None) -> None:
    result = CliRunner().invoke(main, args, env=env)
    assert result.exit_code == 2, (args, result.output)
    assert "Traceback" not in result.output
    assert re.search(expected, result.stderr), result.stderr
    assert result.stderr.count("\n") == 1, f"expected one line: {result.stderr!r}"


@pytest.fixture
def no_work(monkeypatch):
    """Tripwires: a command that starts its work before rejecting its arguments fails the test."""

    def tripwire(*args, **kwargs):
        raise AssertionError("the work started before the arguments were checked")

    monkeypatch.setattr(validation, "run_experiment", tripwire)
    monkeypatch.setattr(codegen, "generate", tripwire)
    monkeypatch.setattr(bench, "run_bench", tripwire)


@pytest.fixture
def a_file(tmp_path) -> Path:
    path = tmp_path / "a_file"
    path.write_text("x")
    return path


ARGUMENTS = [
    (["check", "paper", "--seed", "-1"], r"Invalid value for '--seed': -1 is not in the range x>=0"),
    (["check", "paper", "--samples", "0"], r"Invalid value for '--samples'"),
    (["check", "paper", "--samples", "many"], r"Invalid value for '--samples'"),
    (["validate", "--dt", "nan"], r"--dt nan is not a positive finite number"),
    (["validate", "--dt", "inf"], r"--dt inf is not a positive finite number"),
    (["validate", "--dt", "-1e-3"], r"--dt -0.001 is not a positive finite number"),
    (["validate", "--horizon", "nan"], r"--horizon nan is not a positive finite number"),
    (["validate", "--horizon", "inf"], r"--horizon inf is not a positive finite number"),
    (["validate", "--horizon", "0"], r"--horizon 0.0 is not a positive finite number"),
    (["validate", "--horizon", "0.01", "--dt", "0.05"], r"--horizon 0.01 s is shorter than one step \(--dt 0.05 s\)"),
    (["validate", "--integrator", "rk4", "--dt", "0.0007"], r"--dt 0.0007 does not divide the gait's phase"),
    (["validate", "--gait", "gallop"], r"Invalid value for '--gait'"),
    (["codegen", "paper", "--out", "gen", "--precision", "half"], r"Invalid value for '--precision'"),
    (["bench", "--robot", "solo12", "--robot", "/nonexistent.urdf"], r"no such file: '/nonexistent.urdf'"),
    (["bench", "--calls", "0"], r"Invalid value for '--calls'"),
    (["info"], r"Missing argument 'ROBOT'"),
    (["info", "paper", "--no-such-option"], r"No such option '--no-such-option'"),
]


@pytest.mark.parametrize(("args", "expected"), ARGUMENTS, ids=[" ".join(a) for a, _ in ARGUMENTS])
def test_bad_argument(args, expected, no_work, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    _fails_with(args, expected)


@pytest.mark.parametrize("command", [["codegen", "paper"], ["validate", "paper"]])
@pytest.mark.parametrize("where", ["the file", "under the file", "/proc/quadruped_dyn", "/proc"])
def test_unwritable_out_is_rejected_before_the_work(command, where, a_file, no_work):
    out = {"the file": str(a_file), "under the file": str(a_file / "gen")}.get(where, where)
    _fails_with([*command, "--out", out], r"--out '.*'.*(is a file|is not writable).*; expected a writable directory")


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_out_is_rejected(tmp_path, no_work):
    tmp_path.chmod(0o500)
    try:
        _fails_with(["codegen", "paper", "--out", str(tmp_path / "gen")], r"is not writable")
    finally:
        tmp_path.chmod(0o700)


def test_codegen_check_needs_a_directory(tmp_path):
    _fails_with(["codegen", "paper", "--check", "--out", str(tmp_path / "none")], r"is not a directory; expected")


def test_missing_compiler_is_exit_2(tmp_path, no_work):
    _fails_with(["bench"], r"gcc, g\+\+ not found; expected on PATH", env={"PATH": str(tmp_path)})


@pytest.mark.parametrize("kind", ["file", "under a file"])
def test_bench_cache_that_is_a_file(kind, a_file, no_work):
    cache = str(a_file) if kind == "file" else str(a_file / "cache")
    _fails_with(["bench"], r"QUADRUPED_DYN_CACHE.*is a file; expected a writable directory", env={"QUADRUPED_DYN_CACHE": cache})


def test_make_urdf_into_unwritable_place(monkeypatch):
    monkeypatch.setattr(paper_robot, "URDF_COPIES", (Path("/proc/quadruped_dyn/paper_quadruped.urdf"),))
    _fails_with(["make-urdf"], r"cannot write '/proc/quadruped_dyn/paper_quadruped.urdf' .*expected a writable file")


@pytest.mark.parametrize("kind", ["missing", "a directory"])
def test_bundled_urdf_missing_or_a_directory(kind, tmp_path, monkeypatch):
    monkeypatch.setattr(robot, "URDF_PATH", tmp_path / "paper_quadruped.urdf")
    if kind == "a directory":
        (tmp_path / "paper_quadruped.urdf").mkdir()
    for command in (["info", "paper"], ["check", "paper"], ["codegen", "paper", "--out", str(tmp_path / "gen")]):
        _fails_with(command, r"the URDF of built-in robot 'paper' is missing at .*; expected the installed package's file")


def test_check_progress_without_a_terminal():
    result = CliRunner().invoke(main, ["check", "paper", "--samples", "2"])
    assert result.exit_code == 0
    assert "checking paper: 2/2" in result.stderr
