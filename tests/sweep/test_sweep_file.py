"""The sweep file: every kind of bad input is exit 2 and one line naming the key, before any task or
cluster (``engine.connect`` and ``engine.run`` are tripwires here); what a good file expands to."""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.errors import InputError
from quadruped_dyn.sweep import engine
from quadruped_dyn.sweep.robots import sweep_robots
from quadruped_dyn.sweep.spec import read_spec
from quadruped_dyn.sweep.tasks import sweep_tasks

REPO = Path(__file__).resolve().parents[2]
CHECK = '[robots]\nnames = ["paper"]\n[tasks.check]\nstates = 2\nlibraries = []\n'


@pytest.fixture
def tripwire(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("a cluster was started or a task submitted before the input was checked")

    monkeypatch.setattr(engine, "connect", fail)
    monkeypatch.setattr(engine, "run", fail)


def _sweep(tmp_path: Path, text: str, *args: str) -> tuple[int, str]:
    path = tmp_path / "s.toml"
    path.write_text(text)
    result = CliRunner().invoke(main, ["sweep", str(path), "--out", str(tmp_path / "out"), *args])
    assert "Traceback" not in result.output
    return result.exit_code, result.stderr


@pytest.mark.parametrize(("text", "key"), [
    (CHECK.replace("states", "statse"), r"unknown key 'tasks\.check\.statse'"),
    (CHECK.replace("states = 2", 'states = "two"'), r"tasks\.check\.states is 'two', a str; expected a whole number"),
    (CHECK.replace('names = ["paper"]', "names = []"), r"robots is empty"),
    (CHECK.replace('names = ["paper"]', 'paths = ["nowhere/*.urdf"]'), r"robots\.paths\[0\] 'nowhere/\*\.urdf' matches no file"),
    (CHECK.replace('names = ["paper"]', 'names = ["paper", "spot"]'), r"robots\.names\[1\] 'spot' is not a built-in"),
    (CHECK + "[tasks.control]\ncontrollers = ['pd', 'lqr']\n", r"tasks\.control\.controllers\[1\] 'lqr' is unknown"),
    (CHECK + "[tasks.control.perturbations]\nmu = [0.5, 0.2]\n", r"tasks\.control\.perturbations\.mu is \[0\.5, 0\.2\]"),
    (CHECK + "[tasks.control.perturbations]\ngravity = 2\n", r"unknown key 'tasks\.control\.perturbations\.gravity'"),
    (CHECK + "[tasks.control]\ncycles = 1\n[tasks.control.perturbations]\npush_at_s = [0.0, 5.0]\n",
     r"tasks\.control\.perturbations\.push_at_s reaches 5 s; expected times of the run, before its 1\.2 s \(1 cycles\)"),
    (CHECK + "[tasks.control.perturbations]\nstep_height_m = [0.0, 0.5]\n", r"perturbations\.step_height_m is \[0, 0\.5\]"),
    ('[robots]\nnames = ["paper"]\n', r"tasks is empty"),
    ("[robots\n", r"is not TOML"),
])
def test_bad_sweep_file_is_one_line_naming_the_key(tmp_path, tripwire, text, key):
    code, err = _sweep(tmp_path, text)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and re.search(key, err), err


def test_unwritable_out_is_refused_before_any_task(tmp_path, tripwire):
    (tmp_path / "file").write_text("")
    path = tmp_path / "s.toml"
    path.write_text(CHECK)
    result = CliRunner().invoke(main, ["sweep", str(path), "--out", str(tmp_path / "file" / "out")])
    assert result.exit_code == 2 and "--out" in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_rows_present_without_resume_are_refused(tmp_path, tripwire):
    (tmp_path / "out" / "rows").mkdir(parents=True)
    (tmp_path / "out" / "rows" / "check-0.parquet").write_bytes(b"")
    code, err = _sweep(tmp_path, CHECK)
    assert code == 2 and "expected --resume" in err


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_unreachable_scheduler_is_exit_2_within_10_s(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(CHECK)
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "sweep", str(path), "--out", str(tmp_path / "out"),
                           "--scheduler", f"tcp://127.0.0.1:{_free_port()}"], capture_output=True, text=True, timeout=60)
    assert time.monotonic() - start < 10.0
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "no scheduler answered" in proc.stderr
    assert not list((tmp_path / "out" / "rows").glob("*.parquet"))


def test_bad_scheduler_address_is_refused(tmp_path, tripwire):
    code, err = _sweep(tmp_path, CHECK, "--scheduler", "127.0.0.1")
    assert code == 2 and "expected tcp://HOST:PORT" in err


