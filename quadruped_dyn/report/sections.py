"""The report's sections: one function per section, each rendering the data of one public API
or JSON (``run_check(...).as_dict()``, the validation JSON, ``run_bench(...).as_dict()``, ...)
into a ``Section``. Renderers only read: a key that is missing (an older or newer producer)
shows as "not available" instead of failing, so a new output is wired in with one line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from quadruped_dyn.model.leg import BR_HFE
from quadruped_dyn.report.html import Section, badge, cell, esc, grade, not_available, num, table


def _finite(*xs: Any) -> bool:
    return all(isinstance(x, (int, float)) and math.isfinite(x) for x in xs)


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
    worst = max((t["max_rel_err"] for t in terms), default=float("nan"))
    ok = bool(check.get("passed")) and all(_finite(t["max_rel_err"]) for t in terms)
    body = [
        f"<p>{check.get('samples')} random states (seed {check.get('seed')}): joint angles inside limits, random "
        "orientation, velocities, accelerations and foot forces. Relative error = max |ours − Pinocchio| / max "
        "|Pinocchio| per state, worst over the states. Colour: green ≤ 1 % of the tolerance, yellow ≤ the tolerance, "
        f"red above it (or not finite). Symbolic build {num(check.get('build_seconds'), '.1f')} s.</p>",
        table(["term", "max abs err", "max rel err", "tol", "result"], rows),
    ]
    cross = check.get("cross_library")
    body.append("<h3>Other libraries as references</h3>")
    body.append(generic_table(cross) if cross else not_available("cross-library comparison (MuJoCo, iDynTree)"))
    tol = terms[0]["tol"] if terms else None
    headline = f"{len(terms)} terms on {check.get('samples')} states, worst rel err {num(worst)} (tol {num(tol, '.0e')})"
    return Section("terms", "Every term against Pinocchio", "pass" if ok else "FAIL", headline, "\n".join(body))


# ----------------------------------------------------------------------------- GRF


def grf_section(check: dict[str, Any] | None, posture: dict[str, Any] | None, footprint_html: str) -> Section:
    """``check``: as for ``terms_section`` (its ``grf`` list); ``posture``: the solves at the
    gait posture standing still (``stances``: stance, kind, rank, numeric_rank, singular_values,
    max_residual, min_friction_margin_N, in_cone; ``mu``)."""
    body = ["<p>The body equations A(r) λ = w_req of each stance set (SPEC §4): the paper's model (common f_x, f_y, ...) "
            "has rank 5 with four and with two feet. The solve is rank-revealing: minimum-norm λ, and the residual — the "
            "part of the required trunk wrench the feet cannot produce.</p>"]
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
    ok = bool(regular) and all(_finite(r["err_vs_pinocchio"], r["cond"]) and r["err_vs_pinocchio"] <= r["tol"]
                               for r in regular)
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
    for run, summary in v.get("runs", {}).items():
        left = isinstance(summary, dict) and any(summary.get(k) is not None for k in ("departs_1pct_at_s", "stopped_at_s"))
        if left:
            parts.append(f"<p><b>run '{esc(run)}'</b>: 1 % off IK at {num(summary.get('departs_1pct_at_s'), 'g')} s, "
                         f"stopped at {num(summary.get('stopped_at_s'), 'g')} s</p>")
    for key in ("instability", "static_stability"):
        if key in v:
            parts.append(f"<p><b>{esc(key)}</b></p>{data_html(v[key])}")
    parts.append(plot_html)
    parts.append("<h4>Physics check (rigid-contact dynamics under the same torques)</h4>")
    physics = v.get("physics_check")
    parts.append(data_html(physics) if physics else not_available("physics check (--no-physics)"))
    return "\n".join(parts), f"{gait}: {headline}"


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
    body.append(table(["function", "inputs", "outputs", "instructions", "iw", "w"],
                      [[f["name"], f["inputs"], f["outputs"], str(f["instructions"]), str(f["iw"]), str(f["w"])]
                       for f in functions], "functions (shapes; work sizes in entries)"))
    checks = gen.get("checks", [])
    ok = bool(checks) and all(_finite(c["max_rel_err"]) and c["max_rel_err"] <= c["tol"] for c in checks)
    if checks:
        body.append(table(["function", "rel err vs Pinocchio", "tol"],
                          [[c["name"], cell(num(c["max_rel_err"]), grade(c["max_rel_err"], c["tol"])), num(c["tol"], ".0e")]
                           for c in checks],
                          f"the compiled library (-O3, {num(gen.get('library_bytes'), ',')} bytes, compiled in "
                          f"{num(gen.get('compile_s'), '.1f')} s or cached) at a fixed state near standing, vs Pinocchio"))
    body.append("<h3>Benchmark against Pinocchio</h3>")
    reports = [bench] if isinstance(bench, dict) else list(bench or [])
    bench_headline = "benchmark skipped"
    for b in reports:
        entries = b.get("entries", [])
        rows = [[e["name"], num(e.get("generated_ns"), ".0f"), e.get("pinocchio") or "", num(e.get("pinocchio_ns"), ".0f"),
                 cell(num(e.get("ratio"), ".2f"), grade(e.get("ratio"), e.get("target"))),
                 "" if e.get("target") is None else f"≤ {e['target']:.2f}"] for e in entries]
        body.append(table(["function", "generated ns", "peer", "peer ns", "ratio", "target"], rows,
                          f"{b.get('robot')}: medians timed in C on both sides, same run "
                          f"(Pinocchio {b.get('pinocchio_version')}); "
                          f"C source {num(b.get('code_bytes'), ',')} B, library {num(b.get('library_bytes'), ',')} B"))
        ratios = [e["ratio"] for e in entries if e.get("ratio") is not None]
        bench_headline = f"ratio to Pinocchio {min(ratios):.2f} – {max(ratios):.2f}" if ratios else "benchmark ran"
    if not reports:
        body.append(not_available(f"benchmark ({bench_note})" if bench_note else "benchmark"))
    size = sum(f["bytes"] for f in files)
    headline = f"{len(functions)} functions, {size / 1e3:.0f} kB of C; {bench_headline}"
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
            ok = ok and _finite(err) and err <= tol
            body.append(f"<p><b>{esc(f['title'])}</b> — the formula evaluated with full-precision coefficients agrees "
                        f"with Pinocchio to {num(err)} (relative, tol {num(tol, '.0e')}) "
                        f"{badge('pass' if err <= tol else 'FAIL')}"
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
