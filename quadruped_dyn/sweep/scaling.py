"""How a sweep scales with workers on this machine: the same sweep file run by ``quadruped-dyn sweep`` on a
LocalCluster of each number of workers (one thread each, BLAS and OpenMP threads 1), one after the other, each into
its own folder; per run the wall time, the tasks' CPU and wall time (the cores the tasks obtained; the run's time
outside them: the cluster's start, the last tasks' tail), and the machine's load while it ran (the 1-minute load
average sampled every LOAD_PERIOD_S, and the fraction of all cores busy from /proc/stat: on a shared machine they
say how much the ratio means). A benchmark, not a test::

    python -m quadruped_dyn.sweep.scaling sweeps/scaling.toml --workers 1 2 --out results/scaling

Writes OUT/scaling.json and prints one line per run. Before the runs each robot's generated C is built into the
cache (``GeneratedC``), so no run pays for it.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from quadruped_dyn.errors import InputError
from quadruped_dyn.sweep.dataset import Dataset
from quadruped_dyn.sweep.engine import SINGLE_THREAD_ENV

#: Load average samples are taken this often (s).
LOAD_PERIOD_S = 5.0


def cpu_model() -> str:
    """The CPU's model name (/proc/cpuinfo), or the platform's processor string."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def _cpu_times() -> tuple[float, float] | None:
    """(busy, total) jiffies of all cores since boot (/proc/stat), or None where there is none."""
    try:
        fields = [float(x) for x in Path("/proc/stat").read_text().splitlines()[0].split()[1:]]
    except (OSError, ValueError, IndexError):
        return None
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0.0)  # idle + iowait
    return sum(fields) - idle, sum(fields)


def _one_run(sweep_file: Path, workers: int, out: Path) -> dict[str, Any]:
    """``quadruped-dyn sweep`` on ``workers`` workers into ``out``, with the machine's load while it ran."""
    loads: list[float] = []
    done = threading.Event()

    def sample() -> None:
        while not done.wait(LOAD_PERIOD_S):
            loads.append(os.getloadavg()[0])

    env = {**os.environ, **SINGLE_THREAD_ENV}
    command = [sys.executable, "-m", "quadruped_dyn.cli", "sweep", str(sweep_file), "--workers", str(workers),
               "--out", str(out), "--json"]
    before, start = _cpu_times(), time.monotonic()
    loads.append(os.getloadavg()[0])
    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    proc = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.monotonic() - start
    done.set()
    after = _cpu_times()
    busy = (after[0] - before[0]) / (after[1] - before[1]) if before and after and after[1] > before[1] else None
    try:
        summary = json.loads(proc.stdout)
    except json.JSONDecodeError:
        raise InputError(f"the sweep on {workers} workers exited {proc.returncode}: "
                         f"{(proc.stderr.strip().splitlines() or ['no output'])[-1]}") from None
    kinds = summary["kinds"]
    task_wall = sum(float(r["wall_s"]) for r in Dataset(out).rows())
    return {"workers": workers, "exit_code": proc.returncode, "wall_s": wall, "tasks": summary["this_run"]["tasks"],
            "errors": sum(k["errors"] for k in kinds.values()),
            "task_cpu_s_total": sum(k["cpu_s_total"] or 0.0 for k in kinds.values()), "task_wall_s_total": task_wall,
            # the run's wall time not spent in tasks with every worker busy: starting the cluster, the tail, scheduling
            "overhead_s": wall - task_wall / workers,
            # the cores the sweep's tasks had on average: what the machine gave it (at most ``workers``)
            "cores_obtained": sum(k["cpu_s_total"] or 0.0 for k in kinds.values()) / wall,
            "load_average_1min": {"start": loads[0], "max": max(loads), "mean": sum(loads) / len(loads), "samples": loads},
            "machine_busy_fraction": busy}


def measure(sweep_file: Path, workers: list[int], out: Path) -> dict[str, Any]:
    """Each run of ``sweep_file`` (see the module docstring) and the wall-time speed-up of each against the first."""
    from quadruped_dyn.control.controllers import GeneratedC
    from quadruped_dyn.sweep.robots import materialise, sweep_robots
    from quadruped_dyn.sweep.spec import read_spec

    spec = read_spec(sweep_file)
    if out.exists() and any(out.iterdir()):
        raise InputError(f"--out '{out}' is not empty; expected a new folder (each run writes a sweep into it)")
    for robot in sweep_robots(spec):
        GeneratedC(materialise(robot))  # type: ignore[arg-type]  # a Robot
    runs = [_one_run(sweep_file, n, out / f"workers-{n}") for n in workers]
    for r in runs:
        r["speedup_vs_first"] = runs[0]["wall_s"] / r["wall_s"]
    return {"sweep": spec.name, "cpu": cpu_model(), "cores": os.cpu_count(), "threads_per_worker": 1,
            "thread_env": SINGLE_THREAD_ENV, "runs": runs}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m quadruped_dyn.sweep.scaling", description=__doc__.split("\n\n")[0])
    parser.add_argument("sweep_file", type=Path, metavar="SWEEP.toml")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts, in order [1 2]")
    parser.add_argument("--out", type=Path, default=Path("results/sweep-scaling"))
    args = parser.parse_args(argv)
    try:
        if not args.workers or min(args.workers) < 1:
            raise InputError(f"--workers {args.workers}; expected whole numbers >= 1")
        result = measure(args.sweep_file, args.workers, args.out)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scaling.json").write_text(json.dumps(result, indent=1))
    for r in result["runs"]:
        load = r["load_average_1min"]
        busy = "n/a" if r["machine_busy_fraction"] is None else f"{r['machine_busy_fraction']:.0%}"
        print(f"{r['workers']} workers: {r['tasks']} tasks in {r['wall_s']:.1f} s wall (x{r['speedup_vs_first']:.2f}), "
              f"{r['task_cpu_s_total']:.1f} s task CPU ({r['cores_obtained']:.2f} cores), {r['overhead_s']:.1f} s outside "
              f"tasks, {r['errors']} errors; "
              f"load average {load['start']:.1f} at start, mean {load['mean']:.1f}, max {load['max']:.1f}; "
              f"machine busy {busy} ({result['cpu']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
