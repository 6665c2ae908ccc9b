"""Running a sweep's tasks on Dask distributed: a ``LocalCluster`` on this machine (worker processes,
one thread each, bound to 127.0.0.1), or an existing cluster (``--scheduler tcp://HOST:8786``: workers
started with ``dask worker`` in the same environment).

Each task is submitted under its content key; its row is written (``dataset``) here, by the client, as
soon as it finishes. A worker that dies takes its running task with it: the scheduler reruns it on
another worker (``distributed.scheduler.allowed-failures`` times), so a task appears once; one that
kills every worker it runs on is a row with that error. A task whose future is lost (the scheduler went
away) writes no row: ``--resume`` runs it again.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.interrupts import interrupts_deferred
from quadruped_dyn.sweep.dataset import Dataset
from quadruped_dyn.sweep.rows import error_row, one_line
from quadruped_dyn.sweep.tasks import Task

#: How long to wait for a scheduler to answer (s).
CONNECT_TIMEOUT_S = 5.0
#: Progress is refreshed at least this often (s).
PROGRESS_PERIOD_S = 1.0
#: One thread per worker process and in its numerical libraries: tasks are serial, parallelism is across workers.
SINGLE_THREAD_ENV = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
#: Tasks a worker holds per thread: one, the one it runs. Tasks last seconds to minutes, so nothing is gained by
#: queueing more on a worker, and a task queued on a worker that dies counts as having died with it (towards
#: ``distributed.scheduler.allowed-failures``). On a cluster it is the scheduler's setting (docs/sweeps.md).
WORKER_SATURATION = 1.0
_ADDRESS = re.compile(r"^(tcp|tls)://[^\s/:]+:\d{1,5}$")


@dataclass
class Cluster:
    client: Any
    local: Any  # the LocalCluster, or None on an existing cluster
    dashboard: str | None

    def close(self) -> None:
        try:
            self.client.close(timeout=10)
        finally:
            if self.local is not None:
                self.local.close(timeout=10)


def check_address(address: str) -> str:
    """``address`` if it is tcp://HOST:PORT (or tls://) and something accepts a connection there within
    CONNECT_TIMEOUT_S (a plain TCP probe: fast, before Dask is imported); InputError otherwise."""
    if not _ADDRESS.match(address):
        raise InputError(f"--scheduler '{printable(address)}' is not a scheduler address; expected tcp://HOST:PORT "
                         "(e.g. tcp://10.0.0.5:8786)")
    host, port = address.split("://", 1)[1].rsplit(":", 1)
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except (OSError, ValueError) as e:
        raise InputError(f"--scheduler {printable(address)}: no scheduler answered within {CONNECT_TIMEOUT_S:g} s "
                         f"({one_line(e)[:120]}); expected a running `dask scheduler` there") from e
    return address


def connect(scheduler: str | None, workers: int | None) -> Cluster:
    """A client of the cluster at ``scheduler``, or of a new LocalCluster of ``workers`` processes (default:
    this machine's cores). InputError if no scheduler answers within CONNECT_TIMEOUT_S."""
    for name, value in SINGLE_THREAD_ENV.items():  # inherited by the LocalCluster's processes
        os.environ.setdefault(name, value)
    from distributed import Client, LocalCluster

    for name in ("distributed", "tornado"):  # their warnings are multi-line logs; the sweep reports each task itself
        logging.getLogger(name).setLevel(logging.ERROR)
    if scheduler is not None:
        address = check_address(scheduler)
        try:
            client = Client(address, timeout=f"{CONNECT_TIMEOUT_S}s")
        except (OSError, TimeoutError) as e:
            raise InputError(f"--scheduler {printable(address)}: no scheduler answered within {CONNECT_TIMEOUT_S:g} s "
                             f"({one_line(e)[:120]}); expected a running `dask scheduler` there") from e
        return Cluster(client, None, client.dashboard_link if _has_dashboard(client) else None)
    import dask

    # SIGINT ignored: inherited by the worker processes (a terminal's Ctrl-C reaches the whole process group, and a
    # worker's KeyboardInterrupt is a traceback; the client ends them when it stops). WORKER_SATURATION: see there.
    with _sigint_ignored(), dask.config.set({"distributed.scheduler.worker-saturation": WORKER_SATURATION}):
        local = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                             host="127.0.0.1", dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR)
    client = Client(local)
    return Cluster(client, local, client.dashboard_link if _has_dashboard(client) else None)


