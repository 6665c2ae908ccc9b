"""``report``: one self-contained HTML page of everything."""

from __future__ import annotations

import sys

import click

from quadruped_dyn.checks.sample_counts import CHECK_SAMPLES
from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, foot_frames_option


@click.command()
@click.argument("robot", default="paper")
@click.option("--out", "out_dir", default="results", show_default=True,
              help="The page goes to OUT/<robot>/report.html, its files beside it.")
@click.option("--fast", is_flag=True, help="Skip the benchmark (its first run compiles a C++ harness for minutes).")
@click.option("--samples", type=click.IntRange(min=1), default=CHECK_SAMPLES, show_default=True,
              help="Random states of the term check against Pinocchio (`check --samples` runs it alone).")
@click.option("--footprint", is_flag=True,
              help="Add the Cortex-M footprint (code size, stack): two cross builds, minutes on a cold cache.")
@foot_frames_option
def report(robot: str, out_dir: str, fast: bool, samples: int, footprint: bool, foot_frames: str | None) -> None:
    """One self-contained HTML page of everything the toolkit knows about ROBOT (a name or URDF path,
    default paper; exit 1 if a check fails)."""
    from quadruped_dyn.report.build import build_report, prepare

    prepare(robot, out_dir, samples)  # bad input is reported before any work
    result = build_report(robot, out_dir, fast, samples, footprint=footprint, foot_frames=foot_frames)
    echo(result.summary())
    sys.exit(0 if result.passed else EXIT_CHECK_FAILED)
