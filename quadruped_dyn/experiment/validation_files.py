"""Files of one ``validate`` run: the JSON report, a CSV of the time series, the BR HFE plot
(the paper's Figs. 5-7: acceleration, velocity, displacement) and the physics-check plot."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

import numpy as np

from quadruped_dyn.experiment.paper_experiment import DEPARTURE_PCT, SIGNALS, Experiment, departure, joint_names
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.safe_write import output_path, save_figure, text_writer
from quadruped_dyn.model.leg import BR_HFE


def output_paths(out_dir: Path, robot: str, gait: str) -> dict[str, Path]:
    """The run's files, each a plain file name in ``out_dir`` (``files.safe_write.output_path``)."""
    stem = f"{robot}_{gait}"
    names = {"json": f"{stem}_validation.json", "csv": f"{stem}_timeseries.csv", "plot": f"{stem}_BR_HFE.png",
             "physics_plot": f"{stem}_physics_check.png"}
    return {k: output_path(out_dir, name) for k, name in names.items()}


def write_csv(path: Path, exp: Experiment) -> None:
    """t, then per joint and signal the IK value and the 'paper' run's value (rad, rad/s, rad/s^2)."""
    run, target = exp.runs["paper"], exp.target
    names = joint_names(exp.plan.robot)
    m = min(len(run.t), len(target["t"]))
    header = ["t_s"] + [f"{n}_{s}_{w}" for n in names for s in SIGNALS for w in ("ik", "sim")]
    with text_writer(path) as f:
        w = csv.writer(f)
        w.writerow(header)
        for k in range(m):
            row = [f"{target['t'][k]:.6f}"]
            for j in range(12):
                for s in SIGNALS:
                    row += [repr(float(target[s][k, j])), repr(float(getattr(run, s)[k, j]))]
            w.writerow(row)


def plot_br_hfe(path: Path, exp: Experiment) -> None:
    """BR HFE: IK vs the reduced forward dynamics ('paper'; 'physical' with the roll unactuated
    when there is a roll), and the rigid-contact dynamics under the IK torques."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    robot, target, j = exp.plan.robot, exp.target, BR_HFE
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    labels = ("acceleration (rad/s²)", "velocity (rad/s)", "displacement (rad)")
    for ax, key, label in zip(axes, ("qdd", "qd", "q"), labels):
        ax.plot(target["t"], target[key][:, j], "k-", lw=2.5, label="inverse kinematics")
        paper = exp.runs["paper"]
        ax.plot(paper.t, getattr(paper, key)[:, j], "C1--", lw=1.5,
                label="reduced forward dynamics" + (", roll moment applied (paper)" if "physical" in exp.runs else ""))
        if "physical" in exp.runs:
            ax.plot(exp.runs["physical"].t, getattr(exp.runs["physical"], key)[:, j], "C0:", lw=1.5,
                    label="reduced forward dynamics, roll unactuated")
        if "ik" in exp.rigid:
            ax.plot(exp.rigid["ik"].t, getattr(exp.rigid["ik"], key)[:, j], "C2-.", lw=1.2,
                    label="rigid-contact dynamics, same joint torques")
        lo, hi = target[key][:, j].min(), target[key][:, j].max()
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

    target = exp.target
    scale = float(np.abs(target["q"][:, :12]).max())
    fig, ax = plt.subplots(figsize=(8, 4.5))
    reduced_ik = exp.runs.get("physical", exp.runs["paper"])
    curves = [("rigid vs IK, IK torques", exp.rigid["ik"], None),
              ("reduced (roll unactuated) vs IK, IK torques" if "physical" in exp.runs else "reduced vs IK, IK torques",
               reduced_ik, None),
              ("rigid vs reduced, IK torques", exp.rigid["ik"], reduced_ik),
              ("rigid vs reduced, +1 % torques", exp.rigid["plus_1pct"], exp.runs["plus_1pct"]),
              ("rigid vs reduced, +1 % torques + PD", exp.rigid["pd"], exp.runs["pd"])]
    for label, a, b in curves:
        d, _ = departure(a.t, a.q, target["q"] if b is None else b.q, scale)
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


def summary_text(data: dict[str, Any], names: list[str], written: list[Path]) -> str:
    """The ``validate`` command's text summary of a validation JSON (``paper_experiment.report``'s
    dict): percentage errors per joint, instability and error budget, static stability, runs that
    left IK, the physics check, and the files ``written``."""
    lines = [f"{data['gait']}, {data['robot']}: horizon {data['horizon_s']:g} s; {data['integrator']}",
             "% error = max|sim - IK| / max|IK| x 100, reduced forward dynamics, 'paper' run (n/a: IK signal is zero)",
             f"  {'':<6}" + " ".join(f"{n:>8}" for n in names)]
    for s in SIGNALS:
        cells = [data["max_pct_err"][n][s] for n in names]
        lines.append(f"  {s:<6}" + " ".join(f"{'n/a':>8}" if c is None else f"{c:8.1e}" for c in cells))
    inst = data["instability"]
    rate = inst["growth_rate_per_s"]
    lines.append(f"  instability: one ulp grows to {inst['one_ulp_grows_to_rad']:.1e} rad"
                 + (f", growth rate {rate:.1f} /s" if rate is not None else ""))
    for s, b in inst["error_budget"].items():
        lines.append(f"    {s:<4} total {_pct(b['total_pct'])} %, amplified round-off {_pct(b['roundoff_pct'])} %, "
                     f"truncation {_pct(b['truncation_pct'])} %")
    st = data["static_stability"]
    margin, at = st["min_com_margin_m"], st["min_com_margin_at_s"]
    lines.append(f"  smallest f_z {st['min_fz_N']:.2f} N (at {st['min_fz_at_s']:.3f} s, weight {st['weight_N']:.1f} N)"
                 + ("" if margin is None else f"; smallest CoM margin {margin * 100:.2f} cm (at {at:.3f} s)"))
    for name, run in data["runs"].items():
        if run["stopped_at_s"] is not None or run["departs_1pct_at_s"] is not None:
            lines.append(f"  run {name}: 1 % off IK {_at(run['departs_1pct_at_s'], 'never')}, "
                         f"{_at(run['stopped_at_s'], 'ran to the end', 'stopped (fell) at')}")
    for name, pc in data.get("physics_check", {}).items():
        if isinstance(pc, dict):
            rr = pc["rigid_vs_reduced"]
            ik = pc["rigid_vs_ik"]
            lines.append(f"  physics check, {name}: rigid-contact vs reduced max {rr['max_joint_angle_diff_rad']:.1e} rad, "
                         f"1 % {_at(rr['time_to_1pct_s'], 'never')}; rigid vs IK max {ik['max_joint_angle_diff_rad']:.1e} rad")
    lines.append("  wrote " + ", ".join(printable(p) for p in written))  # one line, whatever --out holds
    return "\n".join(lines)


def _at(t: float | None, none: str, what: str = "at") -> str:
    """'at 0.123 s', or what a missing time means (a run that never departed, never fell)."""
    return none if t is None else f"{what} {t:.3f} s"


def _pct(x: float | None) -> str:
    return "n/a" if x is None else f"{x:.1e}"
