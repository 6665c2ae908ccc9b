"""The same URDF through other libraries (MuJoCo, iDynTree), with every disagreement explained.

For each library: first the **model diagnosis** (what the library does to the URDF: refuses
it and why, rebalances or derives inertias, fuses welded links), then the comparison of its
full-coordinate terms, converted to the project's conventions by its adapter
(``mujoco_ref``, ``idyntree_ref``), on random states:

* ``max_rel_err``: vs Pinocchio on the original URDF;
* ``max_rel_err_vs_quadruped_dyn``: vs the toolkit's own symbolic terms;
* ``max_rel_err_same_model``: vs Pinocchio on the model the library was given (a copy of
  the URDF with the changes of ``model_changes`` that have ``in_comparison``), and
  ``model_change``: how far that copy's terms are from the original's (Pinocchio on both).

A term passes when it agrees on the same model (<= ``REL_TOL_TERMS``) and either agrees with
the original too or the difference is carried by a named model change (not one of
``EXACT_CHANGES``, which must not change the dynamics). A library that refuses even the edited copy is
reported (a ``refused`` change) and not compared. Errors are relative:
max over states of max |lib - ref| / max |ref| (non-finite values count as inf: a failure).

Terms: M (18 x 18), C + G (18,), G (18,), foot Jacobians (4 x 3 x 3, trunk frame, own joints).
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
from quadruped_dyn.references.interface import TERMS, ModelChange, Prepared, max_rel_errors, pinocchio_of
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_TERMS

#: Library name -> (adapter module, the PyPI package it needs).
LIBRARIES: dict[str, tuple[str, str]] = {
    "mujoco": ("quadruped_dyn.references.mujoco", "mujoco"),
    "idyntree": ("quadruped_dyn.references.idyntree", "idyntree"),
}
#: Model changes that must leave the dynamics as they are: never an explanation for a difference.
EXACT_CHANGES: tuple[str, ...] = ("merged_inertial", "fused_links", "links_as_frames", "accepted_as_is")
INSTALL_HINT = "pip install 'quadruped_dyn[xlib]'"


def parse_libraries(text: str) -> tuple[str, ...]:
    """'mujoco,idyntree' -> ('mujoco', 'idyntree'); InputError for unknown or uninstalled ones."""
    names = tuple(dict.fromkeys(n.strip().lower() for n in text.split(",") if n.strip()))
    if not names:
        raise InputError(f"--against is empty; expected a comma-separated subset of: {', '.join(LIBRARIES)}")
    for n in names:
        if n not in LIBRARIES:
            raise InputError(f"unknown library '{n}' in --against; expected a comma-separated subset of: {', '.join(LIBRARIES)}")
    missing = [LIBRARIES[n][1] for n in names if importlib.util.find_spec(LIBRARIES[n][1]) is None]
    if missing:  # after the names: a typo is reported before a missing package
        raise InputError(f"--against {','.join(names)} needs the Python package(s) {', '.join(map(repr, missing))}, "
                         f"not installed; expected them installed: {INSTALL_HINT}")
    return names


class ToolkitDynamics:
    """The toolkit's own symbolic terms behind the ``Dynamics`` interface."""

    def __init__(self, robot: Robot) -> None:
        self.fd = full_dynamics(robot)
        self.kin = robot_kinematics(robot)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        return np.array(self.fd.M_full(q))

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.array(self.fd.C_full(q, v) + self.fd.G_full(q)).ravel()

    def gravity(self, q: np.ndarray) -> np.ndarray:
        return np.array(self.fd.G_full(q)).ravel()

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

    @property
    def passed(self) -> bool:
        """Every comparison passed and every library asked for was compared: a library that
        refused the model (and every edited copy) is a failure, never a silent pass."""
        return all(r.passed for r in self.results) and not self.not_compared and bool(self.results)

    def as_dict(self) -> dict[str, object]:
        return {"cross_library": [asdict(r) for r in self.results], "model_changes": [asdict(c) for c in self.changes],
                "cross_library_not_compared": dict(self.not_compared), "cross_library_passed": self.passed}

    def table(self) -> str:
        lines = [f"{'library':<10}{'term':<16}{'vs pinocchio':>13}{'vs ours':>10}{'same model':>12}{'model change':>14}  result"]
        for r in self.results:
            verdict = "pass" if r.passed else "FAIL"
            if r.passed and r.max_rel_err > r.tol:
                verdict += " (explained: " + ", ".join(r.explained_by) + ")"
            lines.append(f"{r.library:<10}{r.term:<16}{r.max_rel_err:>13.2e}{r.max_rel_err_vs_quadruped_dyn:>10.2e}"
                         f"{r.max_rel_err_same_model:>12.2e}{r.model_change:>14.2e}  {verdict}")
        for library, why in self.not_compared.items():
            lines.append(f"{library:<10}{'(nothing)':<16}{'not compared: ' + why}  FAIL")
        if self.changes:
            lines.append("model diagnosis:")
        for c in self.changes:
            size = ", ".join(f"{t} {v:.1e}" for t, v in c.size.items() if t != "foot Jacobians")
            lines.append(f"  {c.library:<9}{c.kind:<17}{c.detail}" + (f" [relative change: {size}]" if size else ""))
        verdict = ("every difference explained" if self.passed else
                   f"NOT COMPARED: {', '.join(self.not_compared)}" if self.not_compared else "SOME DIFFERENCES UNEXPLAINED")
        lines.append(f"{self.robot}: cross-library check on {self.samples} random states (seed {self.seed}), "
                     f"tolerance {REL_TOL_TERMS:.0e}: {verdict}")
        return "\n".join(lines)


def run_cross_library(robot: Robot, libraries: Sequence[str], samples: int = 20, seed: int = 0) -> CrossLibraryReport:
    """Diagnose and compare each library (names from ``parse_libraries``) on the same random states."""
    rng = np.random.default_rng(seed)
    states = [random_state(robot.lower, robot.upper, rng) for _ in range(samples)]
    pin_ref = PinocchioReference(robot)
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
        for t in TERMS:
            explained = bool(applied) and not within(change[t], REL_TOL_TERMS)
            passed = within(vs_same[t], REL_TOL_TERMS) and (within(vs_pin[t], REL_TOL_TERMS) or explained)
            report.results.append(CrossLibraryResult(name, t, vs_pin[t], vs_ours[t], vs_same[t], change[t], applied,
                                                     passed=passed))
    return report
