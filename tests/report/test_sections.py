"""The report's sections as a reader sees them, rendered from plain data (no report is built):
the experiment's runs, error budget, static stability and physics check are tables, not dumps
of nested dicts; the cross-library comparison is a table with the model diagnosis; the
generated-C table lists every function with its check against Pinocchio. And the two gatherers
behind item 5: the cross-library comparison runs when the extras are installed, and a generated
function's check covers the reduced ones."""

from __future__ import annotations

import importlib.util
import re

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.report import sections as rs
from quadruped_dyn.tolerances import REL_TOL_TERMS

JOINTS = [f"{leg} {role}" for leg in ("FL", "FR", "BL", "BR") for role in ("HAA", "HFE", "KFE")]


def departure(d: float, t: float | None) -> dict[str, object]:
    return {"max_joint_angle_diff_rad": d, "time_to_1pct_s": t}


#: A validation JSON with the keys experiment.paper_experiment.report writes.
VALIDATION = {
    "robot": "paper", "gait": "walk", "horizon_s": 2.4, "backend": "c", "integrator": "DOP853 (scipy), rtol = atol = 1e-13",
    "max_pct_err": {n: {"q": 1e-6, "qd": 2e-6, "qdd": 3e-6} for n in JOINTS},
    "max_pct_err_overall": {"q": 6.2e-6, "qd": 5.6e-5, "qdd": 4.7e-4},
    "instability": {"growth_rate_per_s": 7.1, "one_ulp_grows_to_rad": 2.4e-9,
                    "error_budget": {s: {"total_pct": 4.7e-4, "roundoff_pct": 2.6e-4, "truncation_pct": 7.0e-4}
                                     for s in ("q", "qd", "qdd")}},
    "static_stability": {"min_fz_N": 4.6, "min_fz_at_s": 0.3, "weight_N": 98.1, "min_com_margin_m": 0.0205,
                         "min_com_margin_at_s": 0.6},
    "runs": {name: {"stopped_at_s": None, "departs_1pct_at_s": None, "max_closure_m": 3e-16, "rhs_evaluations": 175,
                    "max_pct_err_q": 1e-6, "max_pct_err_qd": 2e-6, "max_pct_err_qdd": 3e-6}
             for name in ("paper", "twin", "refined")},
    "physics_check": {
        "departure_threshold_pct_of_max_joint_angle": 1.0, "max_joint_angle_rad": 1.57,
        "ik": {"torques": "id_r's joint torques (roll unactuated)", "rigid_vs_reduced": {**departure(1.4e-7, None),
               "over_time": [[0.0, 0.0], [0.1, 1e-9]]}, "rigid_vs_ik": departure(7.0e-8, None),
               "reduced_vs_ik": departure(6.0e-8, None), "rigid_stopped_at_s": None, "reduced_stopped_at_s": None},
        "plus_1pct": {"torques": "1.01 x id_r's joint torques", "rigid_vs_reduced": departure(0.3, 0.38),
                      "rigid_vs_ik": departure(0.4, 0.2), "reduced_vs_ik": departure(0.5, 0.25), "rigid_stopped_at_s": 0.7,
                      "reduced_stopped_at_s": 0.72},
    },
}


def tables(html: str) -> list[str]:
    return re.findall(r"<table.*?</table>", html, flags=re.S)


def table_with(html: str, header: str) -> str:
    found = [t for t in tables(html) if f"<th>{header}</th>" in t]
    assert found, f"no table with a column '{header}'"
    return found[0]


def rows_of(table_html: str) -> list[str]:
    return re.findall(r"<tr>(.*?)</tr>", table_html.split("<tbody>")[1], flags=re.S)


def test_experiment_tables_are_tables():
    section = rs.experiment_section({"walk": VALIDATION}, JOINTS, {})
    body = section.body
    budget = table_with(body, "round-off %")
    assert len(rows_of(budget)) == 3 and "q̈" in budget
    physics = table_with(body, "rigid vs reduced: max rad")
    assert len(rows_of(physics)) == 2
    assert "1.01 x id_r&#x27;s joint torques" in physics and "0.38" in physics and "never" in physics
    runs = table_with(body, "1 % off IK at s")
    assert len(rows_of(runs)) == 3 and "ran to the end" in runs
    assert "2.05 cm" in table_with(body, "static stability of the plan")
    for raw_key in ("error_budget", "rigid_vs_reduced", "time_to_1pct_s", "min_com_margin_m", "max_closure_m"):
        assert raw_key not in body, f"the JSON key '{raw_key}' is dumped instead of rendered"
    assert "<table><thead><tr><th></th><th></th>" not in body  # no key/value dump of a nested dict
    assert section.verdict == "result" and "7.1 /s" in body


