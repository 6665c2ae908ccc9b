"""The summary's statistics against published values, and its counts on a dataset made here."""

from __future__ import annotations

import json

import pytest

from quadruped_dyn.sweep.page import page
from quadruped_dyn.sweep.summary import BINS, BINS_2D, newcombe, summarise, wilson

pd = pytest.importorskip("pandas")


@pytest.mark.parametrize(("k", "n", "lo", "hi"), [(0, 10, 0.0, 0.2775), (81, 263, 0.2553, 0.3662), (15, 148, 0.0624, 0.1605)])
def test_wilson_interval_matches_newcombe_1998(k, n, lo, hi):
    """Newcombe, Statistics in Medicine 17 (1998) 857, Table II, method 3 (score interval)."""
    assert wilson(k, n) == pytest.approx((lo, hi), abs=1e-4)


@pytest.mark.parametrize("n", [1, 3, 7, 10, 25, 200, 1000])
def test_wilson_interval_holds_the_proportion(n):
    for k in range(n + 1):
        lo, hi = wilson(k, n)
        assert 0.0 <= lo <= k / n <= hi <= 1.0


def test_difference_interval_matches_newcombe_1998():
    """Newcombe, Statistics in Medicine 17 (1998) 873, example (a) 56/70 - 48/80, method 10."""
    d, lo, hi = newcombe(56, 70, 48, 80)
    assert (d, lo, hi) == pytest.approx((0.2, 0.0524, 0.3339), abs=1e-4)


def _row(controller: str, mass: float, mu: float, fell: bool) -> dict:
    return {"key": f"control-{controller}-{mass}-{mu}", "kind": "control", "robot": "paper", "status": "ok", "passed": None,
            "error": None, "wall_s": 1.0, "cpu_s": 1.0, "o.gait": "walk", "o.controller": controller, "p.mass_scale": mass,
            "p.mu": mu, "m.fell": fell, "m.first_sign": "trunk tilt" if fell else None, "m.time_to_fall_s": 1.0 if fell else None,
            "m.tracking_rms_rad": 0.01, "metrics": json.dumps({})}


def test_control_summary_without_a_fall():
    rows = [{k: v for k, v in _row(c, 1.0 + i / 10, 0.5, fell=False).items() if v is not None or not k.startswith("m.")}
            for c in ("pd", "ct-diag") for i in range(3)]
    c = summarise(pd.DataFrame(rows))["control"]
    assert [(g["falls"], g["runs"], g["time_to_fall_median_s"]) for g in c["controllers"]] == [(0, 3, None)] * 2


def _mass_mu_rows() -> list[dict]:
    """40 (mass, mu) samples spread over [0.7, 1.3] x [0.3, 1.0]; ct-diag falls above a mass of 1.2, pd-diag above 1.0."""
    rows = []
    for i in range(40):
        mass, mu = 0.7 + 0.6 * i / 39, 0.3 + 0.7 * ((7 * i) % 40) / 39
        rows.append(_row("ct-diag", mass, mu, fell=mass > 1.2))
        rows.append(_row("pd-diag", mass, mu, fell=mass > 1.0))
    return rows


def test_control_summary_counts_falls_per_bin_and_the_models_value():
    rows = _mass_mu_rows()
    s = summarise(pd.DataFrame(rows))
    c = s["control"]
    assert c["perturbations"] == ["mass_scale", "mu"]
    by = {g["controller"]: g for g in c["controllers"]}
    falls = (sum(r["m.fell"] for r in rows[::2]), sum(r["m.fell"] for r in rows[1::2]))
    assert (by["ct-diag"]["falls"], by["pd-diag"]["falls"]) == falls
    mass_bins = [b for b in c["bins"] if b["perturbation"] == "mass_scale" and b["controller"] == "pd-diag"]
    assert len(mass_bins) == BINS and sum(b["runs"] for b in mass_bins) == 40 and mass_bins[0]["falls"] == 0
    assert mass_bins[-1]["fall_rate"] == 1.0
    cells = [x for x in c["bins_2d"] if x["controllers"]]
    assert sum(x["controllers"]["ct-diag"]["runs"] for x in cells) == 40
    assert all(x["model_value"]["difference"] <= 0 for x in cells)  # ct-diag never falls where pd-diag holds here
    assert s["kinds"]["control"] == {"tasks": 80, "errors": 0, "failed_checks": 0, "wall_s_median": 1.0, "cpu_s_median": 1.0,
                                     "cpu_s_total": 80.0}


def test_page_shows_each_bins_falls_with_interval_and_the_models_value():
    """The heaviest, least slippery-proof cell (top third of the masses, bottom third of mu), counted here from the
    rows, is on the page with each controller's Wilson interval and ct-diag - pd-diag with Newcombe's; the holds table
    has each controller's falls and their first sign."""
    df = pd.DataFrame(_mass_mu_rows())
    html = page("walk_robustness", summarise(df))
    mass, mu = df["p.mass_scale"], df["p.mu"]
    heavy = mass >= mass.min() + (mass.max() - mass.min()) * (BINS_2D - 1) / BINS_2D
    slippery = mu < mu.min() + (mu.max() - mu.min()) / BINS_2D
    counts = {}
    for c in ("ct-diag", "pd-diag"):
        cell = df[(df["o.controller"] == c) & heavy & slippery]
        counts[c] = (int(cell["m.fell"].sum()), len(cell))
        lo, hi = wilson(*counts[c])
        assert f"{c} {counts[c][0]}/{counts[c][1]} ({lo:.2f}-{hi:.2f})" in html
    assert 0 < counts["ct-diag"][0] < counts["pd-diag"][0]  # a cell where the two differ: not a comparison of zeros
    d, lo, hi = newcombe(*counts["ct-diag"], *counts["pd-diag"])
    assert f"{d:+.2f} [{lo:+.2f}, {hi:+.2f}]" in html
    for c in ("ct-diag", "pd-diag"):
        falls = int(df.loc[df["o.controller"] == c, "m.fell"].sum())
        assert f"fell {falls}/40: trunk tilt {falls}" in html
