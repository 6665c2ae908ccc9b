"""What a closed-loop run measured (``Trace`` -> plain data for JSON, tables and the report).

* **fell**: whether and when (``run.FALL_HEIGHT_FRACTION``, ``run.FALL_TILT_RAD``), or why the
  run stopped early; ``cycles_up``: gait cycles completed standing.
* **tracking**: q_ref - q per joint over the run (until it stopped): RMS and max |.|, rad.
* **trunk drift** against the plan (trunk origin at the plan's position with R = I): height
  error (final, max |.|), roll / pitch max |.|, yaw final, forward and lateral position error
  (final), m and deg.
* **foot slip**: for each foot and each interval in which the plan has it in stance, the
  horizontal path length of the foot frame's origin while MuJoCo has it on the ground (m; a
  sphere rolling without slipping moves its centre too, by radius x its rolling angle, a few
  mm); max and median over intervals, per foot and overall.
* **GRF** (also of the four-feet stand while the robot settles, ``ClosedLoop.standing_grf``):
  MuJoCo's contact forces vs the paper's GRF model at the same instants (samples every
  ``LoopOptions.grf_every`` ticks; only instants where MuJoCo's feet in contact are exactly the
  plan's stance), per stance kind (4, 3, 2 feet): per-foot force difference |f_paper - f_mujoco|
  (N; median, max), relative to |f_mujoco| summed over the stance feet, and the difference
  per component (x, y, z; world frame; median |.|).
* **saturation**: time with any commanded |tau| above the URDF effort limit (MuJoCo clamps it), s
  and fraction, and per joint.
* **compute**: per tick (median, 99th percentile, us) the generated-C calls, the QP (wbc), the whole
  controller tick in Python (measurement, target lookup, torques), the rest of the tick (Python
  overhead); MuJoCo's steps per tick (median, us).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from quadruped_dyn.control.plant import Plant
from quadruped_dyn.control.run import Trace
from quadruped_dyn.experiment.gait import Plan

STANCE_KINDS = {4: "4 feet", 3: "3 feet", 2: "2 feet"}


def _rpy(R: np.ndarray) -> np.ndarray:
    return np.array([pin.rpy.matrixToRpy(x) for x in R]).reshape(-1, 3)


def tracking(trace: Trace) -> dict[str, Any]:
    e = trace.q_ref - trace.q
    if not e.size:
        return {"rms_rad": None, "max_rad": None, "per_joint_rms_rad": [], "per_joint_max_rad": []}
    return {"rms_rad": float(np.sqrt(np.mean(e**2))), "max_rad": float(np.abs(e).max()),
            "per_joint_rms_rad": np.sqrt(np.mean(e**2, axis=0)).tolist(),
            "per_joint_max_rad": np.abs(e).max(axis=0).tolist()}


def trunk_drift(trace: Trace, plan: Plan) -> dict[str, Any]:
    if not trace.t.size:
        return {}
    planned = np.array([plan.trunk(t)[0] for t in trace.t])
    d = trace.trunk_p - planned
    rpy = np.degrees(_rpy(trace.trunk_R))
    return {"height_final_m": float(d[-1, 2]), "height_max_m": float(np.abs(d[:, 2]).max()),
            "forward_final_m": float(d[-1, 0]), "lateral_final_m": float(d[-1, 1]),
            "roll_max_deg": float(np.abs(rpy[:, 0]).max()), "pitch_max_deg": float(np.abs(rpy[:, 1]).max()),
            "yaw_final_deg": float(rpy[-1, 2]), "roll_deg": rpy[:, 0], "pitch_deg": rpy[:, 1], "yaw_deg": rpy[:, 2],
            "height_m": d[:, 2]}


def foot_slip(trace: Trace) -> dict[str, Any]:
    """Per foot and plan-stance interval, the horizontal path length of the foot frame's origin
    while MuJoCo has it on the ground (consecutive ticks both touching), m."""
    per_foot: list[list[float]] = [[] for _ in range(4)]
    if trace.t.size < 2:
        return {"max_m": None, "median_m": None, "per_foot_max_m": [None] * 4}
    step = np.linalg.norm(np.diff(trace.feet[:, :, :2], axis=0), axis=2)  # (N-1, 4)
    on = trace.touching[1:] & trace.touching[:-1]
    for i in range(4):
        inside = np.array([i in s for s in trace.stance])
        k = 0
        while k < inside.size:
            if not inside[k]:
                k += 1
                continue
            end = k
            while end < inside.size and inside[end]:
                end += 1
            per_foot[i].append(float((step[k : end - 1, i] * on[k : end - 1, i]).sum()))
            k = end
    flat = [x for f in per_foot for x in f]
    return {"max_m": max(flat) if flat else None, "median_m": float(np.median(flat)) if flat else None,
            "per_foot_max_m": [max(f) if f else None for f in per_foot]}


def grf_comparison(grf: list[dict], robot_weight: float) -> dict[str, Any]:
    """Per stance kind, of the samples ``grf`` (``run._grf_sample``'s dicts)."""
    out: dict[str, Any] = {}
    for k, kind in STANCE_KINDS.items():
        samples = [s for s in grf if len(s["stance"]) == k]
        matched = [s for s in samples if s["contacts_match"]]
        entry: dict[str, Any] = {"samples": len(samples), "compared": len(matched)}
        if matched:
            diff = np.concatenate([s["paper"] - s["mujoco"] for s in matched])  # (n feet, 3)
            per_sample_rel = [float(np.linalg.norm(s["paper"] - s["mujoco"])) / max(float(np.linalg.norm(s["mujoco"])), 1e-9)
                              for s in matched]
            norms = np.linalg.norm(diff, axis=1)
            entry.update({"diff_median_N": float(np.median(norms)), "diff_max_N": float(norms.max()),
                          "relative_median": float(np.median(per_sample_rel)),
                          "relative_max": float(np.max(per_sample_rel)),
                          "diff_xyz_median_N": np.median(np.abs(diff), axis=0).tolist(),
                          "weight_N": robot_weight})
        out[kind] = entry
    return out


def saturation(trace: Trace, plant: Plant, dt: float) -> dict[str, Any]:
    over = np.abs(trace.tau) > plant.effort[None, :]
    any_over = over.any(axis=1) if over.size else np.zeros(0, dtype=bool)
    return {"time_s": float(any_over.sum() * dt), "fraction": float(any_over.mean()) if any_over.size else None,
            "per_joint_s": (over.sum(axis=0) * dt).tolist() if over.size else []}


def compute_time(trace: Trace) -> dict[str, Any]:
    """Per tick, us: the generated-C calls, the QP (wbc), the whole controller tick in Python, the
    rest of it (Python overhead: tick - C - QP), median and 99th percentile; MuJoCo's steps."""
    if not trace.t.size:
        return {}
    qp = trace.qp_ns if trace.qp_ns is not None and trace.qp_ns.size == trace.t.size else np.zeros(trace.t.size)
    out = {"c_calls_max_us": float(trace.c_ns.max() / 1e3), "tick_python_max_us": float(trace.tick_ns.max() / 1e3),
           "mujoco_steps_median_us": float(np.median(trace.step_ns) / 1e3)}
    for key, ns in (("c_calls", trace.c_ns), ("qp", qp), ("tick_python", trace.tick_ns),
                    ("python_overhead", trace.tick_ns - trace.c_ns - qp)):
        out[f"{key}_median_us"] = float(np.median(ns) / 1e3)
        out[f"{key}_p99_us"] = float(np.percentile(ns, 99) / 1e3)
    return out


def summary(trace: Trace, plant: Plant, plan: Plan, dt: float, cycles: int) -> dict[str, Any]:
    """Everything of one run as plain data (numpy arrays for the series under ``series``)."""
    horizon = cycles * plan.gait.period
    duration = float(trace.t[-1] + dt) if trace.t.size else 0.0
    drift = trunk_drift(trace, plan)
    series = {k: drift.pop(k) for k in ("roll_deg", "pitch_deg", "yaw_deg", "height_m") if k in drift}
    return {
        "controller": trace.controller,
        "fell": trace.fell_at is not None,
        "fell_at_s": trace.fell_at,
        "stopped": trace.stopped,
        "qp_infeasible": trace.qp_infeasible,
        "simulated_s": duration,
        "horizon_s": horizon,
        "cycles_up": float(np.floor(duration / plan.gait.period + 1e-9)) if trace.stopped else float(cycles),
        "tracking": tracking(trace),
        "trunk": drift,
        "foot_slip": foot_slip(trace),
        "grf": grf_comparison(trace.grf, plant.robot.total_mass * 9.81),
        "saturation": saturation(trace, plant, dt),
        "compute": compute_time(trace),
        "series": series,
    }
