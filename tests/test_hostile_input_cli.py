"""Bad input at the command line: nothing written outside --out or
through a link, hostile file names, bounded work, write failures, empty paths, non-results;
each one line, exit 2 (bad input) or 1 (not a result), no traceback."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.checks import check_program_values
from quadruped_dyn.cli import main
from quadruped_dyn.codegen import emit as codegen
from quadruped_dyn.experiment import paper_experiment as validation
from quadruped_dyn.files.names import is_safe_name
from quadruped_dyn.model.paper_robot import URDF_PATH

EDITED = URDF_PATH.read_text().replace('<mass value="5.4"/>', '<mass value="7.4"/>')  # not the paper robot


def _one_line(result, code: int, expected: str) -> None:
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output and re.search(expected, result.stderr), result.stderr
    assert result.stderr.count("\n") == 1, result.stderr


@pytest.fixture
def no_work(monkeypatch):
    def tripwire(*args, **kwargs):
        raise AssertionError("the work started before the arguments were checked")

    monkeypatch.setattr(validation, "run_experiment", tripwire)
    monkeypatch.setattr(codegen, "generate", tripwire)
    monkeypatch.setattr(check_program_values, "generate", tripwire)  # bound by name there: patched and restored too


def _cli(*args: str, stdout: object = subprocess.PIPE, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", *args], stdout=stdout, stderr=subprocess.PIPE,
                          text=True, env={**os.environ, **(env or {})}, check=False)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
@pytest.mark.parametrize("args", [["info", "paper", "--json"], ["info", "paper"], ["robots"]])
def test_a_failed_write_to_stdout_is_one_line(args):
    with open("/dev/full", "w") as full:
        proc = _cli(*args, stdout=full)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr and "Exception" not in proc.stderr, proc.stderr
    assert proc.stderr.strip().splitlines() == ["error: cannot write to standard output (No space left on device); "
                                                "expected a writable output"]


@pytest.mark.parametrize("args", [["codegen", "paper", "--out", ""], ["validate", "--out", ""], ["report", "--out", ""],
                                  ["codegen", "paper", "--out", " "]])
def test_an_empty_out_is_refused(args, no_work):
    _one_line(CliRunner().invoke(main, args), 2, r"--out '\s*' is an empty path; expected a directory name")


def test_an_empty_cache_variable_is_refused(tmp_path):
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.files.cache import cache_dir

    for value in ("", "  "):
        with pytest.MonkeyPatch.context() as m:
            m.setenv("QUADRUPED_DYN_CACHE", value)
            with pytest.raises(InputError, match="QUADRUPED_DYN_CACHE is set but empty"):
                cache_dir()
            result = CliRunner().invoke(main, ["bench", "--calls", "1", "--reps", "1"], env={"QUADRUPED_DYN_CACHE": value})
            _one_line(result, 2, "QUADRUPED_DYN_CACHE is set but empty")


@pytest.mark.parametrize(("args", "expected"), [
    (["--dt", "1e-12"], r"is 1\.2e\+12 samples per run; expected at most 200,000"),
    (["--horizon", "1e9"], r"--horizon 1e\+09 s at --dt 0\.001 s is 1e\+12 samples"),
    (["--dt", "1e-6"], r"is 1\.2e\+06 samples per run"),
    (["--horizon", "1e300", "--dt", "1e-300"], r"samples per run; expected at most"),
])
def test_validate_bounds_the_work_up_front(args, expected, no_work, tmp_path):
    _one_line(CliRunner().invoke(main, ["validate", "--out", str(tmp_path), *args]), 2, expected)


@pytest.mark.parametrize(("args", "expected"), [
    (["control", "paper", "--cycles", "100000000"], r"is 2\.4e\+11 MuJoCo steps per controller; expected at most 2,000,000"),
    (["control", "paper", "--timestep", "1e-12"], r"at a 1e-12 s step is 1\.2e\+13 MuJoCo steps"),
    (["control", "paper", "--mu", "1e6"], r"friction mu = 1000000\.0; expected a number from 0 to 1000"),
    (["optimize", "--cycles", "1e9"], r"replay samples at 0\.002 s; expected at most 200,000"),
    (["optimize", "--nodes", "100000"], r"--nodes 100000; expected 3 to 40 collocation nodes per phase"),
])
def test_control_and_optimize_bound_the_work_up_front(args, expected, monkeypatch, tmp_path):
    """Found by a fresh-clone review: these ran for minutes (or ever), or failed with a
    traceback after the solve (--cycles 1e9: a 2 TiB allocation), or returned a blown-up MuJoCo run as
    a result (mu 1e6)."""
    from quadruped_dyn.control import closed_loop
    from quadruped_dyn.optimal_control import transcription

    def tripwire(*a, **k):
        raise AssertionError("the work started before the arguments were checked")

    monkeypatch.setattr(closed_loop, "build_plant", tripwire)
    monkeypatch.setattr(transcription, "transcribe", tripwire)
    _one_line(CliRunner().invoke(main, [*args, "--out", str(tmp_path)]), 2, expected)


@pytest.mark.parametrize("extra", [["--no-physics"], ["--json", "--no-physics"], []])
def test_a_run_that_fell_on_its_first_step_is_not_a_result(extra, tmp_path):
    """The static walk with RK4 at --dt 0.3 s (one step per phase) falls at once: exit 1, no
    0 % error, no files."""
    result = CliRunner().invoke(main, ["validate", "--integrator", "rk4", "--dt", "0.3", "--gait", "walk", *extra,
                                       "--out", str(tmp_path)])
    assert result.exit_code == 1, result.output
    assert "run stopped at t = 0 s after 1 sample(s)" in result.stderr and "no result" in result.stderr
    assert "0.0e+00" not in result.output and not list(tmp_path.glob("*_validation.json"))


def test_percent_errors_need_two_samples():
    import numpy as np

    from quadruped_dyn.experiment.paper_experiment import percent_errors

    ref = np.ones((5, 12))
    assert percent_errors(ref[:1], ref) == [None] * 12
    assert percent_errors(ref[:0], ref) == [None] * 12
    assert percent_errors(2 * ref[:2], ref) == [100.0] * 12


ESCAPE = "evil\x1b]0;owned\x07\x1b[31m"


def test_terminal_escapes_in_names_are_not_echoed(tmp_path):
    """An escape sequence in a file name reaches the terminal escaped, in errors and in info."""
    missing = CliRunner().invoke(main, ["info", str(tmp_path / f"{ESCAPE}.urdf")])
    _one_line(missing, 2, r"no such file: .*evil\\x1b\]0;owned\\x07\\x1b\[31m")
    assert "\x1b" not in missing.output
    (tmp_path / f"{ESCAPE}.urdf").write_text(EDITED)
    shown = CliRunner().invoke(main, ["info", str(tmp_path / f"{ESCAPE}.urdf")])
    assert shown.exit_code == 0 and "\x1b" not in shown.output and "\x07" not in shown.output, shown.output
    (tmp_path / f"{ESCAPE}2.urdf").write_text("<robot><link/>")
    bad = CliRunner().invoke(main, ["info", str(tmp_path / f"{ESCAPE}2.urdf")])
    _one_line(bad, 2, "not well-formed XML")
    assert "\x1b" not in bad.output


def test_codegen_writes_only_under_out_and_never_through_a_link(tmp_path):
    """A URDF named '...urdf' (stem '..', which put the report in the parent of --out) generates
    under --out with a valid name (one generation; the other hostile stems are checked without
    generating in tests/model/test_identity.py); a symlink already in --out (Makefile -> a file
    elsewhere) is replaced, the file it pointed to is untouched."""
    victim = tmp_path / "victim"
    victim.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / "Makefile").symlink_to(victim)
    (tmp_path / "...urdf").write_text(EDITED)
    result = CliRunner().invoke(main, ["codegen", str(tmp_path / "...urdf"), "--out", str(out)])
    assert result.exit_code == 0, result.output
    written = [Path(line.removeprefix("wrote ")) for line in result.output.splitlines()]
    assert written and all(p.parent == out and p.is_file() and not p.is_symlink() for p in written)
    assert not (out / "Makefile").is_symlink() and victim.read_text() == "keep me"
    robot = next(p.name for p in written if p.name.endswith("-reference.h")).removeprefix("qd_").removesuffix("-reference.h")
    assert is_safe_name(robot) and robot.startswith("robot_"), robot
    assert sorted(p.name for p in tmp_path.iterdir()) == ["...urdf", "out", "victim"], "nothing written beside --out"
    assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written), "no partial files left"


def test_output_paths_are_plain_names_under_out(tmp_path):
    from quadruped_dyn.errors import InputError
    from quadruped_dyn.experiment.validation_files import output_paths
    from quadruped_dyn.files.safe_write import output_dir, output_path, write_text

    for bad in ("..", ".", "", "a/b", "../x", "x\0"):
        with pytest.raises(InputError, match="not a plain file name"):
            output_path(tmp_path, bad.replace("\\0", "\0"))
    assert all(p.parent == tmp_path for p in output_paths(tmp_path, "..", "walk").values())
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "elsewhere")
    with pytest.raises(InputError, match="is a symbolic link"):
        output_dir(tmp_path, "link")
    target = tmp_path / "f.txt"
    target.symlink_to(tmp_path / "elsewhere" / "g.txt")
    write_text(output_path(tmp_path, "f.txt"), "new")
    assert not target.is_symlink() and target.read_text() == "new" and not (tmp_path / "elsewhere" / "g.txt").exists()
    (tmp_path / "d").mkdir()
    os.mkfifo(tmp_path / "fifo")
    for special in ("d", "fifo"):  # never replaced (nor a device such as /dev/full)
        with pytest.raises(InputError, match="exists and is not a regular file"):
            write_text(tmp_path / special, "x")
    assert (tmp_path / "d").is_dir() and (tmp_path / "fifo").is_fifo()
    (tmp_path / "ro").mkdir()
    (tmp_path / "ro").chmod(0o500)
    if not os.access(tmp_path / "ro", os.W_OK):  # root writes anyway
        with pytest.raises(InputError, match="cannot write .*Permission denied"):
            write_text(tmp_path / "ro" / "x.txt", "x")


@pytest.mark.parametrize(("args", "expected"), [
    (["bench", "--peers", "none", "--calls", "2147483648"], r"--calls.*2147483648 is not in the range 1<=x<=10000000"),
    (["bench", "--peers", "none", "--reps", "99999999999999999999"], r"--reps.*is not in the range 1<=x<=1000"),
])
def test_bench_counts_are_bounded_up_front(args, expected):
    """The harnesses read the counts as a C int: 2^31 calls divided by zero, 2^63 gave negative times."""
    _one_line(CliRunner().invoke(main, args), 2, expected)


@pytest.mark.parametrize("calls", [0, 2**31, 10**20, 1.5, True])
def test_run_bench_refuses_counts_outside_the_bounds(calls, paper):
    from quadruped_dyn.bench.timing import run_bench
    from quadruped_dyn.errors import InputError

    with pytest.raises(InputError, match="calls is .*; expected an integer from 1 to 10,000,000"):
        run_bench(paper, calls=calls)  # type: ignore[arg-type]


@pytest.mark.parametrize("path", ["/dev/null", "/"])
def test_a_path_that_is_not_a_file_says_so(path):
    _one_line(CliRunner().invoke(main, ["info", path]), 2, rf"not a regular file: '{path}'; expected a URDF path")


def test_check_bounds_the_work_up_front():
    """A billion random states (~years at ~15 states/s) is refused before the models are built."""
    _one_line(CliRunner().invoke(main, ["check", "paper", "--samples", "1000000000"]), 2,
              r"'--samples': 1000000000 is not in the range 1<=x<=100000")


def test_paths_in_a_summary_are_echoed_escaped(tmp_path):
    """Found by a review: validate, control, optimize, report and check printed their
    summaries with click.echo, so an --out with a newline split the "wrote" line and an OSC sequence
    (click strips only CSI ones, only off a terminal) reached the terminal raw."""
    out = tmp_path / f"{ESCAPE}\nline"
    result = CliRunner().invoke(main, ["validate", "--horizon", "0.05", "--no-physics", "--out", str(out)])
    assert result.exit_code == 0, result.output
    wrote = [line for line in result.stdout.splitlines() if "wrote" in line]
    assert len(wrote) == 1 and "evil\\x1b]0;owned\\x07" in wrote[0] and "\\nline/paper_trot_validation.json" in wrote[0]
    assert "\x1b" not in result.stdout and "\x07" not in result.stdout


def test_every_command_prints_through_echo():
    """Command output goes through ``cli.app.echo`` (control characters escaped per line); a bare
    ``click.echo`` in a command module is allowed on stderr only (``err=True``)."""
    import ast

    from quadruped_dyn import cli

    bare = []
    for source in Path(cli.__file__).parent.glob("*_command*.py"):
        for node in ast.walk(ast.parse(source.read_text())):
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "echo"
                    and isinstance(node.func.value, ast.Name) and node.func.value.id == "click"
                    and not any(k.arg == "err" for k in node.keywords)):
                bare.append(f"{source.name}:{node.lineno}")
    assert not bare, bare


def test_an_output_set_appears_whole_or_not_at_all(tmp_path):
    """``output_set``: the files of one result are renamed into place together when the block ends;
    an error or an interrupt inside leaves the old files as they were and no temporary file."""
    from quadruped_dyn.files.safe_write import output_set, remove, write_text

    (tmp_path / "a.json").write_text("old a")
    (tmp_path / "b.csv").write_text("old b")
    with pytest.raises(KeyboardInterrupt), output_set():
        write_text(tmp_path / "a.json", "new a")
        raise KeyboardInterrupt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.csv"]
    assert (tmp_path / "a.json").read_text() == "old a"
    with output_set():
        write_text(tmp_path / "a.json", "new a")
        write_text(tmp_path / "b.csv", "new b")
        assert (tmp_path / "a.json").read_text() == "old a", "not before the block ends"
    assert [(tmp_path / n).read_text() for n in ("a.json", "b.csv")] == ["new a", "new b"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json", "b.csv"]
    with output_set():  # a file of the previous result that this one has not: removed with the set
        remove(tmp_path / "b.csv")
        assert (tmp_path / "b.csv").read_text() == "new b", "not before the block ends"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.json"]


def test_validate_interrupted_while_plotting_leaves_no_new_json(tmp_path, monkeypatch):
    """Found by a review: Ctrl-C while validate drew its plots left the new JSON beside
    the previous run's CSV and plots (each file was atomic, the set was not), and exited 1 ("Aborted!")."""
    from quadruped_dyn.experiment import validation_files

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(validation_files, "plot_br_hfe", interrupted)
    result = CliRunner().invoke(main, ["validate", "--horizon", "0.05", "--no-physics", "--out", str(tmp_path)])
    assert result.exit_code == 130, result.output  # click's 'Aborted!' was exit 1, the code of a failed check
    assert "Traceback" not in result.output and result.stderr.splitlines()[-1] == "error: interrupted", result.stderr
    assert list(tmp_path.iterdir()) == [], "no file of the interrupted run, not even a temporary one"


