"""The report's sections: one function per section, each rendering the data of one public API
or JSON (``run_check(...).as_dict()``, the validation JSON, ``run_bench(...).as_dict()``, ...)
into a ``Section``. Renderers only read: a key that is missing (an older or newer producer)
shows as "not available" instead of failing, so a new output is wired in with one line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from quadruped_dyn.math.compare import within
from quadruped_dyn.model.leg import BR_HFE
from quadruped_dyn.report.html import Section, badge, cell, esc, grade, not_available, num, png_image, table


def _finite(*xs: Any) -> bool:
    return all(isinstance(x, (int, float)) and math.isfinite(x) for x in xs)


def _within(err: Any, tol: Any) -> bool:
    """``compare.within`` for values read from JSON: None (a non-finite value) or a non-number never passes."""
    return _finite(err, tol) and within(err, tol)


def generic_table(rows: Sequence[dict[str, Any]], caption: str = "") -> str:
    """Any list of flat dicts (e.g. a section added by another command) as a table."""
    if not rows:
        return not_available(caption or "table")
    columns = list(dict.fromkeys(k for row in rows for k in row))

    def show(x: Any) -> str:
        if isinstance(x, float):
            return num(x, ".3g")
        if isinstance(x, bool) or x is None:
            return {True: "yes", False: "no", None: "n/a"}[x]
        return str(x)

    return table(columns, [[show(row.get(c)) for c in columns] for row in rows], caption)


def data_html(x: Any) -> str:
    """Any JSON value as HTML: a dict as a key/value table (nested values rendered the same
    way), a list of dicts as a table, other lists inline, numbers to 3 digits."""
    if isinstance(x, dict):
        return table(["", ""], [[str(k), cell(data_html(v))] for k, v in x.items()])
    if isinstance(x, list) and x and all(isinstance(r, dict) for r in x):
        return generic_table(x)
    if isinstance(x, list):
        return esc(", ".join(num(v, ".3g") if isinstance(v, float) else str(v) for v in x))
    return num(x, ".3g") if isinstance(x, float) else esc(x)


# ----------------------------------------------------------------------------- the robot


def robot_section(info: dict[str, Any], figure_html: str) -> Section:
    """``info``: ``cli.robot_info`` plus ``joints`` (name, leg, role, lower, upper, standing, rad)
    and ``warnings`` (every message raised while loading the URDF)."""
    legs = info.get("legs", [])
    warnings = info.get("warnings", [])
    rows = [[leg["label"], ", ".join(leg["joints"]), leg["foot_frame"], num(leg["thigh_length_m"], ".3f"),
             num(leg["shank_length_m"], ".3f"), num(sum(leg["link_masses_kg"]), ".3f"),
             " ".join(f"{x:+.3f}" for x in leg["foot_position_standing_m"])] for leg in legs]
    body = [
        f"<p>URDF: <code>{esc(info.get('urdf', '?'))}</code>. Total mass {num(info.get('total_mass_kg'), '.3f')} kg, "
        f"trunk {num(info.get('trunk_mass_kg'), '.3f')} kg. Legs found by tree structure, labelled by the hip's "
        "quadrant in the trunk frame (x forward, y left, z up); joint order FL, FR, BL, BR x (HAA, HFE, KFE).</p>",
        table(["leg", "joints (HAA, HFE, KFE)", "foot frame", "thigh m", "shank m", "mass kg",
               "foot at standing (trunk frame, m)"], rows, "legs"),
    ]
    joints = info.get("joints")
    if joints:
        body.append(table(["joint", "leg", "role", "lower rad", "upper rad", "standing rad"],
                          [[j["name"], j["leg"], j["role"], num(j["lower"], "+.3f"), num(j["upper"], "+.3f"),
                            num(j["standing"], "+.3f")] for j in joints], "joints (project order)"))
    body.append(figure_html)
    body.append("<h3>URDF warnings</h3>")
    body.append("<ul>" + "".join(f'<li class="warn">{esc(w)}</li>' for w in warnings) + "</ul>" if warnings
                else "<p>None: the URDF loaded without a warning.</p>")
    headline = (f"{len(legs)} legs, {sum(len(leg['joints']) for leg in legs)} joints, "
                f"{num(info.get('total_mass_kg'), '.2f')} kg, {len(warnings)} URDF warning(s)")
    return Section("robot", f"The robot: {info.get('name', '?')}", "pass" if len(legs) == 4 else "FAIL", headline,
                   "\n".join(body))


# ----------------------------------------------------------------------------- terms vs Pinocchio


def terms_section(check: dict[str, Any] | None) -> Section:
    """``check``: ``run_check(...).as_dict()``; an optional ``cross_library`` list (other
    libraries as references) is shown as it comes."""
    if not check:
        return Section("terms", "Every term against Pinocchio", "not available", "not run", not_available("the check"))
    terms = check.get("terms", [])
    rows = [[t["name"], num(t["max_abs_err"]),
             cell(num(t["max_rel_err"]), grade(t["max_rel_err"], t["tol"])), num(t["tol"], ".0e"),
             cell(badge("pass" if t["passed"] else "FAIL"))] for t in terms]
    # a non-finite error (NaN/inf, None once through JSON) is the worst of all: shown, never raised on
    worst = max((t["max_rel_err"] if _finite(t["max_rel_err"]) else float("inf") for t in terms), default=float("nan"))
    ok = bool(check.get("passed")) and all(_finite(t["max_rel_err"]) for t in terms)
    body = [
        f"<p>{check.get('samples')} random states (seed {check.get('seed')}): joint angles inside limits, random "
        "orientation, velocities, accelerations and foot forces. Relative error = max |ours − Pinocchio| / max "
        "|Pinocchio| per state, worst over the states. Colour: green ≤ 1 % of the tolerance, yellow ≤ the tolerance, "
        f"red above it (or not finite). Symbolic build {num(check.get('build_seconds'), '.1f')} s.</p>",
        table(["term", "max abs err", "max rel err", "tol", "result"], rows),
    ]
    body.append("<h3>Other libraries as references</h3>")
    body.append(cross_library_html(check))
    ok = ok and check.get("cross_library_passed", True) is not False
    tol = terms[0]["tol"] if terms else None
    headline = f"{len(terms)} terms on {check.get('samples')} states, worst rel err {num(worst)} (tol {num(tol, '.0e')})"
    return Section("terms", "Every term against Pinocchio", "pass" if ok else "FAIL", headline, "\n".join(body))


def cross_library_html(check: dict[str, Any]) -> str:
    """The ``check --against`` part of ``check``: ``cross_library`` rows (library, term,
    max_rel_err vs Pinocchio, max_rel_err_vs_quadruped_dyn, max_rel_err_same_model,
    model_change, explained_by, tol, passed), ``model_changes`` (library, kind, links, detail,
    in_comparison, size), ``conformance`` (library -> term -> status, why) and ``cross_library_note``
    (what was not run, and why)."""
    rows, changes, note = check.get("cross_library"), check.get("model_changes") or [], check.get("cross_library_note")
    if not rows:
        return not_available("cross-library comparison (Pinocchio as loaded, MuJoCo, iDynTree, Drake, adam)"
                             + (f"; {note}" if note else ""))
    missing = [f"{lib}: {term} ({row.get('why', '')})" for lib, terms in (check.get("conformance") or {}).items()
               for term, row in terms.items() if row.get("status") in ("not computed", "not compared")]
    out = [f"<p>The same URDF through each library, converted to the project's conventions by its adapter "
           f"(docs/conventions.md §10), on {esc(check.get('cross_library_samples', '?'))} random states. A term passes "
           "when the library agrees with Pinocchio on the model it was given and any difference from the original "
           "URDF is carried by a named model change.</p>"]
    out.append(table(
        ["library", "term", "vs Pinocchio", "vs quadruped_dyn", "vs Pinocchio, same model", "model change", "explained by",
         "result"],
        [[r.get("library", "?"), r.get("term", "?"), cell(num(r.get("max_rel_err")), grade(r.get("max_rel_err"), r.get("tol"))),
          cell(num(r.get("max_rel_err_vs_quadruped_dyn")), grade(r.get("max_rel_err_vs_quadruped_dyn"), r.get("tol"))),
          cell(num(r.get("max_rel_err_same_model")), grade(r.get("max_rel_err_same_model"), r.get("tol"))),
          num(r.get("model_change")), ", ".join(r.get("explained_by") or []) or "—",
          cell(badge("pass" if r.get("passed") else "FAIL"))] for r in rows],
        f"relative errors, max over the states (tolerance {num(rows[0].get('tol'), '.0e')})"))
    if changes:
        out.append(table(
            ["library", "what it does to the URDF", "links", "detail", "in the comparison", "relative change"],
            [[c.get("library", "?"), c.get("kind", "?"), ", ".join(c.get("links") or []), c.get("detail", ""),
              "yes" if c.get("in_comparison") else "no",
              ", ".join(f"{t} {num(v, '.1e')}" for t, v in (c.get("size") or {}).items()) or "—"] for c in changes],
            "model diagnosis"))
    if missing:
        out.append(f'<p class="na">Not compared: {esc("; ".join(missing))}</p>')
    if note:
        out.append(f'<p class="na">{esc(note)}</p>')
    return "\n".join(out)


# ----------------------------------------------------------------------------- GRF


def grf_section(check: dict[str, Any] | None, posture: dict[str, Any] | None, footprint_html: str) -> Section:
    """``check``: as for ``terms_section`` (its ``grf`` list); ``posture``: the solves at the
    gait posture standing still (``stances``: stance, kind, rank, numeric_rank, singular_values,
    max_residual, min_friction_margin_N, in_cone; ``mu``)."""
    body = ["<p>The body equations A(r) λ = w_req of each stance set (docs/formulation.md §4): the paper's model "
            "(common f_x, f_y, ...) has rank 5 with four and with two feet. The solve is rank-revealing: minimum-norm λ, "
            "and the residual — the part of the required trunk wrench the feet cannot produce.</p>"]
    ok = True
    grf = (check or {}).get("grf", [])
    if grf:
        tol = (check or {}).get("terms", [{}])[0].get("tol")
        rows = [[g["stance"], g["model"], str(g["rank"]), num(g["max_residual"]), cell(num(g["max_err_vs_reference"]),
                 "" if g["passed"] else "bad"), cell(num(g["max_err_vs_pinocchio"]), grade(g["max_err_vs_pinocchio"], tol)),
                 num(g["max_cond"], ".1e"), str(g["rank_mismatches"]), cell(badge("pass" if g["passed"] else "FAIL"))]
                for g in grf]
        ok = all(g["passed"] and _finite(g["max_err_vs_pinocchio"]) for g in grf)
        body.append(table(["stance", "model", "rank", "max residual", "err vs SVD", "err vs Pinocchio", "max cond(A)",
                           "rank mismatches", "result"], rows,
                          "random states of the check: symbolic solve vs an SVD of Pinocchio's contact Jacobians, and "
                          "rnea − Σ J_cᵀ f vs (residual, τ)"))
    else:
        body.append(not_available("GRF check on random states"))
    stances = (posture or {}).get("stances", [])
    if stances:
        rows = [[s["stance"], s["kind"], str(s["rank"]),
                 cell(str(s["numeric_rank"]), "" if s["numeric_rank"] == s["rank"] else "bad"),
                 " ".join(f"{x:.2g}" for x in s["singular_values"]), num(s["max_residual"]),
                 num(s["min_friction_margin_N"], ".1f"), "yes" if s["in_cone"] else "NO"] for s in stances]
        ok = ok and all(s["numeric_rank"] == s["rank"] for s in stances)
        body.append(table(["stance", "kind", "structural rank", "numeric rank", "singular values of A", "max |residual|",
                           "min friction margin N", "in cone"], rows,
                          f"paper model at the gait posture, standing still (gravity only), μ = {(posture or {}).get('mu')}: "
                          "friction margin = μ f_z − |f_t| (negative: slips or pulls)"))
    else:
        body.append(not_available("GRF solves at the gait posture"))
    body.append(footprint_html)
    ranks = {len(s["stance"].split("+")): s["rank"] for s in stances}
    headline = (f"ranks {ranks.get(4, '?')} / {ranks.get(3, '?')} / {ranks.get(2, '?')} with 4 / 3 / 2 feet; "
                f"worst err vs Pinocchio {num(max((g['max_err_vs_pinocchio'] for g in grf), default=None))}")
    return Section("grf", "Ground-reaction-force systems", "pass" if ok and (grf or stances) else "FAIL", headline,
                   "\n".join(body))


# ----------------------------------------------------------------------------- reduced model


def reduced_section(rows: Sequence[dict[str, Any]] | None, posture_note: str = "") -> Section:
    """``rows`` per stance set: stance, kind, n, cond, asymmetry (max |M_r − M_rᵀ| / max |M_r|),
    err_vs_pinocchio (M_r against the Pinocchio-built reduced reference, relative), tol."""
    if not rows:
        return Section("reduced", "Reduced model per stance set", "not available", "not run", not_available("reduced model"))
    regular = [r for r in rows if not r.get("singular")]
    singular = [r for r in rows if r.get("singular")]
    table_rows = [[r["stance"], r["kind"], str(r["n"]), num(r["cond"], ".2e"), num(r["asymmetry"], ".3f"),
                   cell(num(r["err_vs_pinocchio"]), grade(r["err_vs_pinocchio"], r["tol"]))] for r in regular]
    table_rows += [[r["stance"], r["kind"], str(r["n"]), cell("singular", "near"), "", "n/a"] for r in singular]
    ok = bool(regular) and all(_finite(r["cond"]) and _within(r["err_vs_pinocchio"], r["tol"]) for r in regular)
    conds = [r["cond"] for r in regular] or [float("nan")]
    body = (f"<p>M_r = ∂τ_r/∂q̈_r (Walker &amp; Orin unit accelerations) of every stance set of 2, 3 or 4 feet at "
            f"{esc(posture_note)}, trunk level. M_r is not symmetric: the paper's GRF assumptions project the dynamics. "
            "The last column compares M_r with columns of the reduced inverse dynamics built from Pinocchio's foot "
            "quantities and an SVD GRF solve (an independent implementation).</p>"
            + table(["stance", "kind", "n", "cond(M_r)", "asymmetry", "M_r err vs Pinocchio"], table_rows)
            + "".join(f"<p>{esc(r['stance'])}: {esc(r['singular'])}</p>" for r in singular)
            + ("<p>Front and back pairs: their feet leave the trunk's pitch about the lateral foot-to-foot line free, "
               "and the reduced coordinates (joints + roll) cannot describe it, so the velocity map is rank-deficient "
               "— a limit of the paper's 13-coordinate model, not of the numerics.</p>"
               if any(r["kind"] in ("front", "back") for r in singular) else ""))
    asymmetry = max((r["asymmetry"] for r in regular), default=float("nan"))
    headline = (f"{len(rows)} stance sets, cond(M_r) {min(conds):.1e} – {max(conds):.1e}, asymmetry up to {asymmetry:.2f}"
                + (f"; singular: {', '.join(r['stance'] for r in singular)}" if singular else ""))
    return Section("reduced", "Reduced model per stance set", "pass" if ok else "FAIL", headline, body)


# ----------------------------------------------------------------------------- the paper's experiment


def _gait_block(gait: str, v: dict[str, Any], joint_names: Sequence[str], plot_html: str) -> tuple[str, str]:
    """HTML and headline of one gait's validation JSON (validation.report's keys)."""
    parts = [f"<h3>{esc(gait)}</h3>",
             f"<p>Horizon {num(v.get('horizon_s'), 'g')} s; {esc(v.get('integrator', 'n/a'))}. "
             "% error = max_t |sim − IK| / max_t |IK| × 100 per joint, 'paper' run (roll moment applied).</p>"]
    errors = v.get("max_pct_err", {})
    signals = ("q", "qd", "qdd")
    rows = [[s] + [num(errors.get(n, {}).get(s), ".1e") for n in joint_names] for s in signals]
    parts.append(table(["% error", *joint_names], rows))
    overall = v.get("max_pct_err_overall", {})
    br = errors.get(joint_names[BR_HFE], {}) if len(joint_names) > BR_HFE else {}
    headline = (f"BR HFE q {num(br.get('q'), '.1e')} %, worst joint q / qd / qdd "
                + " / ".join(num(overall.get(s), ".1e") for s in signals) + " %")
    runs = v.get("runs")
    if runs:
        parts.append(runs_table(runs))
    if "instability" in v:
        parts.append(instability_html(v["instability"]))
    if "static_stability" in v:
        parts.append(static_stability_html(v["static_stability"]))
    parts.append(plot_html)
    parts.append("<h4>Physics check (rigid-contact dynamics under the same torques)</h4>")
    physics = v.get("physics_check")
    parts.append(physics_check_html(physics) if physics else not_available("physics check (--no-physics)"))
    return "\n".join(parts), f"{gait}: {headline}"


def _time(t: Any, none: str = "never") -> str:
    """A time in s, or what its absence means (a run that never departed, never stopped)."""
    return none if t is None else num(t, "g")


def _rest(data: dict[str, Any], shown: Sequence[str]) -> str:
    """Keys a renderer does not know (a newer producer), shown as they come."""
    rest = {k: x for k, x in data.items() if k not in shown}
    return data_html(rest) if rest else ""


#: What each run of the experiment is (experiment.paper_experiment's runs).
RUN_NOTES = {"paper": "id_r's torques, roll moment applied (the paper's check)", "physical": "roll unactuated",
             "twin": "paper, initial state one ulp up", "coarse": "paper, 10 × looser tolerance (truncation estimate)",
             "refined": "paper, half the step (RK4's truncation estimate)",
             "plus_1pct": "1.01 × id_r's torques, roll unactuated (physics check)",
             "pd": "1.01 × id_r's torques + joint PD, roll unactuated (physics check)"}


def runs_table(runs: dict[str, Any]) -> str:
    """``runs``: name -> stopped_at_s, departs_1pct_at_s, max_closure_m, rhs_evaluations,
    max_pct_err_q / _qd / _qdd (worst joint)."""
    keys = ("stopped_at_s", "departs_1pct_at_s", "max_closure_m", "rhs_evaluations", "max_pct_err_q", "max_pct_err_qd",
            "max_pct_err_qdd")
    rows = [[name, RUN_NOTES.get(name, ""), _time(r.get("stopped_at_s"), "ran to the end"), _time(r.get("departs_1pct_at_s")),
             num(r.get("max_closure_m"), ".1e"), num(r.get("rhs_evaluations"), "d"),
             *(num(r.get(f"max_pct_err_{x}"), ".1e") for x in ("q", "qd", "qdd"))]
            for name, r in runs.items() if isinstance(r, dict)]
    extra = "".join(_rest(r, keys) for r in runs.values() if isinstance(r, dict))
    return table(["run", "what", "stopped at s", "1 % off IK at s", "max closure m", "RHS evaluations", "worst q %",
                  "worst q̇ %", "worst q̈ %"], rows,
                 "runs of the reduced model (worst joint; closure = how far the stance feet are from their footholds)") + extra


def instability_html(inst: dict[str, Any]) -> str:
    """``instability``: growth_rate_per_s, one_ulp_grows_to_rad, error_budget (signal ->
    total_pct, roundoff_pct, truncation_pct)."""
    budget = inst.get("error_budget") or {}
    signals = {"q": "q", "qd": "q̇", "qdd": "q̈"}
    rows = [[signals.get(k, k), num(b.get("total_pct"), ".1e"), num(b.get("roundoff_pct"), ".1e"),
             num(b.get("truncation_pct"), ".1e")] for k, b in budget.items() if isinstance(b, dict)]
    out = (f"<p>Open-loop instability: a one-ulp perturbation of the initial state grows at "
           f"{num(inst.get('growth_rate_per_s'), '.2g')} /s, to {num(inst.get('one_ulp_grows_to_rad'), '.1e')} rad by the "
           "end (docs/experiment.md §6).</p>")
    if rows:
        out += table(["signal", "total %", "round-off %", "truncation %"], rows,
                     "error budget, worst joint: round-off = the one-ulp twin's % difference, truncation = the "
                     "coarse run's difference / 9 (DOP853) or the half-step run's (RK4)")
    return out + _rest(inst, ("growth_rate_per_s", "one_ulp_grows_to_rad", "error_budget"))


def static_stability_html(st: dict[str, Any]) -> str:
    """``static_stability``: min_fz_N (at min_fz_at_s) of weight_N, min_com_margin_m (at
    min_com_margin_at_s; None with fewer than three feet)."""
    rows = [["smallest f_z on a stance foot", f"{num(st.get('min_fz_N'), '.3g')} N of {num(st.get('weight_N'), '.3g')} N "
             f"weight, at {num(st.get('min_fz_at_s'), 'g')} s"]]
    margin: Any = st.get("min_com_margin_m")
    rows.append(["smallest CoM margin inside the support triangle",
                 f"{num(100 * margin, '.3g')} cm at {num(st.get('min_com_margin_at_s'), 'g')} s" if _finite(margin)
                 else "— (fewer than three stance feet)"])
    keys = ("min_fz_N", "min_fz_at_s", "weight_N", "min_com_margin_m", "min_com_margin_at_s")
    return table(["static stability of the plan", ""], rows) + _rest(st, keys)


def physics_check_html(physics: dict[str, Any]) -> str:
    """``physics_check``: per torque law (a dict with torques, rigid_vs_reduced, rigid_vs_ik,
    reduced_vs_ik: max_joint_angle_diff_rad, time_to_1pct_s; rigid_stopped_at_s,
    reduced_stopped_at_s), departure_threshold_pct_of_max_joint_angle, max_joint_angle_rad."""
    laws = {k: x for k, x in physics.items() if isinstance(x, dict) and "rigid_vs_reduced" in x}

    def departure(d: Any) -> list[str]:
        d = d if isinstance(d, dict) else {}
        return [num(d.get("max_joint_angle_diff_rad"), ".1e"), _time(d.get("time_to_1pct_s"))]

    rows = [[law.get("torques", name), *departure(law.get("rigid_vs_reduced")), *departure(law.get("rigid_vs_ik")),
             *departure(law.get("reduced_vs_ik")),
             _time(law.get("rigid_stopped_at_s"), "ran to the end"), _time(law.get("reduced_stopped_at_s"), "ran to the end")]
            for name, law in laws.items()]
    out = ""
    if rows:
        out = table(["torques", "rigid vs reduced: max rad", "1 % at s", "rigid vs IK: max rad", "1 % at s",
                     "reduced vs IK: max rad", "1 % at s", "rigid stopped at s", "reduced stopped at s"], rows,
                    f"largest joint-angle difference; 1 % = {num(physics.get('departure_threshold_pct_of_max_joint_angle'), 'g')}"
                    f" % of the reference's largest |joint angle| ({num(physics.get('max_joint_angle_rad'), '.3g')} rad)")
    shown = [*laws, "departure_threshold_pct_of_max_joint_angle", "max_joint_angle_rad"]
    extra = "".join(_rest(law, ("torques", "rigid_vs_reduced", "rigid_vs_ik", "reduced_vs_ik", "rigid_stopped_at_s",
                                "reduced_stopped_at_s")) for law in laws.values())
    return out + extra + _rest(physics, shown)


def experiment_section(validations: dict[str, dict[str, Any] | None], joint_names: Sequence[str],
                       plots: dict[str, str]) -> Section:
    """``validations``: gait -> the validation JSON (``asdict(ValidationReport)``, as ``validate``
    writes it) or None; ``plots``: gait -> HTML of its BR HFE figure (the paper's Figs. 5-7)."""
    parts = ["<p>The paper's §6 experiment: IK → q, q̇, q̈ → id_r → τ(t) → forward dynamics with τ(t) → integrate → "
             "compare with IK, for all 12 joints. A departure is a measured result (open-loop instability, a gait "
             "the model cannot hold), not a failure of the toolkit.</p>"]
    headlines = []
    ok = True
    for gait, v in validations.items():
        if v is None:
            parts.append(f"<h3>{esc(gait)}</h3>" + not_available(f"{gait} experiment"))
            continue
        html, headline = _gait_block(gait, v, joint_names, plots.get(gait, ""))
        parts.append(html)
        headlines.append(headline)
        paper_run = v.get("runs", {}).get("paper", {})
        ok = ok and bool(paper_run)  # a run that produced no numbers is a failure
    verdict = "result" if ok and headlines else "not available" if not headlines else "FAIL"
    return Section("experiment", "The paper's experiment: trot and static walk", verdict, " | ".join(headlines) or "not run",
                   "\n".join(parts))


# ----------------------------------------------------------------------------- generated C


def embedded_html(embedded: dict[str, Any]) -> str:
    """Code size and worst-case stack on Cortex-M (``checks.embedded.embedded_summary``): the
    issue's budgets per build, then every function's code and stack at each build."""
    fp = embedded.get("footprint", {})
    out = ["<h3>Embedded targets: flash and stack (Cortex-M)</h3>"]
    if "builds" not in fp:
        return "\n".join(out + [not_available(f"footprint ({fp.get('skipped', 'not measured')})")])
    builds = fp["builds"]

    def budget(value: int, limit: int) -> str:
        return cell(f"{value / 1024:.1f}", "pass" if value <= limit else "FAIL")

    rows = [[f"{b['target']} {b['cflags']}", budget(b["full_code"], b["budgets"]["full_code"]),
             budget(max(b["reduced_code"].values()), b["budgets"]["reduced_code"]),
             budget(b["max_stack"], b["budgets"]["stack"]), budget(b["total"], b["budgets"]["total"])] for b in builds]
    out.append(table(["build", "M + C+G + id kB (≤ 64)", "worst stance M_r + CG_r + fd_r kB (≤ 48)",
                      "max stack kB (≤ 8)", "whole robot kB (≤ 1024)"], rows,
                     f"code + read-only data (nm), worst-case stack (-fstack-usage call graph); {esc(builds[0]['compiler'])}"))
    names = list(builds[0]["functions"])
    memory = {f["name"]: f for f in embedded.get("functions", [])}
    out.append(table(["function", "caller B (double/float)",
                      *[f"{b['target']} {b['cflags']} code / stack B" for b in builds]],
                     [[n, f"{memory[n]['caller_bytes_double']}/{memory[n]['caller_bytes_float']}" if n in memory else "",
                       *[f"{b['functions'][n]['code']:,} / {b['functions'][n]['stack']:,}" for b in builds]] for n in names],
                     "per function: its code with the generated functions it calls (libm counted once per robot)"))
    return "\n".join(out)


def generated_c_section(gen: dict[str, Any] | None, bench: Sequence[dict[str, Any]] | dict[str, Any] | None,
                        bench_note: str = "") -> Section:
    """``gen``: files (name, bytes), functions (name, inputs, outputs, instructions, iw, w),
    checks (name, max_rel_err, tol: the compiled library against Pinocchio at a fixed state),
    compile_s, library_bytes, directory; ``bench``: ``run_bench(...).as_dict()`` (or a list
    of them), None when skipped (``bench_note`` says why)."""
    if not gen:
        return Section("c", "Generated C", "not available", "not generated", not_available("generated C"))
    files = gen.get("files", [])
    body = [f"<p>Standalone C99 (no CasADi runtime, no malloc, caller-provided work memory), written to "
            f"<code>{esc(gen.get('directory', ''))}</code>.</p>",
            table(["file", "bytes"], [[f["name"], f"{f['bytes']:,}"] for f in files], "files")]
    functions = gen.get("functions", [])
    checks = {c["name"]: c for c in gen.get("checks", [])}

    def status(c: dict[str, Any] | None) -> str:
        if c is None:
            return "not checked"
        if "status" in c:
            return str(c["status"])
        return "pass" if _within(c.get("max_rel_err"), c.get("tol")) else "FAIL"

    rows = []
    for f in functions:
        c = checks.get(f["name"])
        verdict = status(c)
        err, tol = (c or {}).get("max_rel_err"), (c or {}).get("tol")
        rows.append([f["name"], f["inputs"], f["outputs"], f"{f['instructions']:,}", str(f["iw"]), str(f["w"]),
                     cell(num(err), grade(err, tol) if verdict != "skipped" else ""), num(tol, ".1e"),
                     cell(badge(verdict if verdict != "not checked" else "not available")), (c or {}).get("note", "")])
    verdicts = [status(checks.get(f["name"])) for f in functions]
    ok = bool(functions) and all(v in ("pass", "skipped") for v in verdicts)
    body.append(table(["function", "inputs", "outputs", "instructions", "iw", "w", "rel err vs Pinocchio", "tol", "result",
                       "note"], rows,
                      f"every generated function (shapes; work sizes in entries), and the compiled library (-O3, "
                      f"{num(gen.get('library_bytes'), ',')} bytes, compiled in {num(gen.get('compile_s'), '.1f')} s or cached) "
                      "at a fixed state near standing against Pinocchio; a tolerance is scaled by the state's conditioning "
                      "(docs/formulation.md §11), a case with under two digits left is skipped"))
    body.append("<h3>Benchmark against Pinocchio</h3>")
    reports = [bench] if isinstance(bench, dict) else list(bench or [])
    bench_headline = "benchmark skipped"
    for b in reports:
        entries = b.get("entries", [])
        rows = [[e["name"], num(e.get("generated_ns"), ".0f"), e.get("pinocchio") or "", num(e.get("pinocchio_ns"), ".0f"),
                 cell(num(e.get("ratio"), ".2f"), grade(e.get("ratio"), e.get("target"))),
                 "" if e.get("target") is None else f"≤ {e['target']:.2f}"] for e in entries]
        body.append(table(["function", "generated ns", "peer", "peer ns", "ratio", "target"], rows,
                          f"{b.get('robot')}: medians timed in C on both sides, same run, over "
                          f"{b.get('rounds') or 'several'} rounds of fresh copies of the code timed "
                          f"(Pinocchio {b.get('pinocchio_version')}); "
                          f"C source {num(b.get('code_bytes'), ',')} B, library {num(b.get('library_bytes'), ',')} B"))
        if b.get("parametric"):
            body.append(table(["term", "parametric ns", "fixed ns", "Pinocchio ns", "vs Pinocchio", "vs fixed"],
                              [[name, num(t["parametric_ns"], ".0f"), num(t["fixed_ns"], ".0f"),
                                num(t["pinocchio_ns"], ".0f"), num(t["vs_pinocchio"], ".2f"), num(t["vs_fixed"], ".2f")]
                               for name, t in b["parametric"].items()],
                              f"{b.get('robot')}: the family's parametric library (p as an input, docs/embedded.md) "
                              "against the fixed library and Pinocchio, same run"))
        ratios = [e["ratio"] for e in entries if e.get("ratio") is not None]
        targeted = [e for e in entries if e.get("target") is not None]
        met = sum(1 for e in targeted if grade(e.get("ratio"), e["target"]) != "bad")
        bench_headline = (f"ratio to Pinocchio {min(ratios):.2f} – {max(ratios):.2f}, speed targets met {met} of {len(targeted)}"
                          if ratios else "benchmark ran")
    if not reports:
        body.append(not_available(f"benchmark ({bench_note})" if bench_note else "benchmark"))
    if gen.get("embedded"):
        body.append(embedded_html(gen["embedded"]))  # Cortex-M footprint (docs/embedded.md)
    size = sum(f["bytes"] for f in files)
    checked = f"{verdicts.count('pass')} pass vs Pinocchio" + (f", {verdicts.count('skipped')} skipped" if "skipped" in verdicts
                                                              else "")
    headline = f"{len(functions)} functions, {size / 1e3:.0f} kB of C, {checked}; {bench_headline}"
    return Section("c", "Generated C", "pass" if ok else "FAIL", headline, "\n".join(body))


# ----------------------------------------------------------------------------- symbolic inspection


def symbolic_section(formulas: Sequence[dict[str, Any]] | None, formulas_note: str, sizes: Sequence[dict[str, Any]],
                     sparsity_html: str) -> Section:
    """``formulas``: title, mathml, latex, max_err_vs_pinocchio, tol (None when the robot has
    no DH description); ``sizes``: name, instructions, inputs, outputs, nonzeros."""
    body = ["<h3>Formulas</h3>"]
    ok = True
    if formulas:
        body.append(f"<p>{esc(formulas_note)}</p>")
        for f in formulas:
            err, tol = f["max_err_vs_pinocchio"], f["tol"]
            ok = ok and _within(err, tol)
            body.append(f"<p><b>{esc(f['title'])}</b> — the formula evaluated with full-precision coefficients agrees "
                        f"with Pinocchio to {num(err)} (relative, tol {num(tol, '.0e')}) "
                        f"{badge('pass' if _within(err, tol) else 'FAIL')}"
                        f"</p>{f['mathml']}<details><summary>LaTeX</summary><pre>{esc(f['latex'])}</pre></details>")
    else:
        body.append(f"<p class=\"na\">{esc(formulas_note)}</p>")
    body.append("<h3>Operation counts</h3>")
    body.append(table(["term", "inputs", "outputs", "instructions", "structural nonzeros"],
                      [[s["name"], s["inputs"], s["outputs"], f"{s['instructions']:,}", str(s["nonzeros"])] for s in sizes],
                      "CasADi instructions after common-subexpression elimination"))
    body.append("<h3>Sparsity</h3>" + sparsity_html)
    biggest = max(sizes, key=lambda s: s["instructions"]) if sizes else None
    headline = (f"{len(formulas)} formulas checked vs Pinocchio; " if formulas else "") + (
        f"{len(sizes)} terms, largest {biggest['name']} ({biggest['instructions']:,} instructions)" if biggest else "")
    return Section("symbolic", "Symbolic terms", ("pass" if ok else "FAIL") if formulas else "result", headline,
                   "\n".join(body))


# ----------------------------------------------------------------------------- notebooks, versions


def notebooks_section(notebooks: Sequence[dict[str, Any]] | None, note: str = "") -> Section:
    """``notebooks``: name, seconds, errors (count), html (rendered cells with outputs)."""
    if not notebooks:
        return Section("notebooks", "Notebooks, executed", "skipped" if note else "not available", note or "not run",
                       f'<p class="na">{esc(note)}</p>' if note else not_available("executed notebooks"))
    errors = sum(n["errors"] for n in notebooks)
    body = [f"<p>Executed while this report was built; the repository keeps them without outputs. {esc(note)}</p>"]
    body += [f'<details><summary>{esc(n["name"])} ({n["seconds"]:.1f} s'
             f'{", " + str(n["errors"]) + " error(s)" if n["errors"] else ""})</summary>{n["html"]}</details>'
             for n in notebooks]
    headline = f"{len(notebooks)} notebooks executed, {errors} error(s)"
    return Section("notebooks", "Notebooks, executed", "pass" if errors == 0 else "FAIL", headline, "\n".join(body))


def versions_section(versions: dict[str, Any]) -> Section:
    machine = versions.get("machine", {})
    libraries = versions.get("libraries", {})
    body = table(["", ""], [[k, str(v)] for k, v in machine.items()], "machine") + table(
        ["library", "version"], [[k, str(v)] for k, v in libraries.items()], "libraries")
    headline = ", ".join(f"{k} {libraries[k]}" for k in ("pin", "casadi", "numpy") if k in libraries)
    return Section("versions", "Versions and machine", "result", headline, body)


# ----------------------------------------------------------------------------- optimal control


def _replay_departure(replay: dict[str, Any]) -> str:
    """When the rigid-contact replay left the optimised motion by 1 %: a time in s, 'never within
    the horizon' (it stayed closer), or 'not replayed' (IPOPT did not converge)."""
    if not replay:
        return "not replayed"
    return _time(replay.get("time_to_1pct_s"), f"never within {num(replay.get('horizon_s'), 'g')} s")


def _replay_headline(replay: dict[str, Any]) -> str:
    """The replay in a summary line: 'replay 1 % off at 0.83 s', 'replay within 1 % for all 1.2 s'."""
    if not replay:
        return "not replayed"
    t = replay.get("time_to_1pct_s")
    return (f"replay 1 % off at {num(t, 'g')} s" if t is not None
            else f"replay within 1 % for all {num(replay.get('horizon_s'), 'g')} s")


def optimal_control_section(data: dict[str, Any] | None, plot: str = "") -> Section:
    """``data``: the JSON ``optimize`` writes for the trot (docs/optimal_control.md)."""
    title = "A trot the robot can do"
    if data is None:
        return Section("optimal_control", title, "not available", "not run", not_available("the optimised trot"))
    e, f = data["effort"], data["formulation"]
    rp = data.get("rigid_contact_replay") or {}
    converged = bool(data["converged"])
    rows = [["IPOPT status", esc(data["status"])], ["iterations", str(data["iterations"])],
            ["solve time (s, loaded machine)", num(data["solve_seconds"], ".1f")],
            ["constraint violation", num(data["constraint_violation"])],
            ["largest roll moment needed (N m): optimised / plan",
             f"{num(e['max_roll_moment_optimised_Nm'])} / {num(e['max_roll_moment_plan_Nm'], '.2f')}"],
            ["torque effort, optimised / plan", num(e["ratio"], ".3f")],
            ["rigid-contact replay: 1 % off the optimised motion at (s)", _replay_departure(rp)],
            ["growth rate of the departure (1/s)", num(rp.get("growth_rate_per_s"), ".1f")]]
    html = (f"<p>Direct collocation on the reduced model ({f['nodes']} nodes, {f['variables']} variables, "
            f"{f['constraints']} constraints): the trunk roll unactuated (id_r's 13th entry = 0 at every collocation point), "
            f"the paper's GRF inside the friction cone (μ = {f['mu']:g}, f_z ≥ {f['fz_min_N']:.2f} N), URDF joint and "
            "effort limits, swing clearance, periodicity at the plan's speed; effort plus closeness to the plan. "
            "Today's plan needs a roll moment from nowhere; the optimised trot does not.</p>"
            + table(["quantity", "value"], rows) + plot)
    headline = (f"{data['status']}, roll moment {num(e['max_roll_moment_optimised_Nm'])} N m (plan "
                f"{num(e['max_roll_moment_plan_Nm'], '.2f')}); {_replay_headline(rp)}")
    return Section("optimal_control", title, "result" if converged else "FAIL", headline, html)

# ----------------------------------------------------------------------------- closed loop


def closed_loop_section(loop: dict[str, Any] | None) -> Section:
    """``loop``: ``gather.closed_loop``'s data -- per gait the ``control --json`` output, plots
    (PNG bytes) and the animation (GIF bytes or None)."""
    import base64

    if not loop or not loop.get("gaits"):
        return Section("closed_loop", "Closed loop in MuJoCo", "not available", "not run", not_available("closed loop"))
    parts = ["<p>The generated C in the loop of a simulated robot whose contacts nobody here wrote: MuJoCo, soft, "
             "frictional, unilateral contacts, the robot built from the same URDF. Controllers at 1 kHz read joint q, "
             "q̇ and an IMU (trunk orientation, angular rate); the stance set is the plan's (the ct controllers also use "
             "the foot contact switches). pd: joint PD; ff+pd: id_r at the plan + PD; ct: computed torque, id_r at the "
             "measured state with the feedback inside (through M_r); ct-diag: id_r at the measured state + the feedback "
             "with a positive diagonal inertia estimate, run by the drivers; pd-diag: the same gains without the model; "
             "+level: the reference levelled by the IMU; +step: capture-point foot placement; wbc: a whole-body QP over "
             "(v̇, f) on the generated M_full, nle_full and feet_full (floating-base rows, still contact feet, friction "
             "pyramids, torque limits; trunk velocity by leg odometry) + the drivers' pd-diag PD; mpc+wbc: wbc tracking "
             "the forces of a 50 Hz convex MPC of the locked-joint rigid body. See docs/closed_loop.md.</p>"]
    headlines = []
    for gait, g in loop["gaits"].items():
        d = g.get("data", {})
        plant = d.get("plant", {})
        gains = d.get("gains", {})
        period = num(d.get("period_s"), "g")
        parts.append(f"<h3>{esc(gait)}: {esc(d.get('robot'))}, {esc(d.get('cycles'))} cycles of {period} s</h3>")
        parts.append(f"<p>MuJoCo step {num(plant.get('timestep_s'), 'g')} s ({esc(plant.get('integrator'))}), mu "
                     f"{num(plant.get('mu'), 'g')}, foot radius {num(plant.get('foot_radius_m'), 'g')} m "
                     f"({esc(plant.get('foot_radius_from'))}); joint PD "
                     f"{num(gains.get('kp_Nm_per_rad'), '.3g')} N m/rad, "
                     f"{num(gains.get('kd_Nms_per_rad'), '.3g')} N m s/rad ({num(gains.get('kp_per_kg'), 'g')}, "
                     f"{num(gains.get('kd_per_kg'), 'g')} per kg); ct, ct-diag error dynamics "
                     f"{num(gains.get('ct_omega_stance'), 'g')} rad/s (stance legs), "
                     f"{num(gains.get('ct_omega_swing'), 'g')} rad/s (swing legs), damping ratio "
                     f"{num(gains.get('ct_zeta'), 'g')}.</p>")
        rows, grf_rows = [], []
        up = []
        for name, r in d.get("controllers", {}).items():
            t, tr, c, sat, slip = (r.get(k) or {} for k in ("trunk", "tracking", "compute", "saturation", "foot_slip"))
            fell = "no" if not r.get("fell") else f"at {num(r.get('fell_at_s'), '.3g')} s"
            rows.append([name, num(r.get("cycles_up"), "g"), fell,
                         num(tr.get("rms_rad"), ".2e"), num(tr.get("max_rad"), ".2e"), num(t.get("height_max_m"), ".2e"),
                         num(t.get("roll_max_deg"), ".3g"), num(t.get("pitch_max_deg"), ".3g"),
                         num(t.get("yaw_final_deg"), ".3g"),
                         num(slip.get("max_m"), ".2e"), num(sat.get("time_s"), ".3g"), num(c.get("c_calls_median_us"), ".3g"),
                         num(c.get("c_calls_max_us"), ".3g"), num(c.get("tick_python_median_us"), ".3g")])
            up.append(f"{name} {num(r.get('cycles_up'), 'g')}")
            for kind, e in (r.get("grf") or {}).items():
                if e.get("compared"):
                    grf_rows.append([name, kind, str(e.get("compared")), num(e.get("diff_median_N"), ".3g"),
                                     num(e.get("diff_max_N"), ".3g"), num(e.get("relative_median"), ".2f"),
                                     " / ".join(num(x, ".3g") for x in e.get("diff_xyz_median_N", []))])
        parts.append(table(["controller", "cycles up", "fell", "joint RMS [rad]", "joint max [rad]", "height max [m]",
                            "roll max [°]", "pitch max [°]", "yaw final [°]", "slip max [m]", "saturated [s]",
                            "C median [µs]", "C max [µs]", "tick median [µs]"], rows,
                           "every controller, from the same settled state; C = the generated-C calls of one tick "
                           "(ctypes included); tick = the controller's whole tick in Python (machine shared, loaded)"))
        stand = d.get("standing_grf") or {}
        if stand.get("compared"):
            grf_rows.insert(0, ["(settling, PD + G_r)", "4 feet", str(stand.get("compared")),
                                num(stand.get("diff_median_N"), ".3g"),
                                num(stand.get("diff_max_N"), ".3g"), num(stand.get("relative_median"), ".2f"),
                                " / ".join(num(x, ".3g") for x in stand.get("diff_xyz_median_N", []))])
        parts.append(table(["controller", "stance", "instants", "|Δf| median [N]", "|Δf| max [N]", "relative median",
                            "|Δf| x / y / z median [N]"], grf_rows,
                           "MuJoCo's contact forces vs the paper's GRF model at the same instants (measured state, "
                           "MuJoCo's acceleration; instants whose MuJoCo contacts are the plan's stance); a result about "
                           "the paper's assumptions (common fx, fy; rank-5 pairs), not a pass/fail"))
        if g.get("plot_png"):
            parts.append(png_image(g["plot_png"], f"{gait}: tracking and trunk attitude per controller"))
        if g.get("grf_png"):
            parts.append(png_image(g["grf_png"], f"{gait}: GRF difference over time"))
        if g.get("gif"):
            parts.append(f'<figure><img alt="{esc(gait)} animation" src="data:image/gif;base64,'
                         f'{base64.b64encode(g["gif"]).decode()}"><figcaption>{esc(gait)}, controller '
                         f'{esc(g.get("animated"))}, first seconds</figcaption></figure>')
        else:
            parts.append(f"<p class=\"na\">{esc(g.get('animation_note', 'no animation'))}</p>")
        headlines.append(f"{gait}: cycles up " + ", ".join(up))
    return Section("closed_loop", "Closed loop in MuJoCo", "result", " | ".join(headlines), "\n".join(parts))

