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

TERMS: tuple[str, ...] = ("M", "C+G", "G", "foot Jacobians")

class Dynamics(Protocol):
    """Full-coordinate terms in the project's conventions (``state``), project joint order."""

    def mass_matrix(self, q: np.ndarray) -> np.ndarray: ...
    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray: ...
    def gravity(self, q: np.ndarray) -> np.ndarray: ...
    def foot_jacobians(self, q: np.ndarray) -> np.ndarray: ...

def terms_at(src: Dynamics, s: FullState) -> dict[str, np.ndarray]:
    return {"M": src.mass_matrix(s.q), "C+G": src.nonlinear_effects(s.q, s.v), "G": src.gravity(s.q),
            "foot Jacobians": src.foot_jacobians(s.q)}

def max_rel_errors(src: Dynamics, ref: Dynamics, states: Sequence[FullState]) -> dict[str, float]:
    """Per term, the largest ``compare.relative_error`` of src against ref over the states
    (max |src - ref| / max |ref|, absolute where ref is zero; inf for a non-finite value)."""
    out = dict.fromkeys(TERMS, 0.0)
    for s in states:
        ours, theirs = terms_at(src, s), terms_at(ref, s)
        for t in TERMS:
            out[t] = max(out[t], relative_error(ours[t], theirs[t]))
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