def test_expansion_keys_and_samples(tmp_path):
    """Variants by relative path, one task per (robot, seed) / (robot, gait, controller, run); keys by content: the same
    sample for every controller of a run, another for another run; a variant's bytes change its key."""
    (tmp_path / "robots").mkdir()
    urdf = (REPO / "urdf" / "paper_quadruped.urdf").read_text()
    (tmp_path / "robots" / "mine.urdf").write_text(urdf.replace("<robot", "<!-- a copy -->\n<robot", 1))
    path = tmp_path / "s.toml"
    path.write_text('[robots]\nnames = ["paper"]\npaths = ["robots/*.urdf"]\n'
                    '[[robots.variants]]\nrobot = "robots/mine.urdf"\ncount = 3\nmass_scale = [0.8, 1.2]\n'
                    '[tasks.check]\nrepeats = 2\nlibraries = []\n'
                    '[tasks.control]\ncontrollers = ["pd", "ct-diag"]\nruns = 3\n'
                    '[tasks.control.perturbations]\nmu = [0.3, 1.0]\n')
    spec = read_spec(path)
    robots = sweep_robots(spec)
    assert [r.label for r in robots] == ["paper", "mine", "mine_v000", "mine_v001", "mine_v002"]
    assert len({r.sha256 for r in robots}) == 5 and all(0.8 <= r.scales[0] <= 1.2 for r in robots[2:])
    tasks = sweep_tasks(spec, robots)
    assert len(tasks) == 5 * (2 + 2 * 3) and len({t.key for t in tasks}) == len(tasks)
    control = [t for t in tasks if t.kind == "control" and t.robot.label == "paper"]
    by_run = {}
    for t in control:
        by_run.setdefault(t.options["run"], set()).add(t.options["perturbation"]["mu"])
    assert all(len(v) == 1 for v in by_run.values()) and len({next(iter(v)) for v in by_run.values()}) == 3
    assert [t.key for t in sweep_tasks(read_spec(path), sweep_robots(read_spec(path)))] == [t.key for t in tasks]


def test_spec_errors_are_input_errors(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(CHECK.replace("[tasks.check]", "[[robots.variants]]\ncount = 2\n[tasks.check]"))
    with pytest.raises(InputError, match=r"robots\.variants\[0\]\.robot is missing"):
        read_spec(path)


@pytest.mark.parametrize("path", sorted((REPO / "sweeps").glob("*.toml")), ids=lambda p: p.name)
def test_shipped_sweeps_are_valid(path):
    spec = read_spec(path)
    tasks = sweep_tasks(spec, sweep_robots(spec))
    assert tasks and len({t.key for t in tasks}) == len(tasks)


def test_a_variant_reaches_the_worker_as_its_bytes(tmp_path, monkeypatch):
    """materialise: the bytes written into a fresh verified cache under their hash, loaded; a built-in by name."""
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.sweep.robots import materialise

    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "s.toml"
    path.write_text(CHECK.replace("[tasks.check]", '[[robots.variants]]\nrobot = "paper"\nmass_scale = 1.25\n[tasks.check]'))
    paper_ref, variant_ref = sweep_robots(read_spec(path))
    assert paper_ref.builtin == "paper" and paper_ref.urdf is None and variant_ref.urdf is not None
    variant = materialise(variant_ref)
    assert variant.urdf_sha256 == variant_ref.sha256 and variant.urdf.is_relative_to(tmp_path / "cache")
    assert variant.total_mass == pytest.approx(1.25 * load_robot("paper").total_mass, rel=1e-12)
    assert materialise(paper_ref) is load_robot("paper")


def test_scaling_benchmark_bad_input_is_exit_2_before_any_run(tmp_path, monkeypatch, capsys):
    from quadruped_dyn.sweep import scaling

    def fail(*args, **kwargs):
        raise AssertionError("a sweep was run before the input was checked")

    monkeypatch.setattr(scaling, "_one_run", fail)
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "old.json").write_text("{}")
    path = tmp_path / "s.toml"
    path.write_text(CHECK)
    for argv, said in (([str(tmp_path / "none.toml")], "cannot read the sweep file"),
                       ([str(path), "--out", str(tmp_path / "out")], "is not empty; expected a new folder"),
                       ([str(path), "--workers", "0"], "expected whole numbers >= 1")):
        assert scaling.main(argv) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and said in err, err
