"""``validate``: the paper's experiment (IK -> id_r -> forward dynamics -> compare with the plan)."""

from __future__ import annotations

import json
import math
import sys

import click

from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.model.robot import load_robot

#: Samples per run (horizon / dt) that validate accepts: 100x the default two cycles at 1 ms,
#: minutes of integration per run; beyond it the work (and memory: a state per sample and run)
#: is refused before it starts. Beyond WARN_SAMPLES the cost is stated.
MAX_SAMPLES = 200_000
WARN_SAMPLES = 20_000


@click.command()
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

    from quadruped_dyn.experiment.gait import GAITS
    from quadruped_dyn.experiment.outputs import output_paths, plot_br_hfe, plot_physics_check, write_csv, write_json
    from quadruped_dyn.experiment.paper_experiment import (
        MIN_COMPARED_SAMPLES,
        SIGNALS,
        compared_samples,
        joint_names,
        report,
        run_experiment,
        static_stability,
    )
    from quadruped_dyn.experiment.simulate import reduced_dynamics

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
    samples = horizon / dt
    if samples > MAX_SAMPLES:
        raise InputError(f"--horizon {horizon:g} s at --dt {dt:g} s is {samples:.3g} samples per run; expected at most "
                         f"{MAX_SAMPLES:,} samples (horizon / dt) per run; a larger --dt or a shorter --horizon")
    runs = 3 + (gait.n_coords == 13) + (0 if no_physics else 5)
    if samples > WARN_SAMPLES:
        click.echo(f"warning: {int(samples):,} samples per run x {runs} runs: expect {samples / WARN_SAMPLES:.0f}x the "
                   "default's time (minutes)", err=True)
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    r = load_robot(robot)
    paths = output_paths(out, r.name, gait.name)
    dynamics = reduced_dynamics(r, backend)
    with click.progressbar(length=int(round(runs * horizon * 1000)), label=f"simulating {r.name} {gait.name}",
                           file=sys.stderr) as bar:
        exp = run_experiment(r, gait, dynamics, horizon, dt, integrator, physics=not no_physics,
                             progress=lambda seconds: bar.update(int(round(seconds * 1000))))
    compared = compared_samples(exp)
    if compared < MIN_COMPARED_SAMPLES:
        stop = exp.runs["paper"].stopped_at
        raise NumericalError(f"the 'paper' run stopped at t = {stop if stop is not None else 0.0:g} s after {compared} "
                             f"sample(s) (--dt {dt:g} s); a comparison with IK needs at least {MIN_COMPARED_SAMPLES}: "
                             "no result (try a smaller --dt)")
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
