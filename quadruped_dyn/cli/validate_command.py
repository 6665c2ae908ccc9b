"""``validate``: the paper's experiment (IK -> id_r -> forward dynamics -> compare with the plan)."""

from __future__ import annotations

import json

import click

from quadruped_dyn.cli.app import echo, foot_frames_option
from quadruped_dyn.errors import NumericalError
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.files.provenance import check_source, record_source
from quadruped_dyn.files.safe_write import output_set, remove, replaceable

#: Samples per run beyond which validate states the cost (the limit: simulate.MAX_SAMPLES).
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
@click.option("--engine", type=click.Choice(["native", "python"]), default="native", show_default=True,
              help="DOP853 runs one gait phase per C call, or driven by scipy from Python (the reference).")
@click.option("--no-physics", is_flag=True, help="Skip the physics check (rigid-contact dynamics).")
@click.option("--out", "out_dir", default="results", show_default=True, type=click.Path(),
              help="Directory for the plots, the CSV and the JSON report.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@foot_frames_option
def validate(robot: str, gait_name: str, horizon: float | None, integrator: str, dt: float, backend: str,
             engine: str, no_physics: bool, out_dir: str, as_json: bool, foot_frames: str | None) -> None:
    """The paper's experiment: IK -> id_r -> forward dynamics -> compare with IK (plots, CSV, JSON),
    with the instability, the error budget and the physics check against rigid-contact dynamics.

    Trot: 'paper' applies all of id_r (the roll moment as if actuated), 'physical' leaves the
    roll unactuated. Percentage errors per joint (FL, FR, BL, BR x HAA, HFE, KFE). ROBOT: a name or
    URDF path, default paper."""

    from quadruped_dyn.experiment.gait import GAITS
    from quadruped_dyn.experiment.paper_experiment import (
        MIN_COMPARED_SAMPLES,
        compared_samples,
        joint_names,
        report,
        run_experiment,
        static_stability,
    )
    from quadruped_dyn.experiment.simulate import check_times, reduced_dynamics
    from quadruped_dyn.experiment.validation_files import output_paths, plot_br_hfe, plot_physics_check, summary_text, write_csv
    from quadruped_dyn.files.json import write_json
    from quadruped_dyn.model.robot import load_robot

    gait = GAITS[gait_name]
    horizon = 2 * gait.period if horizon is None else horizon
    check_times(gait, horizon, dt, integrator, names=("--horizon", "--dt"))
    runs = 3 + (gait.n_coords == 13) + (0 if no_physics else 5)
    _warn_work(horizon, dt, runs)
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    r = load_robot(robot, foot_frames=foot_frames)
    paths = output_paths(out, r.name, gait.name)
    replaceable(paths.values())
    check_source(out, r)  # another URDF's outputs of the same name are never overwritten
    dynamics = reduced_dynamics(r, backend)
    from quadruped_dyn.progress import Bar

    with Bar(f"simulating {r.name} {gait.name}", runs * horizon, "s simulated", runs=runs) as bar:
        exp = run_experiment(r, gait, dynamics, horizon, dt, integrator, physics=not no_physics,
                             progress=bar.advance, engine=engine)
    compared = compared_samples(exp)
    if compared < MIN_COMPARED_SAMPLES:
        stop = exp.runs["paper"].stopped_at
        raise NumericalError(f"the 'paper' run stopped at t = {stop if stop is not None else 0.0:g} s after {compared} "
                             f"sample(s) (--dt {dt:g} s); a comparison with IK needs at least {MIN_COMPARED_SAMPLES}: "
                             "no result (try a smaller --dt)")
    stability = static_stability(exp.plan, exp.ik, horizon)
    data = report(exp, integrator, dt, backend, stability)
    with output_set():  # all or nothing: an interrupt never leaves the new JSON beside an old CSV
        write_json(paths["json"], data)
        write_csv(paths["csv"], exp)
        plot_br_hfe(paths["plot"], exp)
        if exp.rigid:
            plot_physics_check(paths["physics_plot"], exp)
        else:  # no physics check: the previous run's plot is not this result's
            remove(paths["physics_plot"])
        record_source(out, r)
    if as_json:
        echo(json.dumps(json.loads(paths["json"].read_text()), indent=2))
        return
    echo(summary_text(data, joint_names(r), [p for p in paths.values() if p.exists()]))


def _warn_work(horizon: float, dt: float, runs: int) -> None:
    """Beyond WARN_SAMPLES samples per run (horizon / dt; ``check_times`` refused beyond MAX_SAMPLES), a
    one-line warning says what it will cost."""
    samples = horizon / dt
    if samples > WARN_SAMPLES:
        click.echo(f"warning: {int(samples):,} samples per run x {runs} runs: expect {samples / WARN_SAMPLES:.0f}x the "
                   "default's time (minutes)", err=True)
