"""``bench``: the generated C timed against Pinocchio and peers in the same run."""

from __future__ import annotations

import json

import click

from quadruped_dyn.cli.app import require_tools
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.model.robot import load_robot


@click.command()
@click.option("--robot", "robots", multiple=True, default=["paper"], show_default=True, help="Robot (repeatable).")
@click.option("--calls", default=20000, show_default=True, type=click.IntRange(min=1), help="Calls per timing run.")
@click.option("--reps", default=9, show_default=True, type=click.IntRange(min=1), help="Timing runs (median).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--peers", default="", help="Also time other libraries' generated dynamics against the toolkit's, "
              "same run, same flags (comma-separated): adam.")
@click.option("--march-native", "native", is_flag=True, help="Build the --peers comparison (both sides) with -march=native.")
def bench(robots: tuple[str, ...], calls: int, reps: int, as_json: bool, peers: str, native: bool) -> None:
    """Time the generated C against Pinocchio's native C++ in the same run (ratios < 1: generated is faster)."""
    from dataclasses import asdict

    from quadruped_dyn.bench.peers import parse_peers, peers_table, run_peers
    from quadruped_dyn.bench.timing import run_bench
    from quadruped_dyn.codegen.cache import cache_dir

    peer_names = parse_peers(peers)
    require_tools("gcc", "g++")
    writable_dir(cache_dir(), f"the cache directory '{cache_dir()}' (QUADRUPED_DYN_CACHE)")
    loaded = [load_robot(r) for r in robots]  # every argument checked before minutes of work
    reports = [run_bench(r, calls, reps) for r in loaded]
    entries = [e for r in loaded for e in run_peers(r, peer_names, native, calls, reps)] if peer_names else []
    if as_json:
        out: object = [r.as_dict() for r in reports]
        click.echo(json.dumps({"bench": out, "peers": [asdict(e) for e in entries]} if peer_names else out, indent=2))
    else:
        click.echo("\n\n".join([r.table() for r in reports] + ([peers_table(entries, native)] if entries else [])))
