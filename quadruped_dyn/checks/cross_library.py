"""The same URDF through other libraries (Pinocchio as loaded, MuJoCo, iDynTree, Drake, adam),
with every disagreement explained.

For each library: first the **model diagnosis** (what the library does to the URDF: refuses
it and why, rebalances, regularises or derives inertias, fuses welded links), then the
comparison of its full-coordinate terms, converted to the project's conventions by its adapter
(``references/<library>.py``), on random states:

* ``max_rel_err``: vs Pinocchio on the original URDF;
* ``max_rel_err_vs_quadruped_dyn``: vs the toolkit's own symbolic terms;
* ``max_rel_err_same_model``: vs Pinocchio on the model the library was given (a copy of
  the URDF with the changes of ``model_changes`` that have ``in_comparison``), and
  ``model_change``: how far that copy's terms are from the original's (Pinocchio on both).

A term passes when it agrees on the same model (<= ``REL_TOL_TERMS``) and either agrees with
the original too or the difference is carried by a named model change (not one of
``EXACT_CHANGES``, which must not change the dynamics). A library that refuses even the edited copy is
reported (a ``refused`` change) and not compared; a term a library does not compute is listed
in ``not_computed`` with the reason. Errors are relative: max over states of
max |lib - ref| / max |ref| (non-finite values count as inf: a failure).

Terms (``references.interface.TERMS``): M (18 x 18), C + G (18,), G (18,), inverse dynamics
(18,), foot positions (4 x 3) and foot Jacobians (4 x 3 x 3, trunk frame, own joints).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.errors import InputError
from quadruped_dyn.math.compare import within
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.interface import TERMS, ModelChange, PinocchioTerms, Prepared, max_rel_errors, pinocchio_of
from quadruped_dyn.tolerances import REL_TOL_TERMS

#: Library name -> (adapter module, the PyPI package it needs).
LIBRARIES: dict[str, tuple[str, str]] = {
    "pinocchio": ("quadruped_dyn.references.pinocchio_urdf", "pinocchio"),
    "mujoco": ("quadruped_dyn.references.mujoco", "mujoco"),
    "idyntree": ("quadruped_dyn.references.idyntree", "idyntree"),
    "drake": ("quadruped_dyn.references.drake", "pydrake"),
    "adam": ("quadruped_dyn.references.adam", "adam"),
}
#: The PyPI distribution of each library's import name, for the install hint.
DISTRIBUTIONS = {"pinocchio": "pin", "pydrake": "drake", "adam": "adam-robotics"}
#: Model changes that must leave the dynamics as they are: never an explanation for a difference.
EXACT_CHANGES: tuple[str, ...] = ("merged_inertial", "fused_links", "links_as_frames", "accepted_as_is", "welded_bodies",
                                  "origin_added")
INSTALL_HINT = "pip install 'quadruped_dyn[xlib]'"


def parse_libraries(text: str) -> tuple[str, ...]:
    """'mujoco,idyntree' -> ('mujoco', 'idyntree'), 'all' -> every library; InputError for unknown
    or uninstalled ones."""
    names = tuple(dict.fromkeys(n.strip().lower() for n in text.split(",") if n.strip()))
    expected = f"expected all, or a comma-separated subset of: {', '.join(LIBRARIES)}"
    if not names:
        raise InputError(f"--against is empty; {expected}")
    if "all" in names:
        if len(names) > 1:
            raise InputError(f"--against '{text.strip()}' names all beside libraries; {expected}")
        names = tuple(LIBRARIES)
    for n in names:
        if n not in LIBRARIES:
            raise InputError(f"unknown library '{n}' in --against; {expected}")
    missing = [DISTRIBUTIONS.get(p, p) for p in (LIBRARIES[n][1] for n in names) if importlib.util.find_spec(p) is None]
    if missing:  # after the names: a typo is reported before a missing package
        raise InputError(f"--against {','.join(names)} needs the Python package(s) {', '.join(map(repr, missing))}, "
                         f"not installed; expected them installed: {INSTALL_HINT}")
    return names


class ToolkitDynamics:
    """The toolkit's own symbolic terms behind the ``Dynamics`` interface."""

    cannot: dict[str, str] = {}

    def __init__(self, robot: Robot) -> None:
        self.fd = full_dynamics(robot)
        self.kin = robot_kinematics(robot)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        return np.array(self.fd.M_full_walker_orin(q))

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.array(self.fd.C_full(q, v) + self.fd.G_full_newton_euler(q)).ravel()

    def gravity(self, q: np.ndarray) -> np.ndarray:
        return np.array(self.fd.G_full_newton_euler(q)).ravel()

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        w_res, tau = self.fd.id_full(q, v, a, np.zeros(12))
        return np.concatenate([np.array(w_res).ravel(), np.array(tau).ravel()])

    def foot_positions(self, q: np.ndarray) -> np.ndarray:
        return np.array([np.array(k.foot_position(q[7 + 3 * i : 10 + 3 * i])).ravel() for i, k in enumerate(self.kin)])

    def foot_jacobians(self, q: np.ndarray) -> np.ndarray:
        return np.array([np.array(k.foot_jacobian(q[7 + 3 * i : 10 + 3 * i])) for i, k in enumerate(self.kin)])


