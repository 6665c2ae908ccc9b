"""The sweep on real Dask processes: a `dask scheduler` and two `dask worker` processes on 127.0.0.1
(random free ports, no dashboard), one worker SIGKILLed mid-run: every row exactly once, and `--resume`
runs nothing; a LocalCluster sweep interrupted (SIGINT) and resumed; a task that kills its worker is a row
with that error. The tasks: sweeps/tiny.toml, the term check with 3 states on the paper robot, 24 seeds."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from quadruped_dyn.sweep.dataset import Dataset
from quadruped_dyn.sweep.robots import sweep_robots
from quadruped_dyn.sweep.spec import read_spec
from quadruped_dyn.sweep.tasks import sweep_tasks

REPO = Path(__file__).resolve().parents[2]
TINY = REPO / "sweeps" / "tiny.toml"
BIN = Path(sys.executable).parent
ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
#: Generous bounds on a loaded machine (a cold worker builds the symbolic models: ~10 s of CPU).
SWEEP_TIMEOUT_S = 600


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _accepts(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
        return True
    except OSError:
        return False


def _wait_for(condition, timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.2)


def _workers_on(address: str) -> int:
    """How many workers the scheduler at ``address`` has (a client that connects, asks and leaves)."""
    from distributed import Client

    with Client(address, timeout=60) as client:
        return len(client.scheduler_info()["workers"])


def _rows(out: Path) -> list[dict]:
    files = sorted((out / "rows").glob("*.parquet"))
    return [pq.read_table(f).to_pylist()[0] for f in files]  # every file a whole, readable row


def _expected_keys() -> set[str]:
    spec = read_spec(TINY)
    return {t.key for t in sweep_tasks(spec, sweep_robots(spec))}


def _sweep(out: Path, *args: str) -> subprocess.Popen:
    """The command in its own process group (as a terminal's foreground job: Ctrl-C reaches every process of it)."""
    return subprocess.Popen([sys.executable, "-m", "quadruped_dyn.cli", "sweep", str(TINY), "--out", str(out), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV, cwd=REPO,
                            start_new_session=True)


def _end(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()


def test_worker_killed_mid_run_every_row_once_then_resume_runs_nothing(tmp_path):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    common = ["--no-dashboard"]
    scheduler = subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port), *common],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV, cwd=REPO)
    procs = [scheduler]
    try:
        _wait_for(lambda: _accepts(port), 60, "the scheduler")
        workers = [subprocess.Popen([str(BIN / "dask"), "worker", address, "--host", "127.0.0.1", "--nthreads", "1",
                                     "--no-nanny", *common], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV,
                                    cwd=REPO) for _ in range(2)]
        procs += workers
        _wait_for(lambda: _workers_on(address) == 2, SWEEP_TIMEOUT_S, "both workers on the scheduler")
        out = tmp_path / "out"
        sweep = _sweep(out, "--scheduler", address)
        procs.append(sweep)
        victim = workers[0]
        # The victim's first row, however slow the machine: then it has worked, and the sweep still has rows to do.
        _wait_for(lambda: victim.pid in {r["pid"] for r in _rows(out)} or sweep.poll() is not None, SWEEP_TIMEOUT_S,
                  "a row of the worker to kill")
        assert sweep.poll() is None, sweep.communicate()
        victim.send_signal(signal.SIGKILL)
        victim.wait()
        stdout, stderr = sweep.communicate(timeout=SWEEP_TIMEOUT_S)
        assert sweep.returncode == 0, stderr[-2000:]
        rows = _rows(out)
        keys = [r["key"] for r in rows]
        assert sorted(keys) == sorted(_expected_keys()) and len(keys) == len(set(keys)) == 24
        assert all(r["status"] == "ok" and r["passed"] for r in rows), [r["error"] for r in rows if r["status"] != "ok"]
        pids = {r["pid"] for r in rows}
        assert victim.pid in pids and workers[1].pid in pids  # both worked; the survivor finished the sweep
        assert not list((out / "rows").glob("*.partial-*"))
        assert (out / "summary.html").is_file() and "Terms: worst relative error" in (out / "summary.html").read_text()
        before = {f.name: f.stat().st_mtime_ns for f in (out / "rows").iterdir()}
        again = _sweep(out, "--scheduler", address, "--resume")
        _, stderr = again.communicate(timeout=SWEEP_TIMEOUT_S)
        assert again.returncode == 0, stderr[-2000:]
        assert "24 already in" in stderr and "0 to run" in stderr
        assert {f.name: f.stat().st_mtime_ns for f in (out / "rows").iterdir()} == before
    finally:
        _end(procs[::-1])


def test_local_cluster_interrupted_then_resumed(tmp_path):
    out = tmp_path / "out"
    sweep = _sweep(out, "--workers", "1")
    try:
        _wait_for(lambda: len(list((out / "rows").glob("*.parquet"))) >= 2 or sweep.poll() is not None, SWEEP_TIMEOUT_S,
                  "two rows")
        assert sweep.poll() is None, sweep.communicate()
        os.killpg(sweep.pid, signal.SIGINT)  # Ctrl-C: the command and its LocalCluster's processes
        _, stderr = sweep.communicate(timeout=120)
    finally:
        _end([sweep])
    assert sweep.returncode == 130 and "error: interrupted" in stderr, stderr[-2000:]
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr
    first = {r["key"]: r["finished_at"] for r in _rows(out)}
    assert 2 <= len(first) < 24
    resumed = _sweep(out, "--workers", "1", "--resume")
    _, stderr = resumed.communicate(timeout=SWEEP_TIMEOUT_S)
    assert resumed.returncode == 0, stderr[-2000:]
    assert f"{len(first)} already in" in stderr
    rows = _rows(out)
    assert sorted(r["key"] for r in rows) == sorted(_expected_keys())
    assert all(r["finished_at"] == first[r["key"]] for r in rows if r["key"] in first)  # the finished rows were kept


def test_task_that_kills_its_worker_is_a_row_with_its_error(tmp_path):
    """Through the engine with a LocalCluster (nannies restart a dead worker): the task that SIGKILLs its
    process every time is an error row naming KilledWorker; the others are rows as usual."""
    import dask

    from quadruped_dyn.sweep import engine
    from quadruped_dyn.sweep.rows import base_row

    tasks = sorted(sweep_tasks(read_spec(TINY), sweep_robots(read_spec(TINY))), key=lambda t: t.key)[:4]
    doomed = tasks[1].key

    def execute(task):  # defined here: cloudpickle sends it by value
        if task.key == doomed:
            os.kill(os.getpid(), signal.SIGKILL)
        return {**base_row(task), "status": "ok", "passed": True, "error": None}

    dataset = Dataset(tmp_path)
    dataset.prepare()
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        cluster = engine.connect(None, 1)
        try:
            counts = engine.run(cluster, tasks, dataset, execute=execute)
        finally:
            cluster.close()
    rows = {r["key"]: r for r in dataset.rows()}
    assert set(rows) == {t.key for t in tasks} and counts.done == 4 and counts.failed == 1
    assert rows[doomed]["status"] == "error" and "KilledWorker" in rows[doomed]["error"]
    assert all(r["status"] == "ok" for k, r in rows.items() if k != doomed)


@pytest.fixture(autouse=True)
def _single_threaded(monkeypatch):
    for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        monkeypatch.setenv(k, "1")
