"""Numeric evaluation of the symbolic Functions with checked inputs and outputs.

CasADi Functions accept any numbers and return NaN or inf for a singular configuration
(coincident or collinear stance feet, a zero quaternion). ``guarded_call`` checks every input's
shape and finiteness and every quaternion (input ``q``'s entries 3:7, input ``quat``), and
refuses a non-finite result with a message saying what is singular.

``GuardedFunction`` is a CasADi Function whose numeric calls go through the same checks (the
public API: ``full_dynamics(robot).M_full_walker_orin(q)`` and the like); called on SX/MX it is the plain
Function, so it builds graphs and generates C as before. A GuardedFunction may carry a
``condition``: a check of the (checked) numeric inputs run before every numeric evaluation, for
configurations where the outputs would be finite nonsense rather than NaN (a GRF system that has
lost rank, an M_r with cond ~1e18): it raises an InputError saying what is singular.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.model.state import check_array, check_quaternion


def _shape(f: ca.Function, i: int) -> tuple[int, ...]:
    return (f.size1_in(i),) if f.size2_in(i) == 1 else (f.size1_in(i), f.size2_in(i))


def check_inputs(f: ca.Function, args: tuple[object, ...]) -> list[np.ndarray]:
    """``f``'s inputs as float arrays of its shapes, finite, with valid quaternions; or an InputError."""
    if len(args) != f.n_in():
        raise InputError(f"{f.name()} takes {f.n_in()} inputs {f.name_in()}; got {len(args)}")
    values = [check_array(f.name_in(i), x, _shape(f, i)) for i, x in enumerate(args)]
    for name, value in zip(f.name_in(), values):
        if name == "q":
            check_quaternion(name, value[3:7])
        elif name == "quat":
            check_quaternion(name, value)
    return values


def check_outputs(f: ca.Function, outs: list[np.ndarray]) -> None:
    bad = [f.name_out(i) for i, o in enumerate(outs) if not np.all(np.isfinite(o))]
    if bad:
        raise InputError(
            f"{f.name()} gives a non-finite {', '.join(bad)} here: a singular configuration (e.g. coincident or "
            "collinear stance feet) or inputs too large; expected feet spanning the support the model needs "
            "and inputs of physical size"
        )


def _check_condition(f: ca.Function, values: list[np.ndarray]) -> None:
    condition = getattr(f, "condition", None)
    if condition is not None:
        condition(values)


def guarded_call(f: ca.Function, *args: object) -> list[np.ndarray]:
    """Evaluate ``f`` on numeric inputs; returns its outputs as dense arrays (vectors 1-D)."""
    values = check_inputs(f, args)
    _check_condition(f, values)
    outs = [np.asarray(o.full()) for o in f.call([ca.DM(v) for v in values])]
    outs = [o.ravel() if o.shape[1] == 1 else o for o in outs]
    check_outputs(f, outs)
    return outs


class GuardedFunction(ca.Function):
    """A CasADi Function whose numeric calls are checked like ``guarded_call`` (InputError on a wrong
    shape, NaN/inf, a zero quaternion or a non-finite result); results as CasADi returns them
    (a DM, or a tuple of DM). Symbolic calls are not checked."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        if any(isinstance(x, ca.SX | ca.MX) for x in (*args, *kwargs.values())):
            return super().__call__(*args, **kwargs)
        if kwargs:
            unknown = sorted(set(kwargs) - set(self.name_in()))
            if args or unknown:
                raise InputError(f"{self.name()} takes inputs {self.name_in()} (all positional or all by name); "
                                 f"got {len(args)} positional and {sorted(kwargs)}")
            missing = [n for n in self.name_in() if n not in kwargs]
            if missing:
                raise InputError(f"{self.name()} takes inputs {self.name_in()}; {missing} missing")
            outs = guarded_call(self, *[kwargs[n] for n in self.name_in()])
            return {self.name_out(i): ca.DM(o) for i, o in enumerate(outs)}
        values = check_inputs(self, args)
        _check_condition(self, values)
        out = super().__call__(*values)
        check_outputs(self, [np.asarray(o) for o in (out if isinstance(out, tuple) else (out,))])
        return out


def with_condition(f: ca.Function, condition: Any) -> GuardedFunction:
    """``f`` as a GuardedFunction whose numeric calls first run ``condition(checked inputs)``."""
    guarded = GuardedFunction(f)
    guarded.condition = condition  # type: ignore[attr-defined]
    return guarded


def guard_fields(obj: object) -> None:
    """Make every ca.Function field of a frozen dataclass a GuardedFunction (call in __post_init__)."""
    for name, value in vars(obj).items():
        if isinstance(value, ca.Function) and not isinstance(value, GuardedFunction):
            object.__setattr__(obj, name, GuardedFunction(value))
