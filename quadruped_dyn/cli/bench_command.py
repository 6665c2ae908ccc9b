"""``bench``: the generated C timed against Pinocchio and peers in the same run."""

from __future__ import annotations

import json

import click

from quadruped_dyn.bench.timing_counts import MAX_CALLS, MAX_REPS
from quadruped_dyn.cli.app import echo, require_tools


@click.command()
@click.option("--robot", "robots", multiple=True, default=["paper"], show_default=True, help="Robot (repeatable).")
@click.option("--calls", default=20000, show_default=True, type=click.IntRange(1, MAX_CALLS), help="Calls per timing run.")
@click.option("--reps", default=9, show_default=True, type=click.IntRange(1, MAX_REPS), help="Timing runs (median).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
@click.option("--peers", default="auto", show_default=True,
              help="Other generated dynamics timed against the toolkit's, same run, same flags (comma-separated): "
              "pinocchio-cppadcodegen (Pinocchio's CppADCodeGen code; the 'bench' extra), adam; none; auto: "
              "pinocchio-cppadcodegen when its headers are installed.")
@click.option("--native", "--march-native", "native", is_flag=True,
              help="Build the generated C and the peers with -march=native (Pinocchio native stays the pin wheel's build).")
@click.option("--call-cost/--no-call-cost", default=True, show_default=True,
              help="Also count each function's instructions, I1 misses and bytes of code per call under valgrind "
              "(callgrind; the same on any machine), beside the graphs' operation counts.")
@click.option("--parametric", is_flag=True,
              help="Also time the robot family's parametric library (p as an input; built once per family into the "
              "cache, about a minute) against the fixed library and Pinocchio.")
def bench(robots: tuple[str, ...], calls: int, reps: int, as_json: bool, peers: str, native: bool,
          call_cost: bool, parametric: bool) -> None:
    """Time the generated C against Pinocchio's native C++ in the same run (ratios < 1: generated is faster)."""
    from dataclasses import asdict

    from quadruped_dyn.bench import cppadcg
    from quadruped_dyn.bench.peers import parse_peers, peers_table, run_peers
    from quadruped_dyn.bench.timing import run_bench
    from quadruped_dyn.files.cache import writable_cache
    from quadruped_dyn.model.robot import load_robot

    auto = peers.strip() == "auto"
    peer_names: tuple[str, ...] = ((cppadcg.PEER,) if cppadcg.available() else ()) if auto else parse_peers(peers)
    require_tools("gcc", "g++")
    writable_cache()
    loaded = [load_robot(r) for r in robots]  # every argument checked before minutes of work
    if auto and not peer_names:  # after the checks: bad input stays one line
        click.echo(f"note: {cppadcg.PEER} is not timed: its headers are not installed ({cppadcg.INSTALL_HINT})", err=True)
    reports = [run_bench(r, calls, reps, native=native, peer=cppadcg.PEER in peer_names, call_cost=call_cost,
                         parametric=parametric)
               for r in loaded]
    adam = [e for r in loaded for e in run_peers(r, native, calls, reps)] if "adam" in peer_names else []
    if as_json:
        out: object = [r.as_dict() for r in reports]
        echo(json.dumps({"bench": out, "peers": [asdict(e) for e in adam]} if adam else out, indent=2))
    else:
        echo("\n\n".join([r.table() for r in reports] + ([peers_table(adam, native)] if adam else [])))
