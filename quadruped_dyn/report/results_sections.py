"""The sections of ``docs/results.md`` (``report.results_page``), each a function of (robots, samples) returning
(the command that measures it, its Markdown): every number in a section's text is computed here from that command's
results, so a rerun rewrites all of them."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from quadruped_dyn.errors import InputError

if TYPE_CHECKING:
    from quadruped_dyn.references.interface import ModelChange

#: The full-coordinate functions whose graph operations the generated-c section counts.
OPERATION_FUNCTIONS: tuple[str, ...] = ("M_full", "C_full", "nle_full", "id_full", "G_full")


def _prose(text: str) -> str:
    return "\n".join(textwrap.wrap(text, 118, break_on_hyphens=False))


def _label(name: str) -> str:
    return f"{name} (by path)" if name == "b1" else name


def robot_path(name: str) -> str:
    """A built-in robot's name as it is, ``b1`` as its example-robot-data URDF path."""
    if name != "b1":
        return name
    from quadruped_dyn.model import example_robot_data_dir

    return str(Path(example_robot_data_dir()) / "b1_description" / "urdf" / "b1.urdf")


def terms_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of every term against Pinocchio, one row per robot."""
    from quadruped_dyn.checks.terms import run_check
    from quadruped_dyn.model.robot import load_robot

    rows = []
    for name in robots:
        report = run_check(load_robot(robot_path(name)), samples, 0)
        full = [t for t in report.terms if not re.search(r"_r |^d", t.name)]
        reduced = [t for t in report.terms if "_r " in t.name]
        derivatives = [t for t in report.terms if t.name.startswith(("did_", "dfd_"))]
        worst_reduced = max(reduced, key=lambda t: t.max_rel_err)
        rows.append(f"| {name}{' (by path)' if name == 'b1' else ''} | {'pass' if report.passed else 'FAIL'} "
                    f"| {max(t.max_rel_err for t in full):.1e} "
                    f"| {worst_reduced.max_rel_err:.1e} ({worst_reduced.name}) "
                    f"| {max(t.max_rel_err for t in derivatives):.1e} "
                    f"| {max(g.max_err_vs_reference for g in report.grf):.1e} "
                    f"| {max(g.max_err_vs_pinocchio for g in report.grf):.1e} "
                    f"| {max(g.max_cond for g in report.grf):.1e} |")
    command = f"`quadruped-dyn check ROBOT --samples {samples} --json` (seed 0)"
    table = ["| robot | result | full-coordinate terms | reduced terms (worst) | derivatives | GRF vs SVD "
             "| GRF vs Pinocchio | largest cond(A) |", "|---|---|---|---|---|---|---|---|", *rows]
    prose = (f"{command}; tolerance 1e-10 for the terms, 1e-9 for the derivatives (`tolerances.py`). Worst relative "
             f"error over the {samples} states; the full-coordinate terms are M_full (three ways), C_full, G_full, the "
             "Coriolis matrix, id_full and the foot kinematics; the reduced ones id_r, M_r, C_r, G_r of four stance "
             "sets; the derivatives did_full and dfd_full against Pinocchio's analytical ones; the GRF columns cover 16 "
             "stance sets × 2 models. The reduced terms carry the conditioning of the maps and of the GRF solve, hence "
             "their larger errors; the GRF ranks are 5 / 6 / 5 with four / three / two feet.")
    text = "\n".join(textwrap.wrap(prose, 118, break_on_hyphens=False)) + "\n\n" + "\n".join(table) + "\n"
    return command, text


def _changes(changes: Sequence[ModelChange]) -> str:
    """What the libraries did to the model, one clause per change (``references.interface.ModelChange``)."""
    parts = []
    for c in changes:
        links = ", ".join(c.links[:3]) + (f" +{len(c.links) - 3}" if len(c.links) > 3 else "")
        size = f", M changes {c.size['M']:.1e}" if "M" in c.size else ""
        used = "" if c.in_comparison else ", not compared"
        parts.append(f"{c.library} {c.kind}{f' ({links})' if c.links else ''}{size}{used}")
    return "; ".join(parts) or "nothing"


def against_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of the same URDF through MuJoCo and iDynTree against Pinocchio, one row per robot."""
    from quadruped_dyn.checks.cross_library import parse_libraries, run_cross_library
    from quadruped_dyn.model.robot import load_robot

    libraries = parse_libraries("mujoco,idyntree")
    n = min(samples, 20)
    rows = []
    for name in robots:
        report = run_cross_library(load_robot(robot_path(name)), libraries, n, 0)
        worst = {lib: max((r.max_rel_err for r in report.results if r.library == lib), default=float("nan"))
                 for lib in libraries}
        rows.append(f"| {name}{' (by path)' if name == 'b1' else ''} | {'pass' if report.passed else 'FAIL'} | "
                    + " | ".join(f"{worst[lib]:.1e}" for lib in libraries) + f" | {_changes(report.changes).replace('|', '/')} |")
    command = f"`quadruped-dyn check ROBOT --against mujoco,idyntree --samples {n}` (seed 0)"
    prose = (f"{command}: M, C + G, G and the foot Jacobians of the same URDF through MuJoCo and iDynTree, largest "
             "relative error against Pinocchio over the terms; a difference the diagnosed model changes explain passes "
             "(conventions.md §10).")
    note = ("Errors of ~1e-12 where a URDF writes right angles with ten digits (1.5707963268: hyq, anymal_c) are the "
            "toolkit's snapping of placements (`SNAP_TOL` = 1e-9, moving the model by ~5e-12 rad); MuJoCo and iDynTree, "
            "both reading the raw numbers, agree with each other to round-off there. A change that is not compared "
            "(MuJoCo's own `balanceinertia` or `inertiafromgeom`) is what the library would do unasked, and its size.")
    table = ["| robot | result | MuJoCo | iDynTree | what the libraries did to the model |", "|---|---|---|---|---|", *rows]
    wrap = "\n".join
    return command, (wrap(textwrap.wrap(prose, 118, break_on_hyphens=False)) + "\n\n" + wrap(table) + "\n\n"
                     + wrap(textwrap.wrap(note, 118, break_on_hyphens=False)) + "\n")


