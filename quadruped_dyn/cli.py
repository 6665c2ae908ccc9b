"""The ``quadruped-dyn`` command line. Exit codes: 0 success, 1 a check failed, 2 bad input."""

from __future__ import annotations

import json
import math
import shutil
import sys
import warnings
from typing import Any

import click
import numpy as np

from .errors import BuildError, InputError, UrdfWarning
from .leg import JOINT_ROLES
from .paths import writable_dir
from .robot import ROBOT_NAMES, Robot, load_robot

EXIT_CHECK_FAILED = 1
EXIT_BAD_INPUT = 2


def _warn_one_line(message: Warning | str, category: type[Warning], *args: object, **kwargs: object) -> None:
    click.echo(f"warning: {message}", err=True)


class _Group(click.Group):
    """Maps InputError and click's usage errors to exit code 2 and BuildError to 1, with a one-line
    message and no traceback; prints UrdfWarnings as one line each."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("always", UrdfWarning)
                warnings.showwarning = _warn_one_line
                return super().invoke(ctx)
        except InputError as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except click.UsageError as e:
            click.echo(f"error: {e.format_message()}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except BuildError as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(EXIT_CHECK_FAILED)


class _FiniteFloat(click.FloatRange):
    """A FloatRange that also refuses NaN and inf (they compare False with every bound)."""

    name = "finite float"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


def _require_tools(*tools: str) -> None:
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        raise InputError(f"{', '.join(missing)} not found; expected on PATH (Debian: apt-get install gcc g++)")


class _ProgressLines:
    """Progress as one stderr line per ~10 % (click's bar draws nothing when stderr is not a terminal)."""

    def __init__(self, label: str, length: int) -> None:
        self.label, self.length, self.done = label, length, 0

    def __enter__(self) -> _ProgressLines:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def update(self, n: int) -> None:
        self.done += n
        if self.done % max(1, self.length // 10) == 0 or self.done == self.length:
            click.echo(f"{self.label}: {self.done}/{self.length}", err=True)


def _progress(label: str, length: int) -> Any:
    if sys.stderr.isatty():
        return click.progressbar(length=length, label=label, file=sys.stderr)
    return _ProgressLines(label, length)


@click.group(cls=_Group)
def main() -> None:
    """quadruped_dyn: the paper's quadruped Newton-Euler dynamics, checked against Pinocchio."""


@main.command()
def robots() -> None:
    """List the built-in robot names."""
    for name in ROBOT_NAMES:
        click.echo(name)


def robot_info(robot: Robot) -> dict[str, Any]:
    feet = [leg.foot_position(q) for leg, q in zip(robot.legs, robot.standing_q.reshape(4, 3))]
    return {
        "name": robot.name,
        "urdf": str(robot.urdf),
        "total_mass_kg": robot.total_mass,
        "trunk_mass_kg": robot.trunk.mass,
        "standing_q_rad": robot.standing_q.tolist(),
        "legs": [
            {
                "label": leg.label,
                "joints": [j.name for j in leg.joints],
                "foot_frame": leg.foot_frame,
                "hip_position_m": leg.hip.tolist(),
                "thigh_length_m": float(np.linalg.norm(leg.joints[2].placement.p)),
                "shank_length_m": float(np.linalg.norm(leg.foot.p)),
                "link_masses_kg": [link.mass for link in leg.links],
                "foot_position_standing_m": foot.tolist(),
            }
            for leg, foot in zip(robot.legs, feet)
        ],
    }


@main.command()
@click.argument("robot")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def info(robot: str, as_json: bool) -> None:
    """Legs, joints, link lengths, masses and standing foot positions of ROBOT (name or URDF path)."""
    data = robot_info(load_robot(robot))
    if as_json:
        click.echo(json.dumps(data, indent=2))
        return
    click.echo(f"{data['name']}  ({data['urdf']})")
    click.echo(f"total mass {data['total_mass_kg']:.3f} kg, trunk {data['trunk_mass_kg']:.3f} kg")
    click.echo(f"{'leg':<4}{'joints (HAA, HFE, KFE)':<48}{'thigh m':>8}{'shank m':>8}{'mass kg':>8}  foot at standing (b, m)")
    for leg in data["legs"]:
        foot = " ".join(f"{x:+.3f}" for x in leg["foot_position_standing_m"])
        click.echo(
            f"{leg['label']:<4}{', '.join(leg['joints']):<48}{leg['thigh_length_m']:>8.3f}"
            f"{leg['shank_length_m']:>8.3f}{sum(leg['link_masses_kg']):>8.3f}  {foot}"
        )


@main.command()
@click.argument("robot")
@click.option("--samples", default=20, show_default=True, type=click.IntRange(min=1), help="Random states.")
@click.option("--seed", default=0, show_default=True, type=click.IntRange(min=0), help="Random seed.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@click.option("--against", default=None, metavar="LIBS",
              help="Also compare M, C + G, G and foot Jacobians with other libraries, after diagnosing what each does "
                   "to the URDF: comma-separated subset of mujoco,idyntree (pip install 'quadruped_dyn[xlib]').")
def check(robot: str, samples: int, seed: int, as_json: bool, against: str | None) -> None:
    """Check every symbolic term of ROBOT against Pinocchio on random states (exit 1 on failure)."""
    from .check import json_safe, run_check

    libraries: tuple[str, ...] = ()
    if against is not None:
        from .cross_library import parse_libraries

        libraries = parse_libraries(against)
    r = load_robot(robot)
    with _progress(f"checking {r.name}", samples) as bar:
        report = run_check(r, samples, seed, progress=lambda n: bar.update(1))
    data, text, passed = report.as_dict(), report.table(), report.passed
    if libraries:
        from .cross_library import run_cross_library

        cross = run_cross_library(r, libraries, samples, seed)
        passed = passed and cross.passed
        data, text = {**data, **cross.as_dict(), "passed": passed}, f"{text}\n\n{cross.table()}"
    click.echo(json.dumps(json_safe(data), indent=2, allow_nan=False) if as_json else text)
    sys.exit(0 if passed else EXIT_CHECK_FAILED)


@main.command()
@click.argument("robot")
@click.option("--out", "out_dir", required=True, type=click.Path(), help="Output directory.")
@click.option("--precision", type=click.Choice(["double", "float"]), default="double", show_default=True,
              help="Default casadi_real of the generated source (the Makefile builds both).")
@click.option("--check", is_flag=True, help="Compare OUT with a fresh generation instead of writing (exit 1 if it differs).")
def codegen(robot: str, out_dir: str, precision: str, check: bool) -> None:
    """Generate standalone C for ROBOT's M, C, G, id and GRF solves, with a Makefile and a check program."""
    from pathlib import Path

    from .codegen import differing_files, generate

    r = load_robot(robot)
    if check:
        if not Path(out_dir).is_dir():
            raise InputError(f"--out '{out_dir}' is not a directory; expected the directory to compare (--check)")
        stale = differing_files(r, Path(out_dir))
        click.echo(f"{out_dir}: " + (f"differs from a fresh generation: {', '.join(stale)}" if stale else "up to date"))
        sys.exit(EXIT_CHECK_FAILED if stale else 0)
    for path in generate(r, writable_dir(out_dir, f"--out '{out_dir}'"), precision):
        click.echo(f"wrote {path}")


@main.command()
@click.option("--robot", "robots", multiple=True, default=["paper"], show_default=True, help="Robot (repeatable).")
@click.option("--calls", default=20000, show_default=True, type=click.IntRange(min=1), help="Calls per timing run.")
@click.option("--reps", default=9, show_default=True, type=click.IntRange(min=1), help="Timing runs (median).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def bench(robots: tuple[str, ...], calls: int, reps: int, as_json: bool) -> None:
    """Time the generated C against Pinocchio's native C++ in the same run (ratios < 1: generated is faster)."""
    from .bench import run_bench
    from .cache import cache_dir

    _require_tools("gcc", "g++")
    writable_dir(cache_dir(), f"the cache directory '{cache_dir()}' (QUADRUPED_DYN_CACHE)")
    loaded = [load_robot(r) for r in robots]  # every argument checked before minutes of work
    reports = [run_bench(r, calls, reps) for r in loaded]
    if as_json:
        click.echo(json.dumps([r.as_dict() for r in reports], indent=2))
    else:
        click.echo("\n\n".join(r.table() for r in reports))


@main.command()
@click.argument("robot", default="paper")
@click.option("--gait", "gait_name", type=click.Choice(["trot", "walk"]), default="trot", show_default=True,
              help="Trot (the paper's experiment) or static walk.")
@click.option("--horizon", default=None, type=_FiniteFloat(min=0.01, max=1e3),
              help="Seconds [default: two gait cycles].")
@click.option("--dt", default=5e-4, show_default=True, type=_FiniteFloat(min=1e-5, max=0.05), help="RK4 step, s.")
@click.option("--out", "out_dir", default="results", show_default=True, type=click.Path(),
              help="Directory for the plot and the JSON report.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
def validate(robot: str, gait_name: str, horizon: float | None, dt: float, out_dir: str, as_json: bool) -> None:
    """The paper's experiment: IK -> id_r -> forward dynamics -> compare with IK (plot + report).

    Trot: 'paper' applies all of id_r (the roll moment as if actuated), 'physical' leaves the
    roll unactuated. Static walk: one run. Percentage errors per joint (FL, FR, BL, BR x HAA..KFE)."""
    from dataclasses import asdict

    from .gait import GAITS
    from .gait import validate as run_validation

    gait = GAITS[gait_name]
    horizon = 2 * gait.period if horizon is None else horizon
    if abs(gait.phase_duration / dt - round(gait.phase_duration / dt)) > 1e-9:
        raise InputError(f"--dt {dt} does not divide the gait's phase of {gait.phase_duration} s; expected e.g. 1e-3")
    if horizon < dt:
        raise InputError(f"--horizon {horizon} s is shorter than one step (--dt {dt} s); expected horizon >= dt")
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    r = load_robot(robot)
    plot = out / f"{r.name}_{gait.name}_BR_HFE.png"
    report, _ = run_validation(r, gait, horizon, dt, str(plot))
    data = asdict(report)
    json_path = out / f"{r.name}_{gait.name}_validation.json"
    json_path.write_text(json.dumps(data, indent=2))
    if as_json:
        click.echo(json.dumps(data, indent=2))
        return
    names = [f"{leg.label}_{role}" for leg in r.legs for role in JOINT_ROLES]
    click.echo(f"{gait.name}, {r.name}: horizon {horizon} s, {report.integrator}, dt {dt} s; "
               "% error = max|sim - IK| / max|IK| x 100")
    for run, signals in report.runs.items():
        diverged, departs = report.diverged_at_s[run], report.departs_1pct_at_s[run]
        click.echo(f"  {run}: stance-foot closure error up to {report.max_closure_m[run]:.1e} m"
                   + (f"; 1 % off IK at {departs:.3f} s" if departs is not None else "")
                   + (f"; fell (a stance foot 0.1 m off its foothold) at {diverged:.3f} s" if diverged is not None else ""))
        if departs is not None:
            continue  # percentages of a run that left the reference mean nothing; see the JSON
        for signal, errors in signals.items():
            cells = " ".join(f"{'n/a':>7}" if np.isnan(e) else f"{e:7.1e}" for e in errors)
            click.echo(f"    {signal:<13}{cells}")
    click.echo(f"    {'':<13}" + " ".join(f"{n:>7}" for n in names))
    if gait.n_coords == 13:
        click.echo(f"  largest roll moment id_r asks for (unactuated on the robot): {report.max_roll_moment_Nm:.2f} N m")
    click.echo(f"  wrote {plot} and {json_path}")


@main.command()
@click.argument("robot", default="paper")
@click.option("--out", "out_dir", default="results", show_default=True,
              help="The page goes to OUT/<robot>/report.html, its files beside it.")
@click.option("--fast", is_flag=True, help="Skip the benchmark (its first run compiles a C++ harness for minutes).")
def report(robot: str, out_dir: str, fast: bool) -> None:
    """One self-contained HTML page of everything the toolkit knows about ROBOT (exit 1 if a check fails)."""
    from .report import build_report, prepare

    prepare(robot, out_dir)  # bad input is reported before any work
    result = build_report(robot, out_dir, fast)
    click.echo(result.summary())
    sys.exit(0 if result.passed else EXIT_CHECK_FAILED)


@main.command("make-urdf")
@click.option("--check", is_flag=True, help="Only compare the committed URDF with a fresh generation.")
def make_urdf(check: bool) -> None:
    """Regenerate the paper robot's URDF (package data, and urdf/ in a checkout) from the paper's DH table."""
    from .paper_robot import URDF_COPIES, stale_urdf_copies, write_urdf

    if check:
        stale = stale_urdf_copies()
        for path in URDF_COPIES:
            click.echo(f"{path}: {'DIFFERS from the generator' if path in stale else 'up to date'}")
        sys.exit(EXIT_CHECK_FAILED if stale else 0)
    for path in write_urdf():
        click.echo(f"wrote {path}")


if __name__ == "__main__":
    main()
