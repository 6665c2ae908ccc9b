"""``optimize``: one periodic gait cycle optimised on the reduced model (CasADi + IPOPT), replayed
open loop in the rigid-contact dynamics (docs/optimal_control.md)."""

from __future__ import annotations

import json
import math
import sys

import click

from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, foot_frames_option
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.paths import writable_dir
from quadruped_dyn.files.provenance import check_source, record_source
from quadruped_dyn.files.safe_write import output_set, replaceable


@click.command()
@click.argument("robot", default="paper")
@click.option("--gait", "gait_name", type=click.Choice(["trot", "walk"]), default="trot", show_default=True,
              help="Trot (roll unactuated) or statically stable walk.")
@click.option("--nodes", default=None, type=int, help="Collocation nodes per phase [default: 4].")
@click.option("--mu", default=None, type=float, help="Friction coefficient of the cone [default: 0.6].")
@click.option("--speed", default=None, type=float, help="Forward speed, m/s [default: the gait's].")
@click.option("--hessian", type=click.Choice(["exact", "limited-memory"]), default="exact", show_default=True,
              help="IPOPT's Hessian: exact (assembled from the blocks' SX Hessians) or L-BFGS.")
@click.option("--cycles", default=2.0, show_default=True, type=float,
              help="Cycles of the rigid-contact replay (0: no replay).")
@click.option("--out", "out_dir", default="results", show_default=True, type=click.Path(),
              help="Directory for the CSV, the JSON report and the plot.")
@click.option("--json", "as_json", is_flag=True, help="Print the report as JSON.")
@foot_frames_option
def optimize(robot: str, gait_name: str, nodes: int | None, mu: float | None, speed: float | None, hessian: str,
             cycles: float, out_dir: str, as_json: bool, foot_frames: str | None) -> None:
    """Optimise one periodic gait cycle on the reduced model: the roll unactuated (id_r's 13th entry
    = 0), the paper's GRF in the friction cone, URDF joint and effort limits, swing clearance,
    periodicity at the plan's speed; effort + closeness to the plan. Exit 1 with IPOPT's status when
    the solve does not converge. ROBOT: a name or URDF path, default paper."""
    from quadruped_dyn.experiment.gait import GAITS
    from quadruped_dyn.experiment.simulate import MAX_SAMPLES
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.optimal_control.replay import REPLAY_DT, replay_rigid
    from quadruped_dyn.optimal_control.solve import MAX_CONSTRAINT_VIOLATION, solve
    from quadruped_dyn.optimal_control.trajectory_files import output_paths, report, write_outputs
    from quadruped_dyn.optimal_control.transcription import MU, NODES_PER_PHASE, Options, transcribe

    if not (math.isfinite(cycles) and cycles >= 0):
        raise InputError(f"--cycles {cycles} is not a number of cycles; expected e.g. 2")
    gait = GAITS[gait_name]
    samples = cycles * gait.period / REPLAY_DT
    if samples > MAX_SAMPLES:
        raise InputError(f"--cycles {cycles:g} of the {gait.period:g} s cycle is {samples:.3g} replay "
                         f"samples at {REPLAY_DT:g} s; expected at most {MAX_SAMPLES:,} "
                         f"(--cycles <= {MAX_SAMPLES * REPLAY_DT / gait.period:g})")
    if 0 < cycles * gait.period < REPLAY_DT:  # replay_rigid would refuse it, after the solve
        raise InputError(f"--cycles {cycles:g} of the {gait.period:g} s cycle is shorter than one replay step "
                         f"({REPLAY_DT:g} s); expected 0 (no replay) or at least {REPLAY_DT / gait.period:.3g}")
    options = Options(nodes_per_phase=NODES_PER_PHASE if nodes is None else nodes, mu=MU if mu is None else mu, speed=speed)
    out = writable_dir(out_dir, f"--out '{out_dir}'")
    r = load_robot(robot, foot_frames=foot_frames)
    options.check(r, gait)  # bad input: exit 2 before any work
    paths = output_paths(out, r.name, gait.name)
    replaceable(paths.values())
    check_source(out, r)  # another URDF's outputs of the same name are never overwritten
    click.echo(f"transcribing {r.name} {gait.name} ...", err=True)
    tr = transcribe(r, gait, options)
    click.echo(f"solving: {tr.lbw.size} variables, {tr.lbg.size} constraints, {hessian} Hessian ...", err=True)
    sol = solve(tr, hessian)
    if not sol.converged:
        click.echo(f"error: IPOPT did not converge on {r.name} {gait.name}: {sol.status} after {sol.iterations} iterations, "
                   f"constraint violation {sol.constraint_violation:.1e} (allowed {MAX_CONSTRAINT_VIOLATION:g})", err=True)
        sys.exit(EXIT_CHECK_FAILED)
    replay = None
    if cycles > 0:
        click.echo(f"replaying the torques open loop in the rigid-contact dynamics for {cycles:g} cycles ...", err=True)
        replay = replay_rigid(sol, cycles)
    data = report(sol, replay)
    with output_set():  # the record with the outputs
        write_outputs(paths, sol, replay, data)
        record_source(out, r)
    if as_json:
        echo(json.dumps(json.loads(paths["json"].read_text()), indent=2))
        return
    e = data["effort"]
    echo(f"{gait.name}, {r.name}: {sol.status} in {sol.iterations} iterations, {sol.solve_seconds:.1f} s "
               f"({sol.solve_cpu_seconds:.1f} s CPU; + {sol.build_seconds:.1f} s building), "
               f"constraint violation {sol.constraint_violation:.1e}")
    echo(f"  effort {e['optimised_Nm2s']:.3g} N^2 m^2 s vs the plan's {e['plan_Nm2s']:.3g} "
               f"({100 * (e['ratio'] - 1):+.1f} %); largest roll moment needed "
               f"{e['max_roll_moment_optimised_Nm']:.1e} N m (plan {e['max_roll_moment_plan_Nm']:.2f})")
    if "feasibility" in data:
        f = data["feasibility"]
        opt, pl = f["optimised"], f["plan"]
        echo(f"  smallest f_z {opt['min_fz_N']:.2f} N (plan {pl['min_fz_N']:.2f}), CoM margin "
                   f"{100 * opt['min_com_margin_m']:.2f} cm (plan {100 * pl['min_com_margin_m']:.2f})")
    if replay is not None:
        s = replay.summary()
        t, rate, stop = s["time_to_1pct_s"], s["growth_rate_per_s"], s["stopped_at_s"]
        echo(f"  rigid-contact replay, open loop over {s['horizon_s']:g} s: "
                   + (f"1 % off at {t:.3g} s" if t is not None else "never 1 % off")
                   + (f", growth rate {rate:.1f} /s" if rate is not None else ", no growth rate (no departure to fit)")
                   + (f", stopped (fell or singular) at {stop:.3g} s" if stop is not None else ", ran to the end"))
    echo("  wrote " + ", ".join(printable(p) for p in paths.values()))
