"""``sweep``: a sweep file's tasks over many robots on Dask distributed, each result a Parquet row (docs/sweeps.md)."""

from __future__ import annotations

import importlib.util
import json
import os
import sys
import time
from pathlib import Path

import click

from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, progress
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable

SWEEP_EXTRA = ("distributed", "pyarrow", "pandas")


@click.command()
@click.argument("sweep_file", metavar="SWEEP.toml")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="An existing Dask cluster's scheduler, tcp://HOST:PORT [default: a LocalCluster on this machine].")
@click.option("--workers", default=None, type=click.IntRange(1, 4096),
              help="Worker processes of the LocalCluster, one thread each [default: this machine's cores].")
@click.option("--out", "out_dir", default=None, metavar="DIR",
              help="The dataset (DIR/rows/*.parquet) and its summary [default: results/sweep-<name>].")
@click.option("--resume", is_flag=True, help="Continue the sweep in --out: skip every task whose row is there.")
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
def sweep(sweep_file: str, scheduler: str | None, workers: int | None, out_dir: str | None, resume: bool,
          as_json: bool) -> None:
    """Run SWEEP.toml's tasks (check, codegen, validate, control) over its robots on Dask: one Parquet row per
    finished task under --out, then OUT/summary.html and OUT/summary.json (exit 1 if a task failed or a check did)."""
    missing = [m for m in SWEEP_EXTRA if importlib.util.find_spec(m) is None]
    if missing:
        raise InputError(f"{', '.join(missing)} not installed; expected the sweep extra (pip install 'quadruped_dyn[sweep]')")
    from quadruped_dyn.files.names import safe_name
    from quadruped_dyn.files.paths import writable_dir
    from quadruped_dyn.files.safe_write import write_text
    from quadruped_dyn.sweep.dataset import Dataset
    from quadruped_dyn.sweep.engine import check_address, connect, run
    from quadruped_dyn.sweep.page import page
    from quadruped_dyn.sweep.robots import sweep_robots
    from quadruped_dyn.sweep.spec import read_spec
    from quadruped_dyn.sweep.summary import summarise
    from quadruped_dyn.sweep.tasks import sweep_tasks

    if scheduler is not None:
        check_address(scheduler)  # an unreachable scheduler: exit 2 in seconds
        if workers is not None:
            raise InputError("--workers is for the LocalCluster; expected no --workers with --scheduler "
                             "(the cluster has its own)")
    spec = read_spec(sweep_file)
    out_text = out_dir if out_dir is not None else str(Path("results") / f"sweep-{safe_name(spec.name)}")
    out = writable_dir(out_text, f"--out '{out_text}'")
    dataset = Dataset(out)
    present = dataset.keys()
    if present and not resume:
        raise InputError(f"--out '{printable(out)}' holds {len(present)} rows of a sweep; expected --resume to continue "
                         "it, or another --out")
    tasks = sweep_tasks(spec, sweep_robots(spec))
    todo = [t for t in tasks if t.key not in present]
    dataset.prepare()
    click.echo(f"{spec.name}: {len(tasks)} tasks, {len(tasks) - len(todo)} already in {printable(out)}, "
               f"{len(todo)} to run", err=True)
    lost, ran, start = 0, {"tasks": len(todo), "workers": 0, "wall_s": 0.0, "load_average": os.getloadavg()[0]}, time.monotonic()
    if todo:
        cluster = connect(scheduler, workers)
        try:
            ran["workers"] = len(cluster.client.scheduler_info()["workers"])
            if cluster.dashboard:
                click.echo(f"Dask dashboard: {cluster.dashboard}", err=True)
            with progress(f"sweep {spec.name}", len(todo)) as bar:
                def show(done: int, status: str) -> None:
                    bar.set_status(status)
                    bar.update(done - bar.done)

                lost = run(cluster, todo, dataset, show).lost
            ran["wall_s"] = time.monotonic() - start
        finally:
            cluster.close()
    keys = {t.key for t in tasks}
    frame = dataset.frame()
    frame = frame[frame["key"].isin(keys)] if len(frame) else frame
    # this invocation: its tasks, workers, wall time and the machine's load average (1 min) when it started
    summary = {"sweep": spec.name, "out": str(out), "lost": lost, "this_run": ran, **summarise(frame)}
    write_text(out / "summary.json", json.dumps(summary, indent=1, allow_nan=False))
    write_text(out / "summary.html", page(spec.name, summary))
    _report(summary, as_json, out)
    bad = lost or any(k["errors"] or k["failed_checks"] for k in summary["kinds"].values())
    sys.exit(EXIT_CHECK_FAILED if bad else 0)


def _report(summary: dict, as_json: bool, out: Path) -> None:
    if as_json:
        echo(json.dumps(summary, indent=1, allow_nan=False))
        return
    for kind, k in summary["kinds"].items():
        echo(f"{kind}: {k['tasks']} tasks, {k['errors']} errors, {k['failed_checks']} failed checks, "
             f"median {k['wall_s_median'] or 0:.2f} s wall, {k['cpu_s_median'] or 0:.2f} s CPU")
    for g in summary.get("control", {}).get("controllers", []):
        echo(f"  {g['robot']} {g['gait']} {g['controller']}: {g['falls']}/{g['runs']} fell "
             f"(95 % {g['ci95'][0]:.2f}-{g['ci95'][1]:.2f})")
    for e in summary.get("errors", [])[:10]:
        echo(f"  error: {e['kind']} {e['robot']} {e['key']}: {e['error']}")
    if summary["lost"]:
        echo(f"{summary['lost']} tasks lost with the scheduler: run again with --resume")
    echo(f"wrote {printable(out / 'summary.html')}, {printable(out / 'summary.json')}, {printable(out / 'rows')}")
