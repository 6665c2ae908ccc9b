"""Bad input: exit code 2 and a one-line message saying what was found and what was expected.

Bad URDFs (``info``), and bad command-line arguments, found BEFORE any work starts (the work is
replaced by a tripwire that fails the test if it runs)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.bench import timing as bench
from quadruped_dyn.cli import main
from quadruped_dyn.codegen import emit as codegen
from quadruped_dyn.experiment import paper_experiment as validation
from quadruped_dyn.model import paper_robot, registry


def _info(path: str) -> tuple[int, str]:
    result = CliRunner().invoke(main, ["info", path])
    assert "Traceback" not in result.output
    return result.exit_code, result.stderr


def _paper_variant(tmp_path, old: str, new: str) -> str:
    text = paper_robot.urdf_text()
    assert old in text
    path = tmp_path / "variant.urdf"
    path.write_text(text.replace(old, new, 1))
    return str(path)


SHANK_MASS = f'<mass value="{paper_robot.PARAMS.shank_mass:g}"/>'


@pytest.mark.parametrize(
    ("case", "expected"),
    [
        ("missing", r"no such file.*expected a URDF path or one of"),
        ("malformed", r"not well-formed XML.*expected a URDF"),
        ("not_urdf", r"root element <html>.*expected a URDF <robot>"),
        ("two_dof_legs", r"4 joint chains from the trunk with \[2, 2, 2, 2\] joints; expected a quadruped"),
        ("humanoid", r"joint chains from the trunk.*expected a quadruped"),
        ("fixed_base_arm", r"joint chains from the trunk.*expected a quadruped"),
        ("prismatic", r"leg joint 'FL_HAA' is prismatic \(JointModelP.*expected revolute"),
        ("zero_mass", r"moved by joint 'FL_KFE' has mass 0 kg.*expected a positive mass"),
        ("non_pd_inertia", r"link 'FL_shank' <inertial> <inertia> is not positive semi-definite.*expected a physical rigid body"),
        ("knee_deleted", r"cannot parse.*Two root links.*expected one tree of links.*four legs of three revolute joints"),
    ],
)
def test_bad_urdf(case, expected, tmp_path, erd):
    paths = {
        "missing": str(tmp_path / "nope.urdf"),
        "two_dof_legs": str(erd / "quadruped_description/urdf/quadruped.urdf"),
        "humanoid": str(erd / "simple_humanoid_description/urdf/simple_humanoid.urdf"),
        "fixed_base_arm": str(erd / "ur_description/urdf/ur5_robot.urdf"),
    }
    if case == "malformed":
        (tmp_path / "bad.urdf").write_text("<robot><link name='a'></robot>")
        paths[case] = str(tmp_path / "bad.urdf")
    elif case == "not_urdf":
        (tmp_path / "page.urdf").write_text("<html></html>")
        paths[case] = str(tmp_path / "page.urdf")
    elif case == "prismatic":
        paths[case] = _paper_variant(tmp_path, '<joint name="FL_HAA" type="revolute">', '<joint name="FL_HAA" type="prismatic">')
    elif case == "knee_deleted":  # the shank is left without a parent: a second root
        text = paper_robot.urdf_text()
        start = text.index('<joint name="FL_KFE"')
        paths[case] = _paper_variant(tmp_path, text[start : text.index("</joint>", start) + len("</joint>")], "")
    elif case == "zero_mass":
        paths[case] = _paper_variant(tmp_path, SHANK_MASS, '<mass value="0"/>')
    elif case == "non_pd_inertia":
        text = paper_robot.urdf_text()
        shank = text.index('<link name="FL_shank">')
        ixx = re.search(r'ixx="[^"]+"', text[shank:]).group(0)
        paths[case] = _paper_variant(tmp_path, text[shank : text.index(ixx, shank) + len(ixx)],
                                     text[shank : text.index(ixx, shank)] + 'ixx="-1"')
    code, err = _info(paths[case])
    assert code == 2, err
    assert re.search(expected, err), err
    assert err.count("\n") == 1, "expected a one-line message"


def test_unknown_command_line_argument_is_exit_2():
    assert CliRunner().invoke(main, ["info"]).exit_code == 2


def test_cli_subprocess_has_no_traceback(tmp_path):
    """The installed entry point, as a user runs it."""
    proc = subprocess.run(
        [sys.executable, "-m", "quadruped_dyn.cli", "info", str(tmp_path / "missing.urdf")],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: no such file") and "Traceback" not in proc.stderr


# ----------------------------------------------------------------------------- command-line arguments


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
    (["check", "paper", "--samples", "100001"], r"'--samples': 100001 is not in the range 1<=x<=100000"),
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
@pytest.mark.parametrize("where", ["the file", "under the file", "a dangling link", "under a dangling link",
                                   "/proc/quadruped_dyn", "/proc"])
def test_unwritable_out_is_rejected_before_the_work(command, where, a_file, no_work):
    dangling = a_file.parent / "dangling"
    dangling.symlink_to(a_file.parent / "nowhere")
    out = {"the file": str(a_file), "under the file": str(a_file / "gen"), "a dangling link": str(dangling),
           "under a dangling link": str(dangling / "gen")}.get(where, where)
    reason = r"is a symbolic link to '.*nowhere', which does not exist" if "dangling" in where \
        else r"(is a file|is not writable)"
    _fails_with([*command, "--out", out], rf"--out '.*'.*{reason}.*; expected a writable directory")


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


def test_bench_bad_robot_is_one_line_without_the_peers_headers(no_work, monkeypatch):
    """The note that pinocchio-cppadcodegen is not timed came before the checks: two lines."""
    from quadruped_dyn.bench import cppadcg

    monkeypatch.setattr(cppadcg, "available", lambda: False)
    _fails_with(["bench", "--robot", "/nonexistent.urdf"], r"no such file: '/nonexistent.urdf'")


def test_make_urdf_into_unwritable_place(monkeypatch):
    monkeypatch.setattr(paper_robot, "URDF_COPIES", (Path("/proc/quadruped_dyn/paper_quadruped.urdf"),))
    _fails_with(["make-urdf"], r"cannot write '/proc/quadruped_dyn/paper_quadruped.urdf' .*expected a writable file")


@pytest.mark.parametrize("kind", ["missing", "a directory"])
def test_bundled_urdf_missing_or_a_directory(kind, tmp_path, monkeypatch):
    monkeypatch.setattr(registry, "URDF_PATH", tmp_path / "paper_quadruped.urdf")
    if kind == "a directory":
        (tmp_path / "paper_quadruped.urdf").mkdir()
    for command in (["info", "paper"], ["check", "paper"], ["codegen", "paper", "--out", str(tmp_path / "gen")]):
        _fails_with(command, r"the URDF of built-in robot 'paper' is missing at .*; expected the installed package's file")


def test_check_progress_without_a_terminal():
    result = CliRunner().invoke(main, ["check", "paper", "--samples", "2"])
    assert result.exit_code == 0
    assert "checking paper: 2/2" in result.stderr


def test_numerical_failure_is_exit_1_one_line(monkeypatch):
    """A numerical outcome is not bad input: NumericalError exits 1 with one line, no traceback."""
    from quadruped_dyn.checks import terms
    from quadruped_dyn.errors import NumericalError

    def singular(*args, **kwargs):
        raise NumericalError("M_r of FL+FR has condition number 3.0e+17 here; the reduced model is singular")

    monkeypatch.setattr(terms, "run_check", singular)
    result = CliRunner().invoke(main, ["check", "paper", "--samples", "1"])
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    # the progress display may have drawn its lines first (stderr is not a terminal here); the error is one line
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert errors == ["error: M_r of FL+FR has condition number 3.0e+17 here; the reduced model is singular"]
    assert result.stderr.endswith(errors[0] + "\n")
