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
import tempfile
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from .errors import InputError
from .kinematics import robot_kinematics
from .newton_euler import full_dynamics
from .pinocchio_ref import PinocchioReference
from .robot import Robot, load_robot
from .state import FullState, random_state
from .tolerances import REL_TOL_TERMS

#: Library name -> (adapter module, the PyPI package it needs).
LIBRARIES: dict[str, tuple[str, str]] = {
    "mujoco": ("quadruped_dyn.mujoco_ref", "mujoco"),
    "idyntree": ("quadruped_dyn.idyntree_ref", "idyntree"),
}
TERMS: tuple[str, ...] = ("M", "C+G", "G", "foot Jacobians")
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


class Dynamics(Protocol):
    """Full-coordinate terms in the project's conventions (``state``), project joint order."""

    def mass_matrix(self, q: np.ndarray) -> np.ndarray: ...
    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...
    def gravity(self, q: np.ndarray) -> np.ndarray: ...
    def foot_jacobians(self, q: np.ndarray) -> np.ndarray: ...


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


def evaluate(src: Dynamics, s: FullState) -> dict[str, np.ndarray]:
    return {"M": src.mass_matrix(s.q), "C+G": src.nonlinear_effects(s.q, s.v), "G": src.gravity(s.q),
            "foot Jacobians": src.foot_jacobians(s.q)}


def rel_err(x: np.ndarray, ref: np.ndarray) -> float:
    """max |x - ref| / max |ref| (scale 1 if ref is zero); inf if either has a non-finite entry."""
    x, ref = np.asarray(x, dtype=float), np.asarray(ref, dtype=float)
    if x.shape != ref.shape:
        raise AssertionError(f"shape {x.shape} vs reference {ref.shape}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(ref))):
        return float("inf")
    return float(np.abs(x - ref).max()) / (float(np.abs(ref).max()) or 1.0)


def max_rel_errors(src: Dynamics, ref: Dynamics, states: Sequence[FullState]) -> dict[str, float]:
    """Per term, the largest ``rel_err`` of src against ref over the states."""
    out = dict.fromkeys(TERMS, 0.0)
    for s in states:
        ours, theirs = evaluate(src, s), evaluate(ref, s)
        for t in TERMS:
            out[t] = max(out[t], rel_err(ours[t], theirs[t]))
    return out


def pinocchio_of(urdf_text: str) -> PinocchioReference:
    """Pinocchio on a URDF copy (loaded like any robot: validated, placements snapped)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "copy.urdf"
        path.write_text(urdf_text)
        robot = load_robot(str(path), cached=False)  # a temporary file
    return PinocchioReference(robot)


@dataclass
class ModelChange:
    """What a library does to the URDF, named, with its measured size where it changes the model."""

    library: str
    kind: str  # refused | merged_inertial | balanced_inertia | balanceinertia | inertiafromgeom | fused_links | ...
    links: list[str]
    detail: str
    in_comparison: bool  # the compared model carries this change
    size: dict[str, float] = field(default_factory=dict)  # term -> max relative change; {} when none is measured


@dataclass
class Prepared:
    """An adapter's answer: the library's terms (None if it refused every copy), what it did to
    the model, and the URDF text it was compared on (None: the original, geometry aside)."""

    reference: Dynamics | None
    changes: list[ModelChange]
    compared_urdf: str | None = None


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

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)

    def as_dict(self) -> dict[str, object]:
        return {"cross_library": [asdict(r) for r in self.results], "model_changes": [asdict(c) for c in self.changes],
                "cross_library_passed": self.passed}

    def table(self) -> str:
        lines = [f"{'library':<10}{'term':<16}{'vs pinocchio':>13}{'vs ours':>10}{'same model':>12}{'model change':>14}  result"]
        for r in self.results:
            verdict = "pass" if r.passed else "FAIL"
            if r.passed and r.max_rel_err > r.tol:
                verdict += " (explained: " + ", ".join(r.explained_by) + ")"
            lines.append(f"{r.library:<10}{r.term:<16}{r.max_rel_err:>13.2e}{r.max_rel_err_vs_quadruped_dyn:>10.2e}"
                         f"{r.max_rel_err_same_model:>12.2e}{r.model_change:>14.2e}  {verdict}")
        if self.changes:
            lines.append("model diagnosis:")
        for c in self.changes:
            size = ", ".join(f"{t} {v:.1e}" for t, v in c.size.items() if t != "foot Jacobians")
            lines.append(f"  {c.library:<9}{c.kind:<17}{c.detail}" + (f" [relative change: {size}]" if size else ""))
        verdict = "every difference explained" if self.passed else "SOME DIFFERENCES UNEXPLAINED"
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
            continue
        lib = prepared.reference
        same_ref = pin_ref if prepared.compared_urdf is None else pinocchio_of(prepared.compared_urdf)
        vs_pin = max_rel_errors(lib, pin_ref, states)
        vs_ours = max_rel_errors(lib, ours, states)
        vs_same = vs_pin if same_ref is pin_ref else max_rel_errors(lib, same_ref, states)
        change = dict.fromkeys(TERMS, 0.0) if same_ref is pin_ref else max_rel_errors(same_ref, pin_ref, states)
        applied = [c.kind for c in prepared.changes if c.in_comparison and c.kind not in EXACT_CHANGES]
        for t in TERMS:
            passed = vs_same[t] <= REL_TOL_TERMS and (vs_pin[t] <= REL_TOL_TERMS or (bool(applied) and change[t] > REL_TOL_TERMS))
            report.results.append(CrossLibraryResult(name, t, vs_pin[t], vs_ours[t], vs_same[t], change[t], applied,
                                                     passed=passed))
    return report
