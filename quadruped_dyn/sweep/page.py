"""The sweep's page: one self-contained HTML file (plots inlined as PNG) of ``summary.summarise``'s data:
tasks and cost per kind, the robots x libraries x terms matrix (worst relative error; green within the
tolerance, amber a difference explained by a named model change, red a failure), the codegen and
validate tables, and the closed loop's fall rates per controller, per perturbation bin (plots) and per
pair of bins with the model's value."""

from __future__ import annotations

import base64
import html
import io
from collections import defaultdict
from typing import Any

GREEN, AMBER, RED = "#cdeccd", "#fbe3b0", "#f6c1c1"


def _e(x: Any) -> str:
    if isinstance(x, float):
        return f"{x:.3g}"
    return html.escape("" if x is None else str(x))


def _table(header: list[str], rows: list[list[str]]) -> str:
    head = "".join(f"<th>{_e(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(c if c.startswith("<td") else f"<td>{c}</td>" for c in r) + "</tr>" for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _badness(e: dict[str, Any]) -> tuple[bool, float]:
    return (not e["passed"], float("inf") if e["err"] is None else e["err"])


def _matrix(entries: list[dict[str, Any]]) -> str:
    terms = list(dict.fromkeys(e["term"] if not e["term"].startswith("GRF ") else "GRF solves" for e in entries))
    cells: dict[tuple[str, str], dict[str, Any]] = defaultdict(dict)
    for e in entries:
        term = "GRF solves" if e["term"].startswith("GRF ") else e["term"]
        shown = cells[(e["robot"], e["library"])]
        shown[term] = max(filter(None, (shown.get(term), e)), key=_badness)  # a failure first, then the largest error
    rows = []
    for (robot, library), by_term in cells.items():
        row = [_e(robot), _e(library)]
        for t in terms:
            cell: dict[str, Any] | None = by_term.get(t)
            if cell is None:
                row.append("<td></td>")
                continue
            e = cell
            colour = RED if not e["passed"] else AMBER if e["tol"] is not None and (e["err"] or 0) > e["tol"] else GREEN
            why = f" ({', '.join(e['explained_by'])})" if e["explained_by"] else ""
            text = "fail" if e["err"] is None else f"{e['err']:.1e}"
            row.append(f'<td style="background:{colour}" title="tol {_e(e["tol"])}{_e(why)}">{text}{_e(why)}</td>')
        rows.append(row)
    return _table(["robot", "library", *terms], rows)


def _plot(control: dict[str, Any], perturbation: str) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3.2))
    by: dict[tuple[str, str, str], list[dict[str, Any]]] = defaultdict(list)
    for b in control["bins"]:
        if b["perturbation"] == perturbation and b["runs"]:
            by[(b["robot"], b["gait"], b["controller"])].append(b)
    for (robot, gait, controller), bins in by.items():
        x = [sum(b["bin"]) / 2 for b in bins]
        y = [b["fall_rate"] for b in bins]
        err = [[max(0.0, y_ - b["ci95"][0]) for y_, b in zip(y, bins)], [max(0.0, b["ci95"][1] - y_) for y_, b in zip(y, bins)]]
        ax.errorbar(x, y, yerr=err, marker="o", capsize=3, label=f"{controller} ({robot} {gait})")
    ax.set_xlabel(perturbation)
    ax.set_ylabel("fall rate (95 % interval)")
    ax.set_ylim(-0.05, 1.05)
    ax.legend(fontsize=7)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    png = base64.b64encode(buf.getvalue()).decode()
    return f'<img alt="fall rate against {_e(perturbation)}" src="data:image/png;base64,{png}">'


def _holds(groups: list[dict[str, Any]]) -> str:
    """Robots x controllers per gait: "holds" (green) where no run fell, else the falls and their first signs
    (red where every run fell, amber where some did)."""
    controllers = list(dict.fromkeys(g["controller"] for g in groups))
    cells: dict[tuple[str, str], dict[str, dict[str, Any]]] = defaultdict(dict)
    for g in groups:
        cells[(g["robot"], g["gait"])][g["controller"]] = g
    rows = []
    for (robot, gait), by in cells.items():
        row = [_e(robot), _e(gait)]
        for c in controllers:
            if c not in by or not by[c]["runs"]:
                row.append("<td></td>")
                continue
            g = by[c]
            colour = GREEN if not g["falls"] else RED if g["falls"] == g["runs"] else AMBER
            text = "holds" if not g["falls"] else (f"fell {g['falls']}/{g['runs']}: "
                                                   + ", ".join(f"{k} {v}" for k, v in g["first_sign_of_falls"].items()))
            row.append(f'<td style="background:{colour}">{_e(text)}</td>')
        rows.append(row)
    return _table(["robot", "gait", *controllers], rows)