def test_validate_without_physics_removes_the_previous_physics_plot(tmp_path):
    """The physics plot of an earlier run is not this result's: removed with the result's set (it was unlinked after
    the set, outside it), and kept when the run is interrupted."""
    from quadruped_dyn.experiment import validation_files

    old = validation_files.output_paths(tmp_path, "paper", "trot")["physics_plot"]
    old.write_bytes(b"the previous run's plot")
    args = ["validate", "--horizon", "0.05", "--no-physics", "--out", str(tmp_path)]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(validation_files, "plot_br_hfe", lambda *a, **k: (_ for _ in ()).throw(KeyboardInterrupt))
        assert CliRunner().invoke(main, args).exit_code == 130
    assert old.read_bytes() == b"the previous run's plot"
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0 and not old.exists(), result.output


def test_output_files_are_written_through_safe_write():
    """The modules that write a command's files (JSON, CSV, plots, animation) never open, save or
    write a path themselves: only ``files.safe_write`` does (never through a link, atomic, in sets)."""
    import quadruped_dyn

    direct = re.compile(r"\.write_text\(|\.write_bytes\(|\bopen\([^)]*[\"']w|savefig\((?!buf)|\.save\((?!gif)")
    package = Path(quadruped_dyn.__file__).parent
    writers = [package / "control" / "study_files.py", package / "experiment" / "validation_files.py",
               package / "optimal_control" / "trajectory_files.py"]
    assert all(p.is_file() for p in writers), writers
    offenders = [f"{p.relative_to(package)}:{n}" for p in writers
                 for n, line in enumerate(p.read_text().splitlines(), 1) if direct.search(line)]
    offenders += [f"cli/{p.name}:{n}" for p in (package / "cli").glob("*.py")
                  for n, line in enumerate(p.read_text().splitlines(), 1) if direct.search(line)]
    assert not offenders, offenders


