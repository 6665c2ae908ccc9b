"""``check``: every term against Pinocchio (and, with --against, other libraries)."""

from __future__ import annotations

import json
import sys

import click

from quadruped_dyn.checks.sample_counts import MAX_SAMPLES
from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, foot_frames_option, progress


@click.command()
@click.argument("robot")
@click.option("--samples", default=20, show_default=True, type=click.IntRange(min=1, max=MAX_SAMPLES),
              help=f"Random states, 1 to {MAX_SAMPLES:,} (~15 per second once the models are built).")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(min=0), help="Random seed.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--against", default=None, metavar="LIBS",
              help="Also compare M, C + G, G, inverse dynamics, foot positions and Jacobians with other libraries, after "
                   "diagnosing what each does to the URDF: all, or a comma-separated subset of "
                   "pinocchio,mujoco,idyntree,drake,adam (pip install 'quadruped_dyn[xlib]'). With --json: a "
                   "'conformance' table, the worst error per library and term and why it differs.")
@foot_frames_option
def check(robot: str, samples: int, seed: int, as_json: bool, against: str | None, foot_frames: str | None) -> None:
    """Check every symbolic term of ROBOT against Pinocchio on random states (exit 1 on failure)."""
    from quadruped_dyn.checks.terms import run_check
    from quadruped_dyn.files.json import json_safe
    from quadruped_dyn.model.robot import load_robot

    libraries: tuple[str, ...] = ()
    if against is not None:
        from quadruped_dyn.checks.cross_library import parse_libraries

        libraries = parse_libraries(against)
    r = load_robot(robot, foot_frames=foot_frames)
    with progress(f"checking {r.name}", samples) as bar:
        report = run_check(r, samples, seed, progress=lambda n: bar.update(1))
    data, text, passed = report.as_dict(), report.table(), report.passed
    if libraries:
        from quadruped_dyn.checks.cross_library import run_cross_library

        cross = run_cross_library(r, libraries, samples, seed)
        passed = passed and cross.passed
        data, text = {**data, **cross.as_dict(), "passed": passed}, f"{text}\n\n{cross.table()}"
    echo(json.dumps(json_safe(data), indent=2, allow_nan=False) if as_json else text)
    sys.exit(0 if passed else EXIT_CHECK_FAILED)
