"""``control``: the generated C controls the robot in MuJoCo along a gait (docs/closed_loop.md)."""

from __future__ import annotations

import json

import click

from quadruped_dyn.cli.app import echo, foot_frames_option, progress
from quadruped_dyn.files.cache import writable_cache
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.files.provenance import check_source, record_source
from quadruped_dyn.files.safe_write import output_set, replaceable


@click.command()
@click.argument("robot")
@click.option("--gait", "gait_name", default="walk", show_default=True, help="walk (static, 3 feet) or trot.")
@click.option("--controller", "controllers", multiple=True, metavar="NAME",
              help="pd, ff+pd, ct, ct-diag, pd-diag, ct-diag+land, id+pd, ff+pd+level, ff+pd+step, wbc, mpc+wbc "
                   "(repeatable) [default: all].")
@click.option("--cycles", default=10, show_default=True, type=int, help="Gait cycles to simulate.")
@click.option("--rate", "rate_hz", default=1000.0, show_default=True, type=float, help="Control rate, Hz.")
@click.option("--timestep", default=0.0005, show_default=True, type=float, help="MuJoCo's step, s.")
@click.option("--mu", default=0.8, show_default=True, type=float, help="Friction coefficient of feet and floor.")
@click.option("--kp-per-kg", default=None, type=float, help="Joint PD stiffness, N m/rad per kg [default: 20].")
@click.option("--kd-per-kg", default=None, type=float, help="Joint PD damping, N m s/rad per kg [default: 0.5].")
@click.option("--push", nargs=4, type=float, default=None, metavar="T IX IY IZ",
              help="Push the trunk at T s with an impulse (IX, IY, IZ) N s, world frame, over 10 ms.")
@click.option("--out", "out_dir", default="results", show_default=True, type=click.Path(),
              help="Directory for the JSON, CSV, plots and animation.")
@click.option("--no-animation", is_flag=True, help="Skip the animation.")
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@foot_frames_option
def control(robot: str, gait_name: str, controllers: tuple[str, ...], cycles: int, rate_hz: float, timestep: float,
            mu: float, kp_per_kg: float | None, kd_per_kg: float | None, push: tuple[float, float, float, float] | None,
            out_dir: str, no_animation: bool,
            as_json: bool, foot_frames: str | None) -> None:
    """Closed loop: each controller (on the generated C) walks or trots ROBOT in MuJoCo.
    Reports falls, tracking, trunk drift, foot slip, MuJoCo's contact forces against the
    paper's GRF model, torque saturation and the C calls' time per tick."""
    from dataclasses import replace

    from quadruped_dyn.control.closed_loop import prepare, run_all
    from quadruped_dyn.control.controllers import Gains
    from quadruped_dyn.control.plant import PlantOptions
    from quadruped_dyn.control.run import LoopOptions
    from quadruped_dyn.control.study_files import output_paths, write_all
    from quadruped_dyn.model.robot import load_robot

    gains = Gains()
    gains = replace(gains, **{k: v for k, v in (("kp_per_kg", kp_per_kg), ("kd_per_kg", kd_per_kg)) if v is not None})
    study = prepare(load_robot(robot, foot_frames=foot_frames), gait_name, controllers, gains,
                    LoopOptions(rate_hz=rate_hz, cycles=cycles, push=push or None), PlantOptions(timestep=timestep, mu=mu))
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    replaceable(output_paths(out, study.robot.name, study.plan.gait.name).values())
    check_source(out, study.robot)  # another URDF's outputs of the same name are never overwritten
    writable_cache()  # the generated C is built there: a read-only cache is one line, before the progress
    total = study.loop.cycles * study.plan.gait.period * len(study.controllers)
    with progress(f"{study.robot.name} {gait_name}: simulated ms", int(round(total * 1000))) as bar:
        done = [0]

        def tick(t: float) -> None:
            ms = int(round(t * 1000))
            bar.update(max(0, ms - done[0]))
            done[0] = max(done[0], ms)

        run_all(study, progress=tick, keep_qpos=not no_animation)
    with output_set():  # the record with the outputs
        data, paths = write_all(out, study, animation=not no_animation)
        record_source(out, study.robot)
    if as_json:
        echo(json.dumps(data, indent=2))
        _fail_on_infeasible_qp(data)
        return
    echo(f"{study.robot.name} {gait_name}, {study.loop.cycles} cycles of {study.plan.gait.period:g} s, "
               f"{study.loop.rate_hz:g} Hz control, MuJoCo step {study.plant.options.timestep:g} s")
    width = max(len("controller"), *map(len, data["controllers"]))  # ct-diag+land: 12
    echo(f"{'controller':<{width}} {'cycles up':>9} {'RMS [rad]':>10} {'max [rad]':>10} {'slip [mm]':>9} "
               f"{'sat [s]':>8} {'C med [us]':>10} {'tick [us]':>9}")
    for name, r in data["controllers"].items():
        slip, nan = r["foot_slip"]["max_m"], float("nan")  # None (JSON null) where the run stopped at its first tick
        rms, worst, compute = r["tracking"]["rms_rad"] or nan, r["tracking"]["max_rad"] or nan, r["compute"]
        echo(f"{name:<{width}} {r['cycles_up']:>9.0f} {rms:>10.4f} {worst:>10.3f} "
                   f"{(slip or 0) * 1e3:>9.1f} {r['saturation']['time_s']:>8.3f} {compute.get('c_calls_median_us', nan):>10.2f} "
                   f"{compute.get('tick_python_median_us', nan):>9.0f}" + (f"  {r['stopped']}" if r["stopped"] else ""))
    echo(f"files: {', '.join(printable(p) for p in paths.values() if p.exists())}")
    _fail_on_infeasible_qp(data)


def _fail_on_infeasible_qp(data: dict) -> None:
    """Exit 1 with one line if a controller's whole-body QP had no solution (the files are written)."""
    from quadruped_dyn.errors import NumericalError

    for name, r in data["controllers"].items():
        if r.get("qp_infeasible"):
            raise NumericalError(f"{name}: {r['stopped']}")
