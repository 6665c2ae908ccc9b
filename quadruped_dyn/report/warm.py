"""Work ahead, in a second process, for the report's later steps: compiling, then the notebooks.

The report's long steps are single-threaded Python (the term check, the experiment, the optimal
control, the closed loop); its compilers (the robot's library, the experiment's native driver,
the Cortex-M footprint builds, the Pinocchio benchmark harness) would otherwise run only when
their step comes. ``start`` runs them at once in a spawned process, on the machine's other core,
and then executes the notebooks there, one task each (each notebook's kernel is a process of its
own: nothing of the report's process is shared), whose pages the notebooks step collects.

Nothing is handed over between the processes: every artefact goes through the verified build
cache (``files/cache.py``), whose per-entry lock makes a step that needs an artefact still
being built wait for it instead of building it again, and which verifies each artefact's hash
before use. A warm build that fails is only a lost head start: the step builds it again itself
and reports the failure in its section.
"""

from __future__ import annotations

import multiprocessing
import tempfile
from collections.abc import Sequence
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path
from typing import Any

from quadruped_dyn.interrupts import interrupts_deferred


def warm_caches(urdf: str, with_benchmark: bool, with_footprint: bool = False,
                foot_frames: tuple[str, ...] | None = None) -> str:
    """Build every cached artefact of the report for the robot at ``urdf`` on ``foot_frames`` (``load_robot``'s), in
    the order the steps need them (the Cortex-M builds only ``with_footprint``); "" on success, else the first
    error (one line)."""
    try:
        from quadruped_dyn.codegen.library import compiled_library
        from quadruped_dyn.experiment.native_run import native_library
        from quadruped_dyn.model.robot import load_robot

        robot = load_robot(urdf, foot_frames=foot_frames)
        compiled_library(robot)  # the reduced-model step, the experiment, the generated-C step
        native_library(robot)  # the experiment's native driver
        if with_benchmark:
            from quadruped_dyn.bench.timing import pinocchio_harness

            with ThreadPoolExecutor(max_workers=1) as beside:  # one C++ compiler beside the Cortex-M builds' make -j2
                harness = beside.submit(pinocchio_harness)
                if with_footprint:
                    from quadruped_dyn.report.gather import embedded_footprint, generate_c_directory

                    with tempfile.TemporaryDirectory() as tmp:  # the report's own c/ has the same bytes: the same key
                        generate_c_directory(robot, Path(tmp))
                        embedded_footprint(robot, Path(tmp))  # the Cortex-M builds, cached by content
                harness.result()
        return ""
    except Exception as e:  # noqa: BLE001 -- reported by the step that needs the artefact
        return f"{type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else ''}"


def start(urdf: Path, with_benchmark: bool, notebooks: Sequence[Path] = (), with_footprint: bool = False,
          foot_frames: tuple[str, ...] | None = None) -> tuple[ProcessPoolExecutor, Future[str], list[Future[dict[str, Any]]]]:
    """The warm process, started (spawned: no state of this process is shared): ``warm_caches`` (of the robot on
    ``foot_frames``, the report's: the caches key on them),
    then each of ``notebooks`` executed and rendered (``gather.executed_notebook``), in that order.
    Shut it down with ``stop`` when the report is written, so no process outlives the command; interrupted while it
    starts, it is stopped here (after the spawn: a worker cut mid-spawn printed a traceback)."""
    from quadruped_dyn.report.gather import executed_notebook

    pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"), initializer=_quiet)
    try:
        with interrupts_deferred():  # the first submit spawns the worker: cut there, it read a closed pipe (traceback)
            warmed = pool.submit(warm_caches, str(urdf), with_benchmark, with_footprint, foot_frames)
            ahead = [pool.submit(executed_notebook, path) for path in notebooks]
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM while it started: the caller has no pool to stop
        stop(pool, now=True)
        raise
    return pool, warmed, ahead


def _quiet() -> None:
    """The warm process's stderr is /dev/null: its errors come back through the futures, one line each; what it
    would print (nbclient's traceback when ``stop(now=True)`` ends it during a kernel's start, the URDF's warnings
    again) would land under the report's own lines."""
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    os.close(devnull)  # sys.stderr writes to fd 2: now /dev/null too


def stop(pool: ProcessPoolExecutor, now: bool = False) -> None:
    """Shut the warm process down and wait for it to end; ``now`` (the report interrupted): end it at once
    (SIGTERM) instead of waiting for its work in hand (a compile, the benchmark: minutes); a second interrupt
    meanwhile takes effect once it has ended."""
    if not now:
        pool.shutdown(wait=True, cancel_futures=True)
        return
    with interrupts_deferred():  # a second Ctrl-C or SIGTERM here left the pool running: the exit hung on it
        workers = getattr(pool, "_processes", None) or {}  # CPython's; Python 3.14 has pool.terminate_workers()
        for process in list(workers.values()):
            process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