@dataclass
class CrossLibraryResult:
    library: str
    term: str
    max_rel_err: float  # vs Pinocchio, original URDF
    max_rel_err_vs_quadruped_dyn: float
    max_rel_err_same_model: float  # vs Pinocchio on the model the library was given
    model_change: float  # Pinocchio: that model vs the original
    explained_by: list[str]  # kinds of the model changes in the comparison that change the dynamics
    tol: float = REL_TOL_TERMS
    passed: bool = True


@dataclass
class CrossLibraryReport:
    robot: str
    samples: int
    seed: int
    results: list[CrossLibraryResult] = field(default_factory=list)
    changes: list[ModelChange] = field(default_factory=list)
    not_compared: dict[str, str] = field(default_factory=dict)  # library asked for -> why it compared nothing
    not_computed: dict[str, dict[str, str]] = field(default_factory=dict)  # library -> term -> why it has none

    @property
    def passed(self) -> bool:
        """Every comparison passed and every library asked for was compared: a library that
        refused the model (and every edited copy) is a failure, never a silent pass."""
        return all(r.passed for r in self.results) and not self.not_compared and bool(self.results)

    def conformance(self) -> dict[str, dict[str, dict[str, object]]]:
        """Library -> term -> the worst relative error vs Pinocchio on the original URDF and its
        status: 'agrees' (within tolerance), 'explained' (by the named model changes in
        ``explained_by``, the same-model rerun agreeing), 'unexplained', 'not computed' (``why``)
        or 'not compared' (the library refused the model: ``why``)."""
        table: dict[str, dict[str, dict[str, object]]] = {}
        for r in self.results:
            status = "unexplained" if not r.passed else "agrees" if within(r.max_rel_err, r.tol) else "explained"
            row: dict[str, object] = {"worst_rel_err": r.max_rel_err, "status": status}
            if status == "explained":
                row |= {"explained_by": r.explained_by, "worst_rel_err_same_model": r.max_rel_err_same_model}
            table.setdefault(r.library, {})[r.term] = row
        for library, terms in self.not_computed.items():
            for term, why in terms.items():
                table.setdefault(library, {})[term] = {"worst_rel_err": None, "status": "not computed", "why": why}
        for library, why in self.not_compared.items():
            table[library] = {t: {"worst_rel_err": None, "status": "not compared", "why": why} for t in TERMS}
        return table

    def as_dict(self) -> dict[str, object]:
        return {"cross_library": [asdict(r) for r in self.results], "model_changes": [asdict(c) for c in self.changes],
                "cross_library_not_compared": dict(self.not_compared), "cross_library_passed": self.passed,
                "conformance": self.conformance(), "cross_library_unexplained": sum(not r.passed for r in self.results)}

    def table(self) -> str:
        lines = [f"{'library':<10}{'term':<18}{'vs pinocchio':>13}{'vs ours':>10}{'same model':>12}{'model change':>14}  result"]
        for r in self.results:
            verdict = "pass" if r.passed else "FAIL"
            if r.passed and r.max_rel_err > r.tol:
                verdict += " (explained: " + ", ".join(r.explained_by) + ")"
            lines.append(f"{r.library:<10}{r.term:<18}{r.max_rel_err:>13.2e}{r.max_rel_err_vs_quadruped_dyn:>10.2e}"
                         f"{r.max_rel_err_same_model:>12.2e}{r.model_change:>14.2e}  {verdict}")
        for library, terms in self.not_computed.items():
            lines += [f"{library:<10}{term:<18}{'not computed: ' + why}" for term, why in terms.items()]
        for library, why in self.not_compared.items():
            lines.append(f"{library:<10}{'(nothing)':<18}{'not compared: ' + why}  FAIL")
        if self.changes:
            lines.append("model diagnosis:")
        for c in self.changes:
            size = ", ".join(f"{t} {v:.1e}" for t, v in c.size.items() if t != "foot Jacobians")
            lines.append(f"  {c.library:<10}{c.kind:<22}{c.detail}" + (f" [relative change: {size}]" if size else ""))
        verdict = ("every difference explained" if self.passed else
                   f"NOT COMPARED: {', '.join(self.not_compared)}" if self.not_compared else "SOME DIFFERENCES UNEXPLAINED")
        lines.append(f"{self.robot}: cross-library check on {self.samples} random states (seed {self.seed}), "
                     f"tolerance {REL_TOL_TERMS:.0e}: {verdict}")
        return "\n".join(lines)