@contextmanager
def _sigint_ignored() -> Iterator[None]:
    """SIGINT ignored in the block (processes started in it keep ignoring it), in the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _has_dashboard(client: Any) -> bool:
    try:
        return "dashboard" in client.scheduler_info().get("services", {})
    except Exception:  # an older scheduler: no link rather than no sweep
        return False


@dataclass
class Counts:
    total: int
    done: int = 0
    failed: int = 0
    lost: int = 0
    running: int = 0

    def status(self, started: float) -> str:
        elapsed = max(time.monotonic() - started, 1e-9)
        rate = self.done / elapsed
        left = self.total - self.done - self.lost
        eta = f"{left / rate:.0f} s" if rate > 0 else "?"
        return f"{self.failed} failed, {self.running} running, {rate * 60:.1f} tasks/min, ETA {eta}"


def _row_of(future: Any, task: Task) -> dict[str, Any] | str:
    """The finished future's row; an error row for a task that killed its workers; "lost" for a future the
    scheduler cancelled (it went away), "again" for one that is not finished after all (its worker died
    as it was reported: the scheduler reruns it)."""
    from distributed import KilledWorker

    if future.status == "finished":
        return future.result()
    if future.status == "cancelled":
        return "lost"
    exc = future.exception() if future.status == "error" else None
    if exc is None:
        return "again"
    if isinstance(exc, KilledWorker):
        return error_row(task, f"KilledWorker: the task's worker process died every time it ran it ({exc}); "
                               "a crash in native code, memory exhausted, or a signal")
    return error_row(task, one_line(exc))


def _running(client: Any) -> int:
    """Tasks running now: those assigned to each worker, at most its threads (a worker also holds queued ones)."""
    try:
        threads = {w: info.get("nthreads", 1) for w, info in client.scheduler_info()["workers"].items()}
        return sum(min(len(keys), threads.get(w, 1)) for w, keys in client.processing().items())
    except Exception:  # a scheduler that went away: its futures are cancelled, counted as lost
        return 0


def run(cluster: Cluster, tasks: list[Task], dataset: Dataset, progress: Callable[[int, str], None] | None = None,
        execute: Callable[[Task], dict[str, Any]] | None = None) -> Counts:
    """Run ``tasks`` (none of whose keys the dataset holds), writing each row as it finishes;
    ``progress(done, status)`` about every PROGRESS_PERIOD_S. ``execute`` replaces ``rows.execute`` (tests)."""
    from distributed import wait

    from quadruped_dyn.sweep.rows import execute as default_execute

    client = cluster.client
    by_key = {t.key: t for t in tasks}
    pending = {client.submit(execute or default_execute, t, key=t.key, pure=False) for t in tasks}
    counts, started = Counts(len(tasks)), time.monotonic()
    while pending:
        try:
            finished, pending = wait(pending, timeout=PROGRESS_PERIOD_S, return_when="FIRST_COMPLETED")
        except TimeoutError:
            finished = set()
        for future in finished:
            row = _row_of(future, by_key[future.key])
            if row == "again":
                pending.add(future)
                continue
            if isinstance(row, str):
                counts.lost += 1
                continue
            with interrupts_deferred():  # a row is written whole (the rename is atomic anyway) and counted
                dataset.write(row)
                counts.done += 1
                counts.failed += row["status"] != "ok"
            future.release()
        counts.running = _running(client)
        if progress:
            progress(counts.done, counts.status(started))
    return counts
