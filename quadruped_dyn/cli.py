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
@click.option("--peers", default="", help="Also time other libraries' generated dynamics against the toolkit's, "
              "same run, same flags (comma-separated): adam.")
@click.option("--march-native", "native", is_flag=True, help="Build the --peers comparison (both sides) with -march=native.")
def bench(robots: tuple[str, ...], calls: int, reps: int, as_json: bool, peers: str, native: bool) -> None:
    """Time the generated C against Pinocchio's native C++ in the same run (ratios < 1: generated is faster)."""
    from dataclasses import asdict

    from .bench import run_bench
    from .cache import cache_dir
    from .peers import parse_peers, peers_table, run_peers

    peer_names = parse_peers(peers)
    _require_tools("gcc", "g++")
    writable_dir(cache_dir(), f"the cache directory '{cache_dir()}' (QUADRUPED_DYN_CACHE)")
    loaded = [load_robot(r) for r in robots]  # every argument checked before minutes of work
    reports = [run_bench(r, calls, reps) for r in loaded]
    entries = [e for r in loaded for e in run_peers(r, peer_names, native, calls, reps)] if peer_names else []
    if as_json:
        out: object = [r.as_dict() for r in reports]
        click.echo(json.dumps({"bench": out, "peers": [asdict(e) for e in entries]} if peer_names else out, indent=2))
    else:
        click.echo("\n\n".join([r.table() for r in reports] + ([peers_table(entries, native)] if entries else [])))


@main.command()
@click.argument("robot", default="paper")
@click.option("--gait", "gait_name", type=click.Choice(["trot", "walk"]), default="trot", show_default=True,
              help="Trot (the paper's experiment) or statically stable walk.")
@click.option("--horizon", default=None, type=float, help="Seconds [default: two gait cycles].")
@click.option("--integrator", type=click.Choice(["dop853", "rk4"]), default="dop853", show_default=True,
              help="Error-controlled DOP853, or classical RK4 with the fixed step --dt.")
@click.option("--dt", default=1e-3, show_default=True, type=float,
              help="RK4 step, s; with DOP853 the sampling interval of the output.")
@click.option("--backend", type=click.Choice(["c", "casadi"]), default="c", show_default=True,
              help="Evaluation of the reduced model: the generated C (built once, cached) or the CasADi graph.")
@click.option("--no-physics", is_flag=True, help="Skip the physics check (rigid-contact dynamics).")
@click.option("--out", "out_dir", default="results", show_default=True, type=click.Path(),
              help="Directory for the plots, the CSV and the JSON report.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
def validate(robot: str, gait_name: str, horizon: float | None, integrator: str, dt: float, backend: str,
             no_physics: bool, out_dir: str, as_json: bool) -> None:
    """The paper's experiment: IK -> id_r -> forward dynamics -> compare with IK (plots, CSV, JSON),
    with the instability, the error budget and the physics check against rigid-contact dynamics.

    Trot: 'paper' applies all of id_r (the roll moment as if actuated), 'physical' leaves the
    roll unactuated. Percentage errors per joint (FL, FR, BL, BR x HAA, HFE, KFE)."""

    from .gait import GAITS
    from .simulate import reduced_dynamics
    from .validation import SIGNALS, joint_names, report, run_experiment, static_stability
    from .validation_files import output_paths, plot_br_hfe, plot_physics_check, write_csv, write_json

    gait = GAITS[gait_name]
    horizon = 2 * gait.period if horizon is None else horizon
    if not (math.isfinite(horizon) and horizon > 0):
        raise InputError(f"--horizon {horizon} is not a positive finite number of seconds; expected e.g. {2 * gait.period}")
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"--dt {dt} is not a positive finite number of seconds; expected e.g. 1e-3")
    if horizon < dt:
        raise InputError(f"--horizon {horizon} s is shorter than one step (--dt {dt} s); expected horizon >= dt")
    if integrator == "rk4" and abs(gait.phase_duration / dt - round(gait.phase_duration / dt)) > 1e-9:
        raise InputError(f"--dt {dt} does not divide the gait's phase of {gait.phase_duration} s; expected e.g. 1e-3")
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    r = load_robot(robot)
    paths = output_paths(out, r.name, gait.name)
    dynamics = reduced_dynamics(r, backend)
    runs = 3 + (gait.n_coords == 13) + (0 if no_physics else 5)
    with click.progressbar(length=int(round(runs * horizon * 1000)), label=f"simulating {r.name} {gait.name}",
                           file=sys.stderr) as bar:
        exp = run_experiment(r, gait, dynamics, horizon, dt, integrator, physics=not no_physics,
                             progress=lambda seconds: bar.update(int(round(seconds * 1000))))
    stability = static_stability(exp.plan, exp.ik, horizon)
    data = report(exp, integrator, dt, backend, stability)
    write_json(paths["json"], data)
    write_csv(paths["csv"], exp)
    plot_br_hfe(paths["plot"], exp)
    if exp.rigid:
        plot_physics_check(paths["physics_plot"], exp)
    else:
        paths["physics_plot"].unlink(missing_ok=True)
    if as_json:
        click.echo(json.dumps(json.loads(paths["json"].read_text()), indent=2))
        return
    names = joint_names(r)
    click.echo(f"{gait.name}, {r.name}: horizon {data['horizon_s']:g} s; {data['integrator']}")
    click.echo("% error = max|sim - IK| / max|IK| x 100, reduced forward dynamics, 'paper' run (n/a: IK signal is zero)")
    click.echo(f"  {'':<6}" + " ".join(f"{n:>8}" for n in names))
    for s in SIGNALS:
        cells = [data["max_pct_err"][n][s] for n in names]
        click.echo(f"  {s:<6}" + " ".join(f"{'n/a':>8}" if c is None else f"{c:8.1e}" for c in cells))
    inst = data["instability"]
    rate = inst["growth_rate_per_s"]
    click.echo(f"  instability: one ulp grows to {inst['one_ulp_grows_to_rad']:.1e} rad"
               + (f", growth rate {rate:.1f} /s" if rate is not None else ""))
    for s, b in inst["error_budget"].items():
        click.echo(f"    {s:<4} total {_pct(b['total_pct'])} %, amplified round-off {_pct(b['roundoff_pct'])} %, "
                   f"truncation {_pct(b['truncation_pct'])} %")
    st = data["static_stability"]
    margin, at = st["min_com_margin_m"], st["min_com_margin_at_s"]
    click.echo(f"  smallest f_z {st['min_fz_N']:.2f} N (at {st['min_fz_at_s']:.3f} s, weight {st['weight_N']:.1f} N)"
               + ("" if margin is None else f"; smallest CoM margin {margin * 100:.2f} cm (at {at:.3f} s)"))
    for name, run in data["runs"].items():
        if run["stopped_at_s"] is not None or run["departs_1pct_at_s"] is not None:
            click.echo(f"  run {name}: 1 % off IK at {run['departs_1pct_at_s']} s, stopped (fell) at {run['stopped_at_s']} s")
    for name, pc in data.get("physics_check", {}).items():
        if isinstance(pc, dict):
            rr = pc["rigid_vs_reduced"]
            ik = pc["rigid_vs_ik"]
            click.echo(f"  physics check, {name}: rigid-contact vs reduced max {rr['max_joint_angle_diff_rad']:.1e} rad, "
                       f"1 % at {rr['time_to_1pct_s']} s; rigid vs IK max {ik['max_joint_angle_diff_rad']:.1e} rad")
    click.echo("  wrote " + ", ".join(str(p) for p in paths.values() if p.exists()))


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.1e}"


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
