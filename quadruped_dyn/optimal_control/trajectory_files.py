"""Files of one ``optimize`` run: the optimised trajectory (CSV), the JSON report (solve time,
iterations, constraint violation, objective, per-node residuals, effort against the plan, the
rigid-contact replay) and plots against today's plan."""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Any

import numpy as np

from quadruped_dyn.experiment.paper_experiment import joint_names, static_stability
from quadruped_dyn.experiment.simulate import IkTorques, reduced_dynamics
from quadruped_dyn.files.json import write_json
from quadruped_dyn.files.safe_write import output_path, output_set, save_figure, text_writer
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.optimal_control.replay import OptimizedTrajectory, Replay
from quadruped_dyn.optimal_control.solve import MAX_CONSTRAINT_VIOLATION, Solution
from quadruped_dyn.optimal_control.transcription import (
    CLEARANCE_FRACTION,
    FOOTHOLD_BOUND_M,
    MIN_COM_MARGIN_M,
    TRUNK_ANGLE_RAD,
    TRUNK_HEIGHT_M,
    W_EFFORT,
    W_PLAN,
    W_SMOOTH,
    plan_coordinates,
)

COORDINATES = ("roll", "pitch", "yaw", "p_x", "p_y", "p_z")

#: Samples per cycle of the CSV and the plots.
SAMPLES_PER_CYCLE = 240


def output_paths(out_dir: Path, robot: str, gait: str) -> dict[str, Path]:
    stem = f"{robot}_{gait}_optimised"
    return {key: output_path(out_dir, f"{stem}{suffix}") for key, suffix in (("json", ".json"), ("csv", ".csv"),
                                                                              ("plot", ".png"))}


def coordinate_names(robot: Any) -> list[str]:
    return joint_names(robot) + list(COORDINATES)


def per_node_residuals(sol: Solution) -> dict[str, list[float]]:
    """Per constraint group, the largest violation at each node (units of the group: N m, N, m, ...)."""
    tr = sol.transcription
    g = sol.g
    out: dict[str, list[float]] = {}
    for name, rows in tr.groups.items():
        per = np.zeros(tr.n_nodes)
        for k, a, b in rows:
            v = np.maximum(tr.lbg[a:b] - g[a:b], 0) + np.maximum(g[a:b] - tr.ubg[a:b], 0)
            per[k] = max(per[k], float(v.max(initial=0.0)))
        out[name] = per.tolist()
    return out


def plan_effort(sol: Solution, samples: int = SAMPLES_PER_CYCLE) -> dict[str, float]:
    """integral over one cycle of sum_j tau_j^2 (N^2 m^2 s) for the optimised motion and for today's
    plan (id_r of the IK plan, the roll moment applied as the paper's check does), on one grid;
    and the largest roll moment each needs (N m)."""
    tr = sol.transcription
    traj = OptimizedTrajectory(sol)
    ik = IkTorques(tr.plan, reduced_dynamics(tr.robot, "casadi"))
    dt = tr.gait.period / samples
    e_opt = e_plan = 0.0
    roll_opt = roll_plan = 0.0
    for j in range(samples):
        t = (j + 0.5) * dt
        stance = tr.gait.stance(t)
        tau, roll = traj.torques(t, stance)
        e_opt += float(tau @ tau) * dt
        roll_opt = max(roll_opt, abs(roll))
        _, tau_p = ik(t, stance)
        e_plan += float(tau_p[:12] @ tau_p[:12]) * dt
        if tau_p.size > 12:
            roll_plan = max(roll_plan, abs(float(tau_p[12])))
    return {"optimised_Nm2s": e_opt, "plan_Nm2s": e_plan, "ratio": e_opt / e_plan,
            "max_roll_moment_optimised_Nm": roll_opt, "max_roll_moment_plan_Nm": roll_plan}