@pytest.mark.parametrize(("args", "in_the_way"), [
    (["validate", "--horizon", "0.05", "--no-physics"], "paper_trot_timeseries.csv"),
    (["control", "paper", "--cycles", "1", "--controller", "pd", "--no-animation"], "paper_walk_closed_loop.png"),
    (["optimize", "--cycles", "0"], "paper_trot_optimised.png"),
    (["codegen", "paper"], "qd_paper-r-FL_BR.c"),
    (["codegen", "paper"], "qd_paper-reference.h"),
])
def test_a_directory_in_place_of_an_output_is_refused_before_the_work(args, in_the_way, tmp_path, monkeypatch):
    """Found by a review: refused only when written, after the runs (control: minutes),
    the solve or the generation (codegen: tens of seconds)."""
    from quadruped_dyn.control import closed_loop
    from quadruped_dyn.optimal_control import transcription

    def tripwire(*a, **k):
        raise AssertionError("the work started before the outputs were checked")

    monkeypatch.setattr(validation, "run_experiment", tripwire)
    monkeypatch.setattr(closed_loop, "run_all", tripwire)
    monkeypatch.setattr(transcription, "transcribe", tripwire)
    monkeypatch.setattr(check_program_values, "generate", tripwire)
    (tmp_path / in_the_way).mkdir()
    result = CliRunner().invoke(main, [*args, "--out", str(tmp_path)])
    _one_line(result, 2, rf"cannot write '.*{in_the_way}': it exists and is not a regular file; expected a file path")


def test_codegen_writes_its_package_whole_or_not_at_all(paper, tmp_path):
    """A directory in place of one generated file (the Makefile): nothing of the package is written,
    not the sources before it (they were, beside whatever the directory held from before). Through the
    API: the command refuses the directory before it generates."""
    from quadruped_dyn.errors import InputError

    (tmp_path / "Makefile").mkdir()
    with pytest.raises(InputError, match=r"cannot write '.*Makefile': it exists and is not a regular file"):
        check_program_values.generate_checked(paper, tmp_path)
    assert [p.name for p in tmp_path.iterdir()] == ["Makefile"]
