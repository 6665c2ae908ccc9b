"""What a sweep's dataset says (pandas), as plain data (``--json``): per kind the tasks run and failed and
their cost; ``check``: each (robot, library, term)'s worst relative error over the sweep's states against its
tolerance, with the model changes that explain a difference; ``codegen``: per robot and precision the
check program's verdict; ``validate``: the experiment's worst errors; ``control``: per robot, gait and
controller the fall rate with its 95 % interval (Wilson), the first warning sign of the falls, and the
fall rate per bin of each perturbation that varies (and of the first two together), with the model's
value — ct-diag's fall rate minus pd-diag's (the same per-joint gains without the model; Newcombe's
interval) — per bin.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

#: Equal-width bins over a perturbation's sampled range, alone and (per axis) for two together.
BINS = 4
BINS_2D = 3
#: The normal quantile of a two-sided 95 % interval.
Z95 = 1.959963984540054
#: The pair whose difference is the model's value in the closed loop (same per-joint gains, with and without the model).
MODEL_PAIR = ("ct-diag", "pd-diag")


def wilson(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """Wilson's score interval of a proportion k / n (n > 0)."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    # k = 0 and k = n end the interval exactly at 0 and 1 (the formula's round-off would leave p just outside it)
    return (0.0 if k == 0 else max(0.0, centre - half)), (1.0 if k == n else min(1.0, centre + half))


def newcombe(k1: int, n1: int, k2: int, n2: int) -> tuple[float, float, float]:
    """p1 - p2 and its 95 % interval (Newcombe's hybrid score method, from the two Wilson intervals)."""
    p1, p2 = k1 / n1, k2 / n2
    (l1, u1), (l2, u2) = wilson(k1, n1), wilson(k2, n2)
    d = p1 - p2
    return d, d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2), d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)


def _rate(falls: Any) -> dict[str, Any]:
    n, k = int(len(falls)), int(np.sum(falls))
    lo, hi = wilson(k, n) if n else (None, None)
    return {"runs": n, "falls": k, "fall_rate": k / n if n else None, "ci95": [lo, hi]}


def _bin_edges(values: Any, bins: int) -> np.ndarray:
    lo, hi = float(np.min(values)), float(np.max(values))
    return np.linspace(lo, hi, bins + 1)


def _bin_index(values: Any, edges: np.ndarray) -> np.ndarray:
    return np.clip(np.searchsorted(edges, values, side="right") - 1, 0, len(edges) - 2)


def _check(df: Any) -> list[dict[str, Any]]:
    worst: dict[tuple[str, str, str], dict[str, Any]] = {}
    for _, row in df.iterrows():
        for t in json.loads(row["metrics"]).get("terms", []):
            e = worst.setdefault((row["robot"], t["library"], t["term"]),
                                 {"robot": row["robot"], "library": t["library"], "term": t["term"], "err": 0.0,
                                  "tol": t["tol"], "passed": True, "explained_by": []})
            e["err"] = None if t["err"] is None or e["err"] is None else max(e["err"], t["err"])
            e["passed"] = e["passed"] and bool(t["passed"])
            e["explained_by"] = sorted(set(e["explained_by"]) | set(t["explained_by"]))
    return list(worst.values())


def _codegen(df: Any) -> list[dict[str, Any]]:
    cols = ["m.functions_passed", "m.functions_failed", "m.functions_skipped", "m.worst_rel_err", "m.generate_s",
            "m.compile_s", "m.c_source_bytes"]
    out = []
    for _, row in df.iterrows():
        out.append({"robot": row["robot"], "precision": row["o.precision"], "passed": bool(row["passed"]),
                    "error": row["error"], **{c[2:]: _plain(row.get(c)) for c in cols}})
    return out


def _validate(df: Any) -> list[dict[str, Any]]:
    cols = ["m.max_pct_err_q", "m.max_pct_err_qd", "m.max_pct_err_qdd", "m.growth_rate_per_s", "m.compared_samples"]
    return [{"robot": row["robot"], "gait": row["o.gait"], "error": row["error"], **{c[2:]: _plain(row.get(c)) for c in cols}}
            for _, row in df.iterrows()]


def _plain(x: Any) -> Any:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return None
    return x.item() if hasattr(x, "item") else x