def conditioning_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of the reduced model's conditioning per robot: cond(M_r) over the regular stance sets of
    2, 3 and 4 feet at the gait posture (trunk level, still), M_r against Pinocchio's, the singular sets."""
    from quadruped_dyn.experiment.gait import gait_posture
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.report.gather import reduced_rows

    del samples  # one posture per robot
    rows = []
    for name in robots:
        robot = load_robot(robot_path(name))
        found = reduced_rows(robot, gait_posture(robot))
        regular = [r for r in found if not r.get("singular")]
        singular = [r["stance"] for r in found if r.get("singular")]
        if not regular:
            raise InputError(f"{name}: no regular stance set at the gait posture")
        conds = [r["cond"] for r in regular]
        rows.append(f"| {_label(name)} | {len(regular)} | {min(conds):.1e} – {max(conds):.1e} "
                    f"| {max(r['err_vs_pinocchio'] for r in regular):.1e} | {', '.join(singular) or 'none'} |")
    command = "`quadruped-dyn report ROBOT --fast` (its reduced-model section: `report.gather.reduced_rows`)"
    prose = (f"{command}: M_r of every stance set of 2, 3 or 4 feet at the gait posture, trunk level and still; its "
             "condition number over the regular sets, and M_r against the reduced model built from Pinocchio's foot "
             "quantities. The front and back pairs (FL+FR, BL+BR) leave the trunk's pitch about the lateral "
             "foot-to-foot line free, which the paper's coordinates (joints + roll) cannot describe (formulation.md §5): "
             "their M_r is singular on every robot.")
    table = ["| robot | regular stance sets | cond(M_r) | M_r vs Pinocchio | singular |", "|---|---|---|---|---|", *rows]
    return command, _prose(prose) + "\n\n" + "\n".join(table) + "\n"