def _control(control: dict[str, Any]) -> str:
    header = ["robot", "gait", "controller", "runs", "falls", "fall rate", "95 % interval", "first sign of the falls",
              "tracking RMS (rad, median)"]
    parts = [_table(header,
                    [[_e(g["robot"]), _e(g["gait"]), _e(g["controller"]), _e(g["runs"]), _e(g["falls"]), _e(g["fall_rate"]),
                      f"{g['ci95'][0]:.2f}-{g['ci95'][1]:.2f}",
                      _e(", ".join(f"{k}: {v}" for k, v in g["first_sign_of_falls"].items())),
                      _e(g["tracking_rms_median_rad"])] for g in control["controllers"]]),
             "<h3>Which controller holds on which robot (the first warning sign of each fall)</h3>",
             _holds(control["controllers"])]
    parts += [_plot(control, p) for p in control["perturbations"]]
    if control["bins_2d"]:
        a, b = control["perturbations"][:2]
        rows = []
        for cell in control["bins_2d"]:
            rates = "; ".join(f"{c} {r['falls']}/{r['runs']} ({r['ci95'][0]:.2f}-{r['ci95'][1]:.2f})"
                              for c, r in cell["controllers"].items())
            mv = cell.get("model_value")
            value = f"{mv['difference']:+.2f} [{mv['ci95'][0]:+.2f}, {mv['ci95'][1]:+.2f}]" if mv else ""
            rows.append([_e(cell["robot"]), _e(f"{cell[a][0]:.3g}-{cell[a][1]:.3g}"),
                         _e(f"{cell[b][0]:.3g}-{cell[b][1]:.3g}"), _e(rates), _e(value)])
        parts.append(f"<h3>Falls per ({_e(a)}, {_e(b)}) bin; the model's value: fall rate of ct-diag minus pd-diag</h3>")
        parts.append(_table(["robot", a, b, "falls / runs (95 % interval)", "ct-diag - pd-diag (95 %)"], rows))
    return "\n".join(parts)


def page(name: str, s: dict[str, Any]) -> str:
    """The HTML page of summary ``s`` of sweep ``name``."""
    parts = [f"<h1>Sweep {_e(name)}</h1>",
             _table(["kind", "tasks", "errors", "failed checks", "wall s (median)", "CPU s (median)", "CPU s (total)"],
                    [[_e(k), _e(v["tasks"]), _e(v["errors"]), _e(v["failed_checks"]), _e(v["wall_s_median"]),
                      _e(v["cpu_s_median"]), _e(v["cpu_s_total"])] for k, v in s["kinds"].items()])]
    if s.get("check"):
        parts += ["<h2>Terms: worst relative error per robot and library</h2>", _matrix(s["check"])]
    if s.get("codegen"):
        cols = ["robot", "precision", "passed", "functions_passed", "functions_failed", "functions_skipped", "worst_rel_err",
                "generate_s", "compile_s", "c_source_bytes", "error"]
        parts += ["<h2>Generated C: the check program</h2>", _table(cols, [[_e(r.get(c)) for c in cols] for r in s["codegen"]])]
    if s.get("validate"):
        cols = list(s["validate"][0])
        parts += ["<h2>The paper's experiment</h2>", _table(cols, [[_e(r.get(c)) for c in cols] for r in s["validate"]])]
    if s.get("control"):
        parts += ["<h2>Closed loop: falls</h2>", _control(s["control"])]
    if s.get("errors"):
        parts += ["<h2>Errors</h2>", _table(["kind", "robot", "key", "error"],
                                            [[_e(e["kind"]), _e(e["robot"]), _e(e["key"]), _e(e["error"])] for e in s["errors"]])]
    style = ("body{font-family:sans-serif;margin:2em}table{border-collapse:collapse;font-size:12px;margin:1em 0}"
             "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>Sweep {_e(name)}</title><style>{style}</style>"
            f"</head><body>{''.join(parts)}</body></html>\n")