def test_unknown_experiment_keys_still_show():
    v = {**VALIDATION, "physics_check": {**VALIDATION["physics_check"], "new_measure": 0.5},
         "instability": {**VALIDATION["instability"], "new_rate": 1.0}}
    body = rs.experiment_section({"walk": v}, JOINTS, {}).body
    assert "new_measure" in body and "new_rate" in body


CROSS = {
    "cross_library": [{"library": lib, "term": term, "max_rel_err": 2e-15, "max_rel_err_vs_quadruped_dyn": 3e-15,
                       "max_rel_err_same_model": 2e-15, "model_change": 0.0, "explained_by": [], "tol": REL_TOL_TERMS,
                       "passed": True}
                      for lib in ("mujoco", "idyntree") for term in ("M", "C + G", "G", "foot Jacobians")],
    "model_changes": [{"library": "mujoco", "kind": "merged_inertial", "links": ["base"], "detail": "dummy base merged",
                       "in_comparison": True, "size": {"M": 3e-18}}],
    "cross_library_passed": True, "cross_library_samples": 20, "cross_library_note": "",
}
CHECK = {"samples": 2, "seed": 0, "passed": True, "build_seconds": 0.1, "grf": [],
         "terms": [{"name": "M_full", "max_abs_err": 1e-14, "max_rel_err": 1e-15, "tol": REL_TOL_TERMS, "passed": True}]}


def test_cross_library_table_and_diagnosis():
    section = rs.terms_section({**CHECK, **CROSS})
    table = table_with(section.body, "vs quadruped_dyn")
    assert len(rows_of(table)) == 8 and "idyntree" in table
    assert "merged_inertial" in table_with(section.body, "what it does to the URDF")
    assert section.verdict == "pass"
    failed = {**CROSS, "cross_library_passed": False}
    failed["cross_library"] = [{**CROSS["cross_library"][0], "max_rel_err": 1e-3, "passed": False}]
    assert rs.terms_section({**CHECK, **failed}).verdict == "FAIL"


def test_cross_library_absent_says_why():
    body = rs.terms_section({**CHECK, "cross_library_note": "not installed: mujoco (pip install 'quadruped_dyn[xlib]')"}).body
    assert "not available" in body and "quadruped_dyn[xlib]" in body


def test_generated_c_lists_every_function_with_its_check():
    names = ["qd_M_full", "qd_grf_FL_BR", "qd_M_r_FL_BR", "qd_fd_r_BL_BR"]
    gen = {"directory": "c", "files": [{"name": "qd_paper.c", "bytes": 1000}], "compile_s": 1.0, "library_bytes": 10,
           "functions": [{"name": n, "inputs": "q[19]", "outputs": "M[18x18]", "instructions": 1, "iw": 0, "w": 1}
                         for n in names],
           "checks": [{"name": n, "max_rel_err": 1e-14, "tol": 1e-10, "status": "pass", "note": ""} for n in names[:3]]
           + [{"name": names[3], "max_rel_err": 1e-4, "tol": 0.05, "status": "skipped", "note": "cond x eps leaves < 2 digits"}]}
    section = rs.generated_c_section(gen, None, "skipped with --fast")
    table = table_with(section.body, "rel err vs Pinocchio")
    assert len(rows_of(table)) == 4 and all(n in table for n in names)
    assert section.verdict == "pass" and "4 functions" in section.headline
    assert "3 pass vs Pinocchio, 1 skipped" in section.headline
    bench = {"robot": "paper", "entries": [{"name": "M_full", "generated_ns": 1.0, "pinocchio_ns": 4.0, "ratio": 0.25,
                                            "target": 0.4},
                                           {"name": "fd_r_FL_BR", "generated_ns": 4.0, "pinocchio_ns": 10.0, "ratio": 0.4,
                                            "target": 0.25},
                                           {"name": "id_r_FL_BR", "generated_ns": 4.0, "pinocchio_ns": 1.0, "ratio": 4.0}]}
    timed = rs.generated_c_section(gen, bench)  # the checks pass; the headline says a speed target is missed
    assert timed.verdict == "pass" and "speed targets met 1 of 2" in timed.headline, timed.headline
    parametric = {"M_full": {"parametric_ns": 350.0, "fixed_ns": 170.0, "pinocchio_ns": 760.0, "vs_pinocchio": 0.46,
                             "vs_fixed": 2.06}}
    rows = rows_of(table_with(rs.generated_c_section(gen, {**bench, "parametric": parametric}).body, "parametric ns"))
    assert len(rows) == 1 and "0.46" in rows[0] and "2.06" in rows[0], rows
    unchecked = {**gen, "checks": gen["checks"][:2]}  # a function without its check does not pass
    assert rs.generated_c_section(unchecked, None).verdict == "FAIL"