def walk_feasibility(sol: Solution) -> dict[str, Any]:
    """Smallest f_z and CoM margin of the optimised walk (its collocation points) and of today's plan
    (``paper_experiment.static_stability``, every 5 ms)."""
    tr = sol.transcription
    groups = tr.groups
    g = sol.g
    fz = min(float(g[a:b].min()) for _, a, b in groups["fz_min"])
    margin = min(float(g[a:b].min()) for _, a, b in groups["com_margin"])
    ik = IkTorques(tr.plan, reduced_dynamics(tr.robot, "casadi"))
    plan = static_stability(tr.plan, ik, tr.gait.period)
    return {"optimised": {"min_fz_N": fz, "min_com_margin_m": margin},
            "plan": {"min_fz_N": plan["min_fz_N"], "min_com_margin_m": plan["min_com_margin_m"]},
            "weight_N": plan["weight_N"]}


def report(sol: Solution, replay: Replay | None, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    tr = sol.transcription
    o = tr.options
    data: dict[str, Any] = {
        "robot": tr.robot.name, "gait": tr.gait.name, "status": sol.status, "converged": sol.converged,
        "iterations": sol.iterations, "solve_seconds": sol.solve_seconds, "solve_cpu_seconds": sol.solve_cpu_seconds,
        "load_average_1min": os.getloadavg()[0], "build_seconds": sol.build_seconds,
        "transcribe_seconds": sol.transcribe_seconds,
        "objective": sol.objective, "constraint_violation": sol.constraint_violation,
        "max_constraint_violation_allowed": MAX_CONSTRAINT_VIOLATION, "hessian": sol.hessian,
        "formulation": {
            "method": "direct collocation in inverse-dynamics form on a quintic spline (C^3 within a phase, C^2 at "
                      "switches); dynamics at every node and at the interior points of every interval",
            "interior_points": list(o.interior_points),
            "nodes_per_phase": o.nodes_per_phase, "nodes": tr.n_nodes, "variables": int(tr.lbw.size),
            "constraints": int(tr.lbg.size), "period_s": tr.gait.period, "speed_m_s": tr.speed,
            "mu": o.mu, "fz_min_N": o.fz_min_fraction * tr.robot.total_mass * 9.81,
            "fz_min_fraction_of_weight": o.fz_min_fraction, "clearance_fraction_of_plan_bump": CLEARANCE_FRACTION,
            "foothold_bound_m": FOOTHOLD_BOUND_M, "trunk_angle_bound_rad": TRUNK_ANGLE_RAD,
            "trunk_height_bound_m": TRUNK_HEIGHT_M, "min_com_margin_m": MIN_COM_MARGIN_M if tr.gait.name == "walk" else None,
            "weights": {"effort": W_EFFORT, "plan": W_PLAN, "smooth": W_SMOOTH},
        },
        "effort": plan_effort(sol),
        "per_node_residuals": per_node_residuals(sol),
    }
    if tr.gait.name == "walk":
        data["feasibility"] = walk_feasibility(sol)
    if replay is not None:
        data["rigid_contact_replay"] = replay.summary()
    data.update(extra or {})
    return data


def write_csv(path: Path, sol: Solution, samples: int = SAMPLES_PER_CYCLE) -> None:
    """One cycle: t, stance, the 18 optimised coordinates, the plan's, and the 12 optimised torques."""
    tr = sol.transcription
    traj = OptimizedTrajectory(sol)
    names = coordinate_names(tr.robot)
    jn = joint_names(tr.robot)
    header = ["t_s", "stance"] + [f"{n}_opt" for n in names] + [f"{n}_plan" for n in names] + [f"tau_{n}_opt" for n in jn] + [
        "roll_moment_opt_Nm"]
    guess = None
    with text_writer(path) as f:
        w = csv.writer(f)
        w.writerow(header)
        for j in range(samples + 1):
            t = j * tr.gait.period / samples
            stance = tr.gait.stance(min(t, tr.gait.period * (1 - 1e-9)))
            x, _, _ = traj.state(t)
            xp, _, _ = plan_coordinates(tr.plan, t, guess)
            guess = xp[:12]
            tau, roll = traj.torques(t, stance)
            w.writerow([f"{t:.6f}", StanceSet(stance).name] + [repr(float(v)) for v in (*x, *xp, *tau)] + [repr(roll)])


def plot(path: Path, sol: Solution, replay: Replay | None = None, samples: int = SAMPLES_PER_CYCLE) -> None:
    """Joint angles (optimised vs plan), trunk roll and lateral sway, torques, and the replay's departure."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tr = sol.transcription
    traj = OptimizedTrajectory(sol)
    ik = IkTorques(tr.plan, reduced_dynamics(tr.robot, "casadi"))
    t = np.linspace(0.0, tr.gait.period * (1 - 1e-9), samples)
    X = np.array([traj.state(float(s))[0] for s in t])
    tau = np.array([traj.torques(float(s), tr.gait.stance(float(s)))[0] for s in t])
    XP = np.array([plan_coordinates(tr.plan, float(s))[0] for s in t])
    taup = np.array([ik(float(s), tr.gait.stance(float(s)))[1] for s in t])
    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    for j, ax in enumerate(axes[0]):  # HAA, HFE, KFE of all legs
        for leg in range(4):
            line = ax.plot(t, X[:, 3 * leg + j], label=f"{joint_names(tr.robot)[3 * leg + j]} optimised")[0]
            ax.plot(t, XP[:, 3 * leg + j], "--", color=line.get_color(), label="plan")
        ax.set_title(("HAA", "HFE", "KFE")[j] + " (rad): optimised (solid) vs plan (dashed)")
        ax.set_xlabel("t (s)")
    axes[0, 0].legend(fontsize=6)
    ax = axes[1, 0]
    ax.plot(t, X[:, 12], label="roll (rad)")
    ax.plot(t, X[:, 13], label="pitch (rad)")
    ax.plot(t, (X[:, 16] - XP[:, 16]) * 10, label="lateral sway (dm)")
    ax.plot(t, XP[:, 12], "--", label="plan roll")
    ax.set_title("trunk")
    ax.legend(fontsize=7)
    ax.set_xlabel("t (s)")
    ax = axes[1, 1]
    ax.plot(t, np.sqrt((tau**2).sum(axis=1)), label="|tau| optimised")
    ax.plot(t, np.sqrt((taup[:, :12] ** 2).sum(axis=1)), "--", label="|tau| plan")
    if taup.shape[1] > 12:
        ax.plot(t, taup[:, 12], ":", label="roll moment the plan needs (N m)")
    ax.set_title("torques (N m)")
    ax.legend(fontsize=7)
    ax.set_xlabel("t (s)")
    ax = axes[1, 2]
    if replay is not None and replay.run.t.size:
        m = len(replay.departure_rad)
        ax.semilogy(replay.run.t[:m], np.maximum(replay.departure_rad, 1e-16), label="optimised torques, open loop")
        ax.axhline(0.01 * float(np.abs(replay.target_q).max()), color="k", ls=":", label="1 %")
        ax.set_title("rigid-contact replay: joint-angle departure (rad)")
        ax.legend(fontsize=7)
        ax.set_xlabel("t (s)")
    else:
        ax.axis("off")
    fig.suptitle(f"{tr.robot.name} {tr.gait.name}: optimised ({sol.status}, {sol.iterations} iterations) vs today's plan")
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)


def write_outputs(paths: dict[str, Path], sol: Solution, replay: Replay | None, data: dict[str, Any]) -> None:
    with output_set():  # all or nothing: an interrupt never leaves the new JSON beside an old CSV
        write_json(paths["json"], data)
        write_csv(paths["csv"], sol)
        plot(paths["plot"], sol, replay)
