"""What every reference library's adapter provides: full-coordinate terms in the project's
conventions, and the model changes the library made."""

from __future__ import annotations

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from quadruped_dyn.math.compare import relative_error
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import FullState
from quadruped_dyn.references.pinocchio import PinocchioReference

TERMS: tuple[str, ...] = ("M", "C+G", "G", "inverse dynamics", "foot positions", "foot Jacobians")


class Dynamics(Protocol):
    """Full-coordinate terms in the project's conventions (``state``), project joint order: M (18, 18),
    C + G (18,), G (18,), inverse dynamics tau = M a + C + G (18,) with a = vdot, foot positions
    (4, 3) relative to the trunk origin and foot Jacobians (4, 3, 3) w.r.t. each leg's own joints,
    both in the trunk frame. ``cannot`` names the terms the library does not compute, and why."""

    cannot: dict[str, str]

    def mass_matrix(self, q: np.ndarray) -> np.ndarray: ...
    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...
    def gravity(self, q: np.ndarray) -> np.ndarray: ...
    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray: ...
    def foot_positions(self, q: np.ndarray) -> np.ndarray: ...
    def foot_jacobians(self, q: np.ndarray) -> np.ndarray: ...


def computed_terms(src: Dynamics) -> tuple[str, ...]:
    return tuple(t for t in TERMS if t not in src.cannot)


def terms_at(src: Dynamics, s: FullState, terms: Sequence[str] = TERMS) -> dict[str, np.ndarray]:
    """The terms of ``src`` at the state (only those in ``terms``)."""
    evaluate = {"M": lambda: src.mass_matrix(s.q), "C+G": lambda: src.nonlinear_effects(s.q, s.v),
                "G": lambda: src.gravity(s.q), "inverse dynamics": lambda: src.inverse_dynamics(s.q, s.v, s.a),
                "foot positions": lambda: src.foot_positions(s.q), "foot Jacobians": lambda: src.foot_jacobians(s.q)}
    return {t: evaluate[t]() for t in terms}


def max_rel_errors(src: Dynamics, ref: Dynamics, states: Sequence[FullState]) -> dict[str, float]:
    """Per term both compute, the largest ``compare.relative_error`` of src against ref over the
    states (max |src - ref| / max |ref|, absolute where ref is zero; inf for a non-finite value)."""
    terms = [t for t in computed_terms(src) if t not in ref.cannot]
    out = dict.fromkeys(terms, 0.0)
    for s in states:
        ours, theirs = terms_at(src, s, terms), terms_at(ref, s, terms)
        for t in terms:
            out[t] = max(out[t], relative_error(ours[t], theirs[t]))
    return out


class PinocchioTerms(PinocchioReference):
    """Pinocchio behind the ``Dynamics`` interface (inverse dynamics: ``rnea``)."""

    name = "pinocchio"
    cannot: dict[str, str] = {}

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        return self.rnea(q, v, a)


def pinocchio_of(urdf_text: str) -> PinocchioTerms:
    """Pinocchio on a URDF copy (loaded like any robot: validated, placements snapped)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "copy.urdf"
        path.write_text(urdf_text)
        robot = load_robot(str(path), cached=False)  # a temporary file
    return PinocchioTerms(robot)

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
