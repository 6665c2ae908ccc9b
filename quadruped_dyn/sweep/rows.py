"""A task's row: what runs on a worker (``execute``: never raises for the task's own failure) and the
row of a task that killed its worker (``error_row``). Columns: the task's key and content, ``status``
("ok" or "error"), ``passed`` (a check's verdict, else null), ``error`` (one line), wall and CPU
time (s), the worker's host and process, library versions, ``metrics`` (JSON), and the scalars of
the options (``o.<name>``), of a control run's perturbation sample (``p.<name>``) and of the
metrics (``m.<name>``) as their own columns."""

from __future__ import annotations

import importlib.metadata
import json
import os
import socket
import time
from functools import cache
from typing import Any

from quadruped_dyn.files.json import json_safe
from quadruped_dyn.sweep.tasks import Task, compute

#: Packages whose versions each row records.
VERSIONED = ("quadruped_dyn", "pin", "casadi", "numpy", "mujoco", "idyntree", "distributed")
#: An error message is cut to this many characters in its row.
MAX_ERROR_CHARS = 500


@cache
def versions() -> str:
    out: dict[str, str | None] = {}
    for name in VERSIONED:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = None
    return json.dumps(out, sort_keys=True)


def _scalars(prefix: str, data: dict[str, Any]) -> dict[str, Any]:
    return {f"{prefix}.{k}": v for k, v in data.items() if isinstance(v, str | int | float | bool)}


def base_row(task: Task) -> dict[str, Any]:
    """The columns known before the task runs."""
    return {"key": task.key, "kind": task.kind, "robot": task.robot.label, "robot_sha256": task.robot.sha256,
            "scales": json.dumps(task.robot.scales), "options": json.dumps(task.options, sort_keys=True),
            **_scalars("o", task.options), **_scalars("p", task.options.get("perturbation", {}))}


def one_line(e: BaseException) -> str:
    text = " ".join(f"{type(e).__name__}: {e}".split())
    return text[:MAX_ERROR_CHARS]


def _cpu_s() -> float:
    """CPU time of this process and of its finished children (the compiler and the check program of ``codegen``), s."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def execute(task: Task) -> dict[str, Any]:
    """Run ``task`` here and return its row; an exception of the task is the row's error. CPU time: this worker
    process's (one thread) and its children's over the task."""
    wall, cpu = time.perf_counter(), _cpu_s()
    try:
        metrics: dict[str, Any] = json_safe(compute(task))
        status, error = "ok", None
    except Exception as e:  # the task's failure is its row, never the sweep's end
        metrics, status, error = {}, "error", one_line(e)
    return {**base_row(task), "status": status, "passed": metrics.get("passed") if status == "ok" else False,
            "error": error, "wall_s": time.perf_counter() - wall, "cpu_s": _cpu_s() - cpu,
            "host": socket.gethostname(), "pid": os.getpid(), "versions": versions(),
            "metrics": json.dumps(metrics, allow_nan=False), **_scalars("m", metrics), "finished_at": time.time()}


def error_row(task: Task, error: str) -> dict[str, Any]:
    """The row of a task that did not return: it killed its worker (every time it was tried), or was lost."""
    return {**base_row(task), "status": "error", "passed": False, "error": error[:MAX_ERROR_CHARS], "wall_s": None,
            "cpu_s": None, "host": None, "pid": None, "versions": versions(), "metrics": "{}", "finished_at": time.time()}
