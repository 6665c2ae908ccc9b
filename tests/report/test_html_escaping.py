"""The report page contains no markup from input: a page built from hostile names
in every field that reaches it has exactly the elements of the same page built from harmless
names; a non-finite error value is shown, not raised on (item 20)."""

from __future__ import annotations

from html.parser import HTMLParser

import pytest

from quadruped_dyn.report import sections as rs
from quadruped_dyn.report.build import _failed
from quadruped_dyn.report.html import page, table

HOSTILE = ['<td><script>alert(1)</script>', '"><img src=x onerror=alert(2)>', "<td class=x>", "</table><b>",
           "&lt;i&gt;", "<!-- x -->", "<![CDATA[y]]>", "<svg onload=alert(3)>"]


class _Elements(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.elements: list[tuple[str, tuple[str, ...]]] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.elements.append((tag, tuple(name for name, _ in attrs)))

    def handle_comment(self, data: str) -> None:
        self.elements.append(("<!--", ()))


def _elements(text: str) -> list[tuple[str, tuple[str, ...]]]:
    parser = _Elements()
    parser.feed(text)
    return parser.elements


def _page(name: str) -> str:
    """Every section the page has, fed ``name`` in every field that comes from input."""
    legs = [{"label": label, "joints": [name, name, name], "foot_frame": name, "thigh_length_m": 0.2,
             "shank_length_m": 0.2, "link_masses_kg": [0.1, 0.2, 0.3], "foot_position_standing_m": [0.1, 0.1, -0.2]}
            for label in ("FL", "FR", "BL", "BR")]
    info = {"name": name, "urdf": f"/tmp/{name}.urdf", "total_mass_kg": 10.0, "trunk_mass_kg": 5.0, "legs": legs,
            "joints": [{"name": name, "leg": "FL", "role": "HAA", "lower": -1.0, "upper": 1.0, "standing": 0.0}],
            "warnings": [f"{name}: a warning"]}
    check = {"terms": [{"name": name, "max_abs_err": float("nan"), "max_rel_err": None, "tol": 1e-10, "passed": False},
                       {"name": "M_full", "max_abs_err": 1e-15, "max_rel_err": float("inf"), "tol": 1e-10, "passed": False}],
             "samples": 2, "seed": 0, "passed": False, "cross_library": [{"library": name, "term": name, "passed": False}]}
    joint_names = [name] * 12
    validation = {"horizon_s": 1.0, "integrator": name, "max_pct_err": {name: {"q": 1.0, "qd": None, "qdd": 2.0}},
                  "max_pct_err_overall": {"q": 1.0}, "runs": {name: {"departs_1pct_at_s": 0.1, "stopped_at_s": None}},
                  "instability": {name: [name, 1.0]}, "physics_check": {name: {name: name}}}
    sections = [
        rs.robot_section(info, ""),
        rs.terms_section(check),
        rs.reduced_section([{"stance": name, "kind": name, "n": 12, "cond": 1.0, "asymmetry": 0.1, "err": 1e-15,
                             "singular": name}], name),
        rs.experiment_section({name: validation}, joint_names, {}),
        _failed("c", "Generated C", RuntimeError(f"robot '{name}' failed")),
        rs.versions_section({"machine": {name: name}, "libraries": {name: name}}),
    ]
    return page(f"quadruped_dyn report: {name}", f"/tmp/{name}.urdf", sections) + table([name], [[name], [name]], name)


@pytest.mark.parametrize("hostile", HOSTILE)
def test_no_element_from_input(hostile):
    harmless, attacked = _page("robot"), _page(hostile)
    assert _elements(attacked) == _elements(harmless), "input changed the page's elements"
    assert "<script" not in attacked and "onerror=" not in attacked.replace("onerror=alert(2)&gt;", "")


def test_non_finite_errors_are_shown():
    section = rs.terms_section({"terms": [{"name": "M_full", "max_abs_err": None, "max_rel_err": None, "tol": 1e-10,
                                           "passed": False},
                                          {"name": "C_full", "max_abs_err": float("nan"), "max_rel_err": float("nan"),
                                           "tol": 1e-10, "passed": False}],
                                "samples": 1, "seed": 0, "passed": True})
    assert section.verdict == "FAIL" and "worst rel err inf" in section.headline and "n/a" in section.body
