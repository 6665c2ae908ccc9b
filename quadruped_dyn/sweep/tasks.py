"""A sweep's tasks: independent, pure, keyed by content (the robot's URDF hash, the task kind, its
options, its seed or perturbation sample), and what each computes on a worker.

* ``check``: every term against Pinocchio on ``states`` random states (``checks.terms``; library
  "quadruped_dyn" in the row's terms) and the full-coordinate terms of each reference library against
  Pinocchio (``checks.cross_library``; "pinocchio" there is Pinocchio as it loads the URDF itself); one task
  per robot and seed.
* ``codegen``: generate the checked C (``checks.check_program_values``), build it with the Makefile and run its
  check program against Pinocchio's reference values; one task per robot and precision.
* ``validate``: the paper's experiment (``experiment.paper_experiment``); one task per robot and gait.
* ``control``: one closed-loop run (``control``) of one controller on the plant perturbed by run k's
  sample (``sampling``): fall, time to fall, the first warning sign (``control.thresholds``), tracking,
  the GRF model's difference from MuJoCo's forces; one task per robot, gait, controller and run.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from quadruped_dyn.sweep.robots import RobotRef, materialise
from quadruped_dyn.sweep.sampling import sample
from quadruped_dyn.sweep.spec import SweepSpec

KINDS = ("check", "codegen", "validate", "control")


@dataclass(frozen=True)
class Task:
    kind: str
    robot: RobotRef
    options: dict[str, Any] = field(hash=False)  # plain JSON values
    key: str = ""

    @staticmethod
    def make(kind: str, robot: RobotRef, options: dict[str, Any]) -> Task:
        content = json.dumps({"kind": kind, "robot_sha256": robot.sha256, "options": options}, sort_keys=True)
        return Task(kind, robot, options, f"{kind}-{hashlib.sha256(content.encode()).hexdigest()[:24]}")


def sweep_tasks(spec: SweepSpec, robots: list[RobotRef]) -> list[Task]:
    """Every task of the sweep, robots outermost; keys are unique (the same content is one task)."""
    tasks: list[Task] = []
    for r in robots:
        for kind, o in spec.tasks.items():
            if kind == "check":
                tasks += [Task.make(kind, r, {"states": o["states"], "seed": o["seed"] + k, "libraries": list(o["libraries"])})
                          for k in range(o["repeats"])]
            elif kind == "codegen":
                tasks += [Task.make(kind, r, {"precision": p}) for p in o["precisions"]]
            elif kind == "validate":
                tasks += [Task.make(kind, r, {"gait": g, "cycles": o["cycles"]}) for g in o["gaits"]]
            else:
                for gait in o["gaits"]:
                    for run in range(o["runs"]):
                        p = sample(o["perturbations"], o["seed"], run)
                        tasks += [Task.make(kind, r, {"gait": gait, "controller": c, "cycles": o["cycles"], "run": run,
                                                      "perturbation": p}) for c in o["controllers"]]
    return list({t.key: t for t in tasks}.values())


# ---------------------------------------------------------------------------------------------- check
def _check(robot: Any, o: dict[str, Any]) -> dict[str, Any]:
    from quadruped_dyn.checks.cross_library import run_cross_library
    from quadruped_dyn.checks.terms import run_check
    from quadruped_dyn.tolerances import REL_TOL_TERMS

    report = run_check(robot, o["states"], o["seed"])
    terms: list[dict[str, Any]] = [{"library": "quadruped_dyn", "term": t.name, "err": t.max_rel_err, "tol": t.tol,
                                    "passed": t.passed, "explained_by": []} for t in report.terms]
    terms += [{"library": "quadruped_dyn", "term": f"GRF {g.stance} {g.model}", "err": g.max_err_vs_pinocchio,
               "tol": REL_TOL_TERMS, "passed": g.passed, "explained_by": []} for g in report.grf]
    passed = report.passed
    not_compared: dict[str, str] = {}
    if o["libraries"]:
        cross = run_cross_library(robot, o["libraries"], o["states"], o["seed"])
        terms += [{"library": c.library, "term": c.term, "err": c.max_rel_err, "tol": c.tol, "passed": c.passed,
                   "explained_by": list(c.explained_by)} for c in cross.results]
        not_compared, passed = dict(cross.not_compared), passed and cross.passed
    worst = max((t["err"] for t in terms), default=0.0)
    return {"passed": passed, "worst_rel_err": worst, "build_s": report.build_seconds, "terms": terms,
            "not_compared": not_compared}


# -------------------------------------------------------------------------------------------- codegen
_LINE = re.compile(r"^(\S+)\s+max rel err vs Pinocchio ([-+.\deEinfa]+)(?: \(tol ([-+.\deE]+)\) (\w+))?", re.M)
_TOTAL = re.compile(r"^(\d+) passed, (\d+) failed(?:, (\d+) skipped)?$", re.M)


def _codegen(robot: Any, o: dict[str, Any]) -> dict[str, Any]:
    from quadruped_dyn.checks.check_program_values import generate_checked

    program = "check_qd" if o["precision"] == "double" else "check_qd_float"
    with tempfile.TemporaryDirectory(prefix="qd-sweep-") as tmp:
        t0 = time.perf_counter()
        files = generate_checked(robot, Path(tmp), o["precision"])
        t1 = time.perf_counter()
        subprocess.run(["make", "-C", tmp, "-j1", f"build/{program}"], capture_output=True, text=True, check=True)
        t2 = time.perf_counter()
        run = subprocess.run([str(Path(tmp) / "build" / program)], capture_output=True, text=True, check=False)
        t3 = time.perf_counter()
        code_bytes = sum(p.stat().st_size for p in files.c_sources)
    total = _TOTAL.search(run.stdout)
    lines = [{"function": m[0], "err": float(m[1]), "tol": float(m[2]) if m[2] else None, "passed": m[3] == "pass"}
             for m in _LINE.findall(run.stdout)]
    passed_n, failed_n, skipped_n = (int(x or 0) for x in total.groups()) if total else (0, 0, 0)
    return {"passed": run.returncode == 0 and total is not None and failed_n == 0, "functions_passed": passed_n,
            "functions_failed": failed_n, "functions_skipped": skipped_n, "exit_code": run.returncode,
            "worst_rel_err": max((x["err"] for x in lines), default=None), "generate_s": t1 - t0, "compile_s": t2 - t1,
            "check_s": t3 - t2, "c_source_bytes": code_bytes, "functions": lines,
            "output_tail": run.stdout[-600:] if run.returncode else ""}


# ------------------------------------------------------------------------------------------- validate
def _validate(robot: Any, o: dict[str, Any]) -> dict[str, Any]:
    from quadruped_dyn.experiment.gait import GAITS
    from quadruped_dyn.experiment.paper_experiment import report, run_experiment, static_stability
    from quadruped_dyn.experiment.simulate import reduced_dynamics

    gait, dt = GAITS[o["gait"]], 1e-3
    horizon = o["cycles"] * gait.period
    exp = run_experiment(robot, gait, reduced_dynamics(robot, "c"), horizon, dt)
    data = report(exp, "dop853", dt, "c", static_stability(exp.plan, exp.ik, horizon))
    worst = data["max_pct_err_overall"]
    return {"passed": None, "max_pct_err_q": worst["q"], "max_pct_err_qd": worst["qd"], "max_pct_err_qdd": worst["qdd"],
            "growth_rate_per_s": data["instability"]["growth_rate_per_s"], "compared_samples": data["compared_samples"],
            "report": data}


# -------------------------------------------------------------------------------------------- control
def _plant_parts(p: dict[str, Any]) -> tuple[dict[str, Any], Any, tuple[float, float, float, float] | None]:
    """(PlantOptions keywords, Perturbation, the run's push (t s, impulse x y z N s) or None) of one run's sample."""
    from quadruped_dyn.control.perturbations import Perturbation

    plant = {k: v for k, v in (("mu", p.get("mu")), ("foot_radius", p.get("foot_radius_m"))) if v is not None}
    if p.get("step_height_m"):
        plant["ground_step"] = (float(p.get("step_x_m", 0.0)), float(p["step_height_m"]))
    both = p.get("mass_scale", 1.0)
    vec = {name: tuple(float(p.get(f"{name}_{axis}_{unit}", 0.0)) for axis in "xyz")
           for name, unit in (("payload_offset", "m"), ("push", "N_s"))}
    x, y, z = vec["push"]
    push = (float(p.get("push_at_s", 0.0)), x, y, z) if any(vec["push"]) else None
    return plant, Perturbation(trunk_mass_scale=both * p.get("trunk_mass_scale", 1.0),
                               link_mass_scale=both * p.get("link_mass_scale", 1.0), payload_kg=p.get("payload_kg", 0.0),
                               payload_offset_m=vec["payload_offset"],  # type: ignore[arg-type]
                               imu_noise_rad_s=p.get("imu_noise_rad_s", 0.0), imu_noise_rad=p.get("imu_noise_rad", 0.0),
                               imu_delay_ticks=p.get("imu_delay_ticks", 0),
                               seed=int(hashlib.sha256(json.dumps(p, sort_keys=True).encode()).hexdigest()[:8], 16)), push


def control_study(robot: Any, o: dict[str, Any]) -> Any:
    """The closed-loop study of a ``control`` task's options ``o``, not run: the plant perturbed by the sample,
    the sample's push on the run's clock (``LoopOptions.push``: at ``push_at_s`` after the settled start)."""
    from quadruped_dyn.control.closed_loop import prepare
    from quadruped_dyn.control.perturbations import perturbed
    from quadruped_dyn.control.plant import PlantOptions
    from quadruped_dyn.control.run import LoopOptions

    plant_options, perturbation, push = _plant_parts(o["perturbation"])
    study = prepare(robot, o["gait"], [o["controller"]], loop=LoopOptions(cycles=o["cycles"], push=push),
                    plant_options=PlantOptions(**plant_options))
    study.plant = perturbed(study.plant, perturbation)
    return study


def _control(robot: Any, o: dict[str, Any]) -> dict[str, Any]:
    from quadruped_dyn.control.closed_loop import run_all
    from quadruped_dyn.control.thresholds import first_crossings
    from quadruped_dyn.errors import NumericalError

    study = control_study(robot, o)
    try:
        run_all(study)
    except NumericalError as e:  # the perturbed robot did not stand: a fall before the first step
        return {"passed": None, "fell": True, "time_to_fall_s": 0.0, "first_sign": "did not stand", "stopped": str(e)}
    r = study.results[o["controller"]]
    signs = first_crossings(study.traces[o["controller"]], study.plant.effort, robot.total_mass * 9.81,
                            1.0 / study.loop.rate_hz)
    grf = {k: v.get("relative_median") for k, v in r["grf"].items()}
    return {"passed": None, "fell": r["fell"], "time_to_fall_s": r["fell_at_s"], "stopped": r["stopped"],
            "cycles_up": r["cycles_up"], "first_sign": signs["first"], "first_sign_at_s": signs["first_at_s"],
            "signs_at_s": signs["crossed"], "tracking_rms_rad": r["tracking"]["rms_rad"],
            "tracking_max_rad": r["tracking"]["max_rad"], "grf_relative_median": grf,
            "saturation_s": r["saturation"]["time_s"], "foot_slip_max_m": r["foot_slip"]["max_m"]}


RUNNERS = {"check": _check, "codegen": _codegen, "validate": _validate, "control": _control}


def compute(task: Task) -> dict[str, Any]:
    """The task's metrics on this worker (raises what the work raises)."""
    robot = materialise(task.robot)
    return RUNNERS[task.kind](robot, task.options)
