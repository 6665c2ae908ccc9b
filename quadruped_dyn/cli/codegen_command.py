"""``codegen``: standalone C with a Makefile and a check program."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import click

from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, foot_frames_option
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.files.provenance import check_source, record_source
from quadruped_dyn.files.safe_write import output_set, replaceable

if TYPE_CHECKING:
    from pathlib import Path

    from quadruped_dyn.model.robot import Robot


@click.command()
@click.argument("robot")
@click.option("--out", "out_dir", required=True, type=click.Path(), help="Output directory.")
@click.option("--precision", type=click.Choice(["double", "float"]), default="double", show_default=True,
              help="Default casadi_real of the generated source (the Makefile builds both).")
@click.option("--check", is_flag=True, help="Compare OUT with a fresh generation instead of writing (exit 1 if it differs).")
@click.option("--json", "as_json", is_flag=True,
              help="Print a JSON summary instead of the file list: every function's caller memory, and its code size "
                   "and worst-case stack on Cortex-M7 and Cortex-M4F at -Os and -O2 (cross builds: minutes, "
                   "cached; docs/embedded.md).")
@click.option("--parametric", is_flag=True,
              help="Write the parametric C of ROBOT's family instead: qdp_<family>.c/.h, the full terms and the "
                   "regressor with the robot's parameters p as the last input, p's layout in the header; with check_qd.c, "
                   "a Makefile and Pinocchio's values at ROBOT's p for `make check`.")
@foot_frames_option
def codegen(robot: str, out_dir: str, precision: str, check: bool, as_json: bool, parametric: bool,
            foot_frames: str | None) -> None:
    """Generate standalone C for ROBOT: M, C, G, id, the GRF solves, the reduced model of every stance set
    and the derivatives, with a Makefile and a check program."""
    from pathlib import Path

    from quadruped_dyn.checks.check_program_values import checked_files, compare_generation, generate_checked
    from quadruped_dyn.model.robot import load_robot

    if parametric and (check or as_json):
        raise InputError("--parametric with --check or --json; expected --parametric alone (it writes the C and a check package)")
    r = load_robot(robot, foot_frames=foot_frames)
    if parametric:
        _write_parametric(r, writable_dir(out_dir, f"--out '{out_dir}'"), precision)
        return
    if check:
        if not Path(out_dir).is_dir():
            raise InputError(f"--out '{printable(out_dir)}' is not a directory; expected the directory to compare (--check)")
        diff = compare_generation(r, Path(out_dir), precision)  # the precision asked for, not always double
        echo(f"{out_dir} ({precision}): {diff.summary()}")
        sys.exit(EXIT_CHECK_FAILED if diff else 0)
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    check_source(out, r)  # another URDF's C of the same name is never overwritten
    replaceable(checked_files(r, out).all())  # a directory in the way is refused now, not after the generation
    with output_set():  # the URDF they came from (no record for a built-in robot), with them
        paths = generate_checked(r, out, precision).all()
        paths += filter(None, [record_source(out, r)])
    if as_json:
        import json

        from quadruped_dyn.checks.embedded import embedded_summary

        echo(json.dumps(embedded_summary(r, Path(out_dir)), indent=1))
        return
    for path in paths:
        echo(f"wrote {path}")


def _write_parametric(robot: Robot, out: Path, precision: str) -> None:
    """qdp_<family>.c and .h of the robot's family into ``out``, with its check package at the robot's p
    (``checks.parametric_check``: the reference header, check_qd.c, the Makefile of ``make check``)."""
    from quadruped_dyn.checks.parametric_check import parametric_package
    from quadruped_dyn.files.safe_write import write_text

    for name, text in parametric_package(robot, precision).items():
        echo(f"wrote {write_text(out / name, text)}")
