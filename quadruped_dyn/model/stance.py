"""Stance sets: which feet are on the ground, and the paper's GRF parameterisation of each (docs/formulation.md §4)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.model.leg import LEG_LABELS

GRF_MODELS: tuple[str, ...] = ("paper", "min_norm")

@dataclass(frozen=True)
class StanceSet:
    """The feet on the ground, as indices into (FL, FR, BL, BR)."""

    feet: tuple[int, ...]

    @property
    def name(self) -> str:
        return "+".join(LEG_LABELS[i] for i in self.feet) or "none"

    @property
    def kind(self) -> str:
        k = len(self.feet)
        if k == 4:
            return "stand"
        if k == 3:
            return f"walk (lifted {LEG_LABELS[self.lifted[0]]})"
        if k == 2:
            a, b = (LEG_LABELS[i] for i in self.feet)
            if a[0] != b[0] and a[1] != b[1]:
                return "trot (diagonal)"
            return "pace (lateral)" if a[1] == b[1] else ("front" if a[0] == "F" else "back")
        return "one foot" if k == 1 else "flight"

    @property
    def lifted(self) -> tuple[int, ...]:
        return tuple(i for i in range(4) if i not in self.feet)

    def selection(self, model: str) -> np.ndarray:
        """P (3k, n): stacked stance-foot forces (trunk frame) = P lambda."""
        k = len(self.feet)
        if model not in GRF_MODELS:
            raise InputError(f"unknown GRF model '{model}'; expected one of {GRF_MODELS}")
        if model == "min_norm" or k < 3:
            return np.eye(3 * k)
        P = np.zeros((3 * k, 6))
        for j in range(k):
            P[3 * j + 2, j] = 1.0  # own fz
            P[3 * j + 0, k] = 1.0  # common fx
        if k == 4:
            P[1::3, 5] = 1.0  # common fy
        else:  # k == 3: the foot on the lifted leg's side has its own fy
            side = LEG_LABELS[self.lifted[0]][1]
            for j, foot in enumerate(self.feet):
                P[3 * j + 1, 4 if LEG_LABELS[foot][1] == side else 5] = 1.0
        return P

    def rank(self, model: str) -> int:
        """Structural rank of A = G P (feet in general position)."""
        k = len(self.feet)
        if k == 2 or (k == 4 and model == "paper"):
            return 5
        return min(6, self.selection(model).shape[1])

#: All 16 stance sets: four feet, the four static-walk triples, the six pairs, singles, none.
STANCE_SETS: tuple[StanceSet, ...] = tuple(
    StanceSet(feet) for k in (4, 3, 2, 1, 0) for feet in itertools.combinations(range(4), k)
)

def stance_set(name: str | StanceSet) -> StanceSet:
    """Look up a stance set by name, e.g. 'FL+BR' (order-insensitive) or 'none', or check one
    built by hand (``StanceSet((0, 3))``: increasing feet of (FL, FR, BL, BR), one of STANCE_SETS)."""
    if isinstance(name, StanceSet):
        if name not in STANCE_SETS:
            raise InputError(f"stance set {name!r} is not one of the 16; expected increasing, distinct foot indices "
                             "0-3 (FL, FR, BL, BR), or a name such as 'FL+BR'")
        return name
    if not isinstance(name, str):
        raise InputError(f"stance set is {type(name).__name__} {name!r}; expected a name such as 'FL+BR' "
                         "(feet joined by '+') or 'none'")
    wanted = sorted(name.split("+")) if name != "none" else []
    for s in STANCE_SETS:
        if sorted(LEG_LABELS[i] for i in s.feet) == wanted:
            return s
    raise InputError(f"unknown stance set '{name}'; expected feet joined by '+' from {LEG_LABELS}, or 'none'")