def run_cross_library(robot: Robot, libraries: Sequence[str], samples: int = 20, seed: int = 0) -> CrossLibraryReport:
    """Diagnose and compare each library (names from ``parse_libraries``) on the same random states."""
    rng = np.random.default_rng(seed)
    states = [random_state(robot.lower, robot.upper, rng) for _ in range(samples)]
    pin_ref = PinocchioTerms(robot)
    ours = ToolkitDynamics(robot)
    report = CrossLibraryReport(robot.name, samples, seed)
    for name in libraries:
        adapter = importlib.import_module(LIBRARIES[name][0])
        prepared: Prepared = adapter.prepare(robot, states, pin_ref)
        report.changes += prepared.changes
        if prepared.reference is None:
            refusals = [c.detail for c in prepared.changes if c.library == name and c.kind == "refused"]
            report.not_compared[name] = (refusals[-1] if refusals else "it produced no model to compare")[:300]
            continue
        lib = prepared.reference
        same_ref = pin_ref if prepared.compared_urdf is None else pinocchio_of(prepared.compared_urdf)
        vs_pin = max_rel_errors(lib, pin_ref, states)
        vs_ours = max_rel_errors(lib, ours, states)
        vs_same = vs_pin if same_ref is pin_ref else max_rel_errors(lib, same_ref, states)
        change = dict.fromkeys(TERMS, 0.0) if same_ref is pin_ref else max_rel_errors(same_ref, pin_ref, states)
        applied = [c.kind for c in prepared.changes if c.in_comparison and c.kind not in EXACT_CHANGES]
        if lib.cannot:
            report.not_computed[name] = dict(lib.cannot)
        for t in vs_pin:
            explained = bool(applied) and not within(change[t], REL_TOL_TERMS)
            passed = within(vs_same[t], REL_TOL_TERMS) and (within(vs_pin[t], REL_TOL_TERMS) or explained)
            report.results.append(CrossLibraryResult(name, t, vs_pin[t], vs_ours[t], vs_same[t], change[t], applied,
                                                     passed=passed))
    return report