def operations_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of the arithmetic operations of the generated full-coordinate functions per robot."""
    from quadruped_dyn.bench.call_cost import arithmetic_operations
    from quadruped_dyn.codegen.emit import codegen_function
    from quadruped_dyn.model.robot import load_robot

    del samples
    rows = []
    for name in robots:
        robot = load_robot(robot_path(name))
        counts = [arithmetic_operations(codegen_function(robot, f)) for f in OPERATION_FUNCTIONS]
        rows.append(f"| {_label(name)} | " + " | ".join(str(c) for c in counts) + " |")
    command = "`quadruped-dyn codegen ROBOT` (the graphs' operations: `bench.call_cost.arithmetic_operations`)"
    prose = (f"{command}: the operations of each generated full-coordinate function (CasADi instructions less inputs, "
             "outputs and constants), built in each leg's canonical frames (`model/leg_frames.py`), so the cost does "
             "not depend on how a URDF places its frames. Their speed against Pinocchio, per robot and function, is "
             "on [benchmark](benchmark.md).")
    table = ["| robot | " + " | ".join(OPERATION_FUNCTIONS) + " |", "|---" * (len(OPERATION_FUNCTIONS) + 1) + "|", *rows]
    return command, _prose(prose) + "\n\n" + "\n".join(table) + "\n"


def validation(name: str, gait: str) -> dict[str, Any]:
    """``quadruped-dyn validate ROBOT --gait GAIT --json`` run as a user runs it, its JSON."""
    with tempfile.TemporaryDirectory(prefix="qd-results-") as out:
        proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "validate", robot_path(name), "--gait", gait,
                               "--json", "--out", out], capture_output=True, text=True, timeout=1800)
    if proc.returncode not in (0, 1) or not proc.stdout.strip():  # 1: a check failed, the JSON says which
        raise InputError(f"validate {name} --gait {gait} exited {proc.returncode}: {proc.stderr.strip()[-300:]}")
    result: dict[str, Any] = json.loads(proc.stdout)
    return result


def _validation_row(name: str, gait: str, v: dict[str, Any]) -> str:
    err, budget = v["max_pct_err_overall"], v["instability"]["error_budget"]["qdd"]
    stab = v["static_stability"]
    margin = stab.get("min_com_margin_m")
    return (f"| {_label(name)}, {gait} | {v['horizon_s']:g} s | {err['q']:.1e} | {err['qd']:.1e} | {err['qdd']:.1e} "
            f"| {v['instability']['growth_rate_per_s']:.1f} | {budget['roundoff_pct']:.1e} / {budget['truncation_pct']:.1e} "
            f"| {stab['min_fz_N']:.3g} N of {stab['weight_N']:.3g} N "
            f"| {'— (two feet)' if margin is None else f'{100 * margin:.2f} cm'} |")


def _departure(pair: dict[str, Any], threshold: float) -> str:
    t = pair.get("time_to_1pct_s")
    return f"{pair['max_joint_angle_diff_rad']:.1e} rad, never {threshold:g} %" if t is None else f"{threshold:g} % at {t:.2f} s"


def _physics_rows(walk: dict[str, Any], trot: dict[str, Any]) -> list[str]:
    rows = []
    for case in walk["physics_check"]:
        w, t = walk["physics_check"][case], trot["physics_check"].get(case)
        if not isinstance(w, dict) or "torques" not in w or not isinstance(t, dict):
            continue
        threshold = walk["physics_check"]["departure_threshold_pct_of_max_joint_angle"]
        rows.append(f"| {w['torques']} | {_departure(w['rigid_vs_reduced'], threshold)} "
                    f"| {_departure(w['rigid_vs_ik'], threshold)} | {_departure(t['rigid_vs_reduced'], threshold)} "
                    f"| {_departure(t['rigid_vs_ik'], threshold)} |")
    return rows


def experiment_section(robots: Sequence[str], samples: int) -> tuple[str, str]:
    """(command, Markdown) of the paper's experiment: every robot's walk and the paper robot's trot against the IK
    plan, with the error budget and static stability, and the paper robot's physics check."""
    del samples
    runs = {(name, gait): validation(name, gait) for name in robots
            for gait in (("trot", "walk") if name == "paper" else ("walk",))}
    command = "`quadruped-dyn validate ROBOT --gait trot|walk --json`"
    prose = (f"{command} (native engine, two cycles, the 'paper' run against the IK plan; largest joint, % of its "
             "range; growth rate from the one-ulp twin run; round-off / truncation = the twin run's difference and the "
             "truncation estimated from a run at a 10× looser tolerance, experiment.md §6; static stability: smallest "
             "vertical foot force and the CoM's margin inside the support polygon):")
    table = ["| robot, gait | horizon | q % | q̇ % | q̈ % | growth /s | round-off / truncation (q̈ %) | smallest f_z "
             "| CoM margin |", "|---|---|---|---|---|---|---|---|---|",
             *[_validation_row(name, gait, v) for (name, gait), v in runs.items()]]
    text = _prose(prose) + "\n\n" + "\n".join(table) + "\n"
    if ("paper", "walk") in runs:
        physics = (" **The physics check** (`physics_check` in the JSON): the same torques drive the full-coordinate "
                   "rigid-contact dynamics (experiment.md §5) and the reduced model with the roll unactuated; departure "
                   "= the largest joint-angle difference, against a threshold in % of the largest joint angle of the "
                   "plan. Paper robot:")
        text += ("\n" + _prose(physics.strip()) + "\n\n| torques | walk: rigid vs reduced | walk: rigid vs IK "
                 "| trot: rigid vs reduced | trot: rigid vs IK |\n|---|---|---|---|---|\n"
                 + "\n".join(_physics_rows(runs[("paper", "walk")], runs[("paper", "trot")])) + "\n")
    return command, text
