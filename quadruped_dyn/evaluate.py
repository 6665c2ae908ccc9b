"""Numeric evaluation of the symbolic Functions with checked inputs and outputs.

CasADi Functions accept any numbers and return NaN or inf for a singular configuration
(coincident or collinear stance feet, a zero quaternion). ``evaluate`` checks every input's
shape and finiteness and refuses a non-finite result with a message saying what is singular.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .errors import InputError
from .state import check_array


def evaluate(f: ca.Function, *args: object) -> list[np.ndarray]:
    """Evaluate ``f`` on numeric inputs; returns its outputs as dense arrays (vectors 1-D)."""
    if len(args) != f.n_in():
        raise InputError(f"{f.name()} takes {f.n_in()} inputs {f.name_in()}; got {len(args)}")
    values = [
        check_array(f.name_in(i), x, (f.size1_in(i),) if f.size2_in(i) == 1 else (f.size1_in(i), f.size2_in(i)))
        for i, x in enumerate(args)
    ]
    if f.n_in() and f.name_in(0) == "q" and np.linalg.norm(values[0][3:7]) == 0.0:
        raise InputError("q has a zero quaternion; expected (x, y, z, w) of a rotation")
    out = f(*values)
    outs = [np.asarray(o.full()) for o in (out if isinstance(out, tuple) else [out])]
    outs = [o.ravel() if o.shape[1] == 1 else o for o in outs]
    bad = [f.name_out(i) for i, o in enumerate(outs) if not np.all(np.isfinite(o))]
    if bad:
        raise InputError(
            f"{f.name()} is singular at this configuration ({', '.join(bad)} not finite): e.g. coincident or "
            "collinear stance feet; expected feet spanning the support the model needs"
        )
    return outs
