"""Two URDFs with the same file stem (/a/robot.urdf, /b/robot.urdf) are both named ``robot``: the
second run must not write over the first's outputs (files/provenance.py, docs/reliability.md §3)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.model.paper_robot import URDF_PATH


def _urdf(folder: Path, tag: str) -> Path:
    """The paper robot's URDF with a comment appended: another file's bytes, loaded in a second,
    named after its stem ("robot")."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "robot.urdf"
    path.write_text(URDF_PATH.read_text() + f"<!-- {tag} -->\n")
    return path


def _stub_report(monkeypatch):
    """``report`` without its sections (each fails at once): the page, written in seconds."""
    from quadruped_dyn.report import build

    def broken(*_args, **_kwargs):
        raise RuntimeError("stubbed out")

    for name in ("_terms_section", "_grf_section", "_reduced_section", "_experiment_section", "_c_section",
                 "_symbolic_section", "optimal_trot", "closed_loop", "_notebooks_section"):
        monkeypatch.setattr(build, name, broken)


def _report(robot: Path | str, out: Path):
    return CliRunner().invoke(main, ["report", str(robot), "--out", str(out), "--fast", "--samples", "1"])


def _tripwire(*_args, **_kwargs):
    raise AssertionError("the work started before the output folder was checked")


@pytest.fixture
def results(tmp_path, monkeypatch) -> Path:
    """``results/`` holding the report of /a/robot.urdf."""
    _stub_report(monkeypatch)
    monkeypatch.setattr("quadruped_dyn.report.build.warm.start", lambda *a, **k: (None, None, None))
    out = tmp_path / "results"
    result = _report(_urdf(tmp_path / "a", "a"), out)
    assert result.exit_code == 1, result.output  # every stubbed section is FAIL
    assert (out / "robot" / "report.html").is_file()
    return out


def _refused(result, out: Path, other: Path) -> None:
    assert result.exit_code == 2, result.output
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output, result.stderr
    line = result.stderr
    assert f"--out '{out}'" in line and f"'{other}'" in line, line
    assert "expected another --out for it, e.g. --out" in line, line


def test_a_second_urdf_of_the_same_name_does_not_overwrite_the_first_report(results, tmp_path, monkeypatch):
    page = (results / "robot" / "report.html").read_bytes()
    monkeypatch.setattr("quadruped_dyn.report.build._staging", _tripwire)
    result = _report(_urdf(tmp_path / "b", "b"), results)
    _refused(result, results, tmp_path / "a" / "robot.urdf")
    assert (results / "robot" / "report.html").read_bytes() == page


@pytest.mark.parametrize(("command", "heavy"), [
    (["validate", "--horizon", "0.05", "--no-physics"], "quadruped_dyn.experiment.simulate.reduced_dynamics"),
    (["control", "--cycles", "1"], "quadruped_dyn.control.closed_loop.run_all"),
    (["optimize", "--cycles", "0"], "quadruped_dyn.optimal_control.transcription.transcribe"),
    (["codegen"], "quadruped_dyn.checks.check_program_values.generate_checked"),
])
def test_every_command_refuses_another_urdfs_folder_before_the_work(results, tmp_path, monkeypatch, command, heavy):
    monkeypatch.setattr(heavy, _tripwire)
    b = _urdf(tmp_path / "b", "b")
    result = CliRunner().invoke(main, [command[0], str(b), *command[1:], "--out", str(results)])
    _refused(result, results, tmp_path / "a" / "robot.urdf")


def test_the_same_file_edited_or_copied_writes_over_its_own_outputs(results, tmp_path):
    """An edited URDF (same path, new bytes) and a copy (new path, same bytes) are the same robot's
    outputs, written as before; so is a built-in robot, which needs no record."""
    a = tmp_path / "a" / "robot.urdf"
    a.write_text(a.read_text() + "<!-- edited -->\n")
    assert _report(a, results).exit_code == 1
    copy = tmp_path / "copy" / "robot.urdf"
    copy.parent.mkdir()
    copy.write_bytes(a.read_bytes())
    assert _report(copy, results).exit_code == 1
    assert json.loads((results / "robot.source.json").read_text()) == {
        "robot": "robot", "urdf": str(copy.resolve()), "urdf_sha256": hashlib.sha256(a.read_bytes()).hexdigest()}
    assert _report("paper", results).exit_code == 1
    assert (results / "paper" / "report.html").is_file() and not (results / "paper.source.json").exists()


def test_a_record_that_is_not_one_is_refused(tmp_path):
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.files.provenance import check_source, record_source
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot(str(_urdf(tmp_path / "a", "a")))
    assert record_source(tmp_path, robot) == tmp_path / "robot.source.json"
    check_source(tmp_path, robot)  # its own record
    (tmp_path / "robot.source.json").write_text("[1, 2]")
    with pytest.raises(InputError, match="does not say which URDF the outputs of 'robot' came from"):
        check_source(tmp_path, robot)


@pytest.mark.parametrize("content", ["[" * 200_000 + "]" * 200_000, "{" + " " * 100_000 + "}", "dir", "devzero"])
def test_a_hostile_record_is_an_input_error(tmp_path, content):
    """A record nested past Python's recursion limit was a RecursionError traceback; a record that is a huge
    file or a symlink to /dev/zero was read whole (endlessly). Each is an InputError naming the record."""
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.files.provenance import check_source, record_path
    from quadruped_dyn.model.robot_identity import urdf_source

    source = urdf_source(_urdf(tmp_path / "a", "a"))
    out = tmp_path / "out"
    out.mkdir()
    record = record_path(out, source.name)
    if content == "dir":
        record.mkdir()
    elif content == "devzero":
        record.symlink_to("/dev/zero")
    else:
        record.write_text(content)
    with pytest.raises(InputError, match=r"robot.source.json' does not say which URDF"):
        check_source(out, source)