@pytest.mark.skipif(any(importlib.util.find_spec(p) is None for p in ("mujoco", "idyntree", "pydrake", "adam")),
                    reason="the xlib extra (mujoco, idyntree, drake, adam) is not installed")
def test_report_runs_cross_library_when_installed(paper, monkeypatch):
    from quadruped_dyn.report import gather

    monkeypatch.setattr(gather, "CROSS_LIBRARY_SAMPLES", 2)
    data = gather.cross_library(paper)
    assert {r["library"] for r in data["cross_library"]} == {"pinocchio", "mujoco", "idyntree", "drake", "adam"}
    assert data["cross_library_passed"] is True and data["cross_library_note"] == ""
    html = rs.cross_library_html({**CHECK, **data})
    assert "not available" not in html and "adam: inverse dynamics (adam has no inverse dynamics" in html


@pytest.mark.parametrize("name", ["M_full", "id_full", "grf_FL_FR_BL_BR", "M_r_FL_BR", "CG_r_FR_BL_BR", "fd_r_FL_FR_BL_BR",
                                  "id_r_FR_BL"])
def test_generated_function_check_against_pinocchio(paper, name):
    """The report's check of one compiled function (full-coordinate, GRF and reduced alike)."""
    from quadruped_dyn.checks.check_program_values import reference_state
    from quadruped_dyn.codegen.emit import PREFIX
    from quadruped_dyn.codegen.library import compiled_library
    from quadruped_dyn.report.gather import c_function_check

    library = compiled_library(paper)
    f = ca.external(PREFIX + name, str(library.path))
    row = c_function_check(paper, library, f, reference_state(paper))
    assert row["status"] == "pass", row
    assert np.isfinite(row["max_rel_err"]) and row["max_rel_err"] <= row["tol"]


def test_a_footprint_not_measured_says_how_to_get_it(tmp_path):
    """Without ``report --footprint`` there is no cross build: the page says so and how to ask for it
    (caller memory is still listed)."""
    from click.testing import CliRunner

    from quadruped_dyn.cli import main
    from quadruped_dyn.report.gather import FOOTPRINT_NOT_MEASURED

    html = rs.embedded_html({"footprint": {"skipped": FOOTPRINT_NOT_MEASURED}})
    assert "not measured in this run: pass --footprint" in html
    assert "--footprint" in CliRunner().invoke(main, ["report", "--help"]).output


def test_a_time_that_never_came_reads_as_such():
    """A run that never left the plan by 1 % or never fell has None times: the summary and the
    optimised trot's headline say 'never' / 'ran to the end', not 'None s' or 'n/a s'."""
    from quadruped_dyn.experiment.validation_files import summary_text

    data = {**VALIDATION, "runs": {"paper": {**VALIDATION["runs"]["paper"], "departs_1pct_at_s": 0.5},
                                   "plus_1pct": {**VALIDATION["runs"]["paper"], "stopped_at_s": 0.7}}}
    text = summary_text(data, JOINTS, [])
    assert "run paper: 1 % off IK at 0.500 s, ran to the end" in text, text
    assert "run plus_1pct: 1 % off IK never, stopped (fell) at 0.700 s" in text, text
    assert "None" not in text, text
    trot = {"status": "Solve_Succeeded", "iterations": 40, "solve_seconds": 30.0, "constraint_violation": 1e-9,
            "converged": True, "effort": {"max_roll_moment_optimised_Nm": 1e-9, "max_roll_moment_plan_Nm": 2.1, "ratio": 0.9},
            "formulation": {"nodes": 40, "variables": 1000, "constraints": 900, "mu": 0.6, "fz_min_N": 1.0},
            "rigid_contact_replay": {"time_to_1pct_s": None, "horizon_s": 2.0, "growth_rate_per_s": None}}
    section = rs.optimal_control_section(trot)
    assert "replay within 1 % for all 2 s" in section.headline, section.headline
    departed = rs.optimal_control_section(
        {**trot, "rigid_contact_replay": {**trot["rigid_contact_replay"], "time_to_1pct_s": 0.83}})
    assert "replay 1 % off at 0.83 s" in departed.headline, departed.headline
    assert "n/a s" not in section.headline and "n/a s" not in section.body