def _control(df: Any) -> dict[str, Any]:
    ok = df[df["status"] == "ok"].copy()
    if ok.empty:
        return {}
    for column in ("m.fell", "m.first_sign", "m.time_to_fall_s", "m.tracking_rms_rad"):  # null in every row: no column
        if column not in ok:
            ok[column] = None
    ok["fell"] = ok["m.fell"].astype(bool)
    varying = [c for c in sorted(ok.columns) if c.startswith("p.") and ok[c].nunique() > 1]
    groups = []
    for (robot, gait, controller), g in ok.groupby(["robot", "o.gait", "o.controller"], sort=False):
        signs = g.loc[g["fell"], "m.first_sign"].fillna("none").value_counts().to_dict()
        groups.append({"robot": robot, "gait": gait, "controller": controller, **_rate(g["fell"]),
                       "first_sign_of_falls": signs, "tracking_rms_median_rad": _plain(g["m.tracking_rms_rad"].median()),
                       "time_to_fall_median_s": _plain(g.loc[g["fell"], "m.time_to_fall_s"].median())})
    bins = []
    for column in varying:
        edges = _bin_edges(ok[column], BINS)
        for (robot, gait, controller), g in ok.groupby(["robot", "o.gait", "o.controller"], sort=False):
            idx = _bin_index(g[column], edges)
            for b in range(BINS):
                sel = g["fell"][idx == b]
                bins.append({"robot": robot, "gait": gait, "controller": controller, "perturbation": column[2:],
                             "bin": [float(edges[b]), float(edges[b + 1])], **_rate(sel)})
    return {"perturbations": [c[2:] for c in varying], "controllers": groups, "bins": bins,
            "bins_2d": _bins_2d(ok, varying[:2]) if len(varying) >= 2 else []}


def _bins_2d(ok: Any, columns: list[str]) -> list[dict[str, Any]]:
    """Fall rate per (bin of the first, bin of the second) perturbation, per controller; the model's value per bin."""
    (a, b) = columns
    ea, eb = _bin_edges(ok[a], BINS_2D), _bin_edges(ok[b], BINS_2D)
    ok = ok.assign(_a=_bin_index(ok[a], ea), _b=_bin_index(ok[b], eb))
    out = []
    for (robot, gait), g in ok.groupby(["robot", "o.gait"], sort=False):
        for i in range(BINS_2D):
            for j in range(BINS_2D):
                cell = g[(g["_a"] == i) & (g["_b"] == j)]
                entry: dict[str, Any] = {"robot": robot, "gait": gait, a[2:]: [float(ea[i]), float(ea[i + 1])],
                                         b[2:]: [float(eb[j]), float(eb[j + 1])], "controllers": {}}
                for controller, c in cell.groupby("o.controller"):
                    entry["controllers"][controller] = _rate(c["fell"])
                pair = [entry["controllers"].get(n) for n in MODEL_PAIR]
                if all(p and p["runs"] for p in pair):
                    d, lo, hi = newcombe(pair[0]["falls"], pair[0]["runs"], pair[1]["falls"], pair[1]["runs"])  # type: ignore[index]
                    entry["model_value"] = {"difference": d, "ci95": [lo, hi], "of": f"{MODEL_PAIR[0]} - {MODEL_PAIR[1]}"}
                out.append(entry)
    return out


def summarise(df: Any) -> dict[str, Any]:
    """The sweep's summary (see the module docstring) from its rows."""
    out: dict[str, Any] = {"tasks": int(len(df)), "kinds": {}}
    if df.empty:
        return out
    for kind, g in df.groupby("kind", sort=False):
        ok = g[g["status"] == "ok"]
        out["kinds"][kind] = {"tasks": int(len(g)), "errors": int((g["status"] != "ok").sum()),
                              "failed_checks": int((ok["passed"] == False).sum()),  # noqa: E712 -- a column, not a bool
                              "wall_s_median": _plain(ok["wall_s"].median()), "cpu_s_median": _plain(ok["cpu_s"].median()),
                              "cpu_s_total": _plain(ok["cpu_s"].sum())}
        if kind == "check":
            out["check"] = _check(ok)
        elif kind == "codegen":
            out["codegen"] = _codegen(g)
        elif kind == "validate":
            out["validate"] = _validate(g)
        elif kind == "control":
            out["control"] = _control(g)
    errors = df[df["status"] != "ok"]
    out["errors"] = [{"key": r["key"], "kind": r["kind"], "robot": r["robot"], "error": r["error"]}
                     for _, r in errors.head(100).iterrows()]
    return out
