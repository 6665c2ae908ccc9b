"""Files of one ``validate`` run: the JSON report, a CSV of the time series, the BR HFE plot
(the paper's Figs. 5-7: acceleration, velocity, displacement) and the physics-check plot."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from quadruped_dyn.experiment.paper_experiment import BR_HFE, DEPARTURE_PCT, SIGNALS, Experiment, departure, joint_names
from quadruped_dyn.files.safe_write import output_path, save_figure, text_writer, write_text


def output_paths(out_dir: Path, robot: str, gait: str) -> dict[str, Path]:
    """The run's files, each a plain file name in ``out_dir`` (``files.safe_write.output_path``)."""
    stem = f"{robot}_{gait}"
    names = {"json": f"{stem}_validation.json", "csv": f"{stem}_timeseries.csv", "plot": f"{stem}_BR_HFE.png",
             "physics_plot": f"{stem}_physics_check.png"}
    return {k: output_path(out_dir, name) for k, name in names.items()}


def _json_safe(x: Any) -> Any:
    """NaN and inf are not JSON: they become None (and never appear as numbers)."""
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def write_json(path: Path, data: dict[str, Any]) -> None:
    write_text(path, json.dumps(_json_safe(data), indent=2, allow_nan=False))


def write_csv(path: Path, exp: Experiment) -> None:
    """t, then per joint and signal the IK value and the 'paper' run's value (rad, rad/s, rad/s^2)."""
    run, ref = exp.runs["paper"], exp.reference
    names = joint_names(exp.plan.robot)
    m = min(len(run.t), len(ref["t"]))
    header = ["t_s"] + [f"{n}_{s}_{w}" for n in names for s in SIGNALS for w in ("ik", "sim")]
    with text_writer(path) as f:
        w = csv.writer(f)
        w.writerow(header)
        for k in range(m):
            row = [f"{ref['t'][k]:.6f}"]
            for j in range(12):
                for s in SIGNALS:
                    row += [repr(float(ref[s][k, j])), repr(float(getattr(run, s)[k, j]))]
            w.writerow(row)


def plot_br_hfe(path: Path, exp: Experiment) -> None:
    """BR HFE: IK vs the reduced forward dynamics ('paper'; 'physical' with the roll unactuated
    when there is a roll), and the rigid-contact dynamics under the IK torques."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    robot, ref, j = exp.plan.robot, exp.reference, BR_HFE
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    labels = ("acceleration (rad/s²)", "velocity (rad/s)", "displacement (rad)")
    for ax, key, label in zip(axes, ("qdd", "qd", "q"), labels):
        ax.plot(ref["t"], ref[key][:, j], "k-", lw=2.5, label="inverse kinematics")
        paper = exp.runs["paper"]
        ax.plot(paper.t, getattr(paper, key)[:, j], "C1--", lw=1.5,
                label="reduced forward dynamics" + (", roll moment applied (paper)" if "physical" in exp.runs else ""))
        if "physical" in exp.runs:
            ax.plot(exp.runs["physical"].t, getattr(exp.runs["physical"], key)[:, j], "C0:", lw=1.5,
                    label="reduced forward dynamics, roll unactuated")
        if "ik" in exp.rigid:
            ax.plot(exp.rigid["ik"].t, getattr(exp.rigid["ik"], key)[:, j], "C2-.", lw=1.2,
                    label="rigid-contact dynamics, same joint torques")
        lo, hi = ref[key][:, j].min(), ref[key][:, j].max()
        ax.set_ylim(lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo))  # a run that falls leaves the frame
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_title(f"BR HFE ({robot.legs[3].joints[1].name} of {robot.name}), {exp.plan.gait.name}")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)


def plot_physics_check(path: Path, exp: Experiment) -> None:
    """Largest joint-angle difference over time: rigid-contact vs reduced dynamics per torque
    law, and each against IK under the IK torques (log scale, the 1 % line dashed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = exp.reference
    scale = float(np.abs(ref["q"][:, :12]).max())
    fig, ax = plt.subplots(figsize=(8, 4.5))
    reduced_ik = exp.runs.get("physical", exp.runs["paper"])
    curves = [("rigid vs IK, IK torques", exp.rigid["ik"], None),
              ("reduced (roll unactuated) vs IK, IK torques" if "physical" in exp.runs else "reduced vs IK, IK torques",
               reduced_ik, None),
              ("rigid vs reduced, IK torques", exp.rigid["ik"], reduced_ik),
              ("rigid vs reduced, +1 % torques", exp.rigid["plus_1pct"], exp.runs["plus_1pct"]),
              ("rigid vs reduced, +1 % torques + PD", exp.rigid["pd"], exp.runs["pd"])]
    for label, a, b in curves:
        d, _ = departure(a.t, a.q, ref["q"] if b is None else b.q, scale)
        ax.semilogy(a.t[: len(d)], np.maximum(d, 1e-17), label=label)
    ax.axhline(DEPARTURE_PCT / 100 * scale, color="k", ls="--", lw=1, label=f"{DEPARTURE_PCT:g} % of max |joint angle|")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("largest joint-angle difference (rad)")
    ax.set_title(f"physics check: paper's reduced model vs rigid contacts ({exp.plan.robot.name}, {exp.plan.gait.name})")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    plt.close(fig)
