"""Errors the toolkit raises (the CLI maps them to exit codes and a one-line message), and the
check of an option's kind that every option's own range check starts with."""

import numbers


class InputError(ValueError):
    """Bad input (exit code 2): says what was found and what was expected, in one line."""


class NumericalError(ArithmeticError):
    """A numerical outcome, not bad input (exit code 1): the inputs were valid, but the computation
    cannot go on there, e.g. M_r singular at a configuration, an integrator that fails, rigid
    contacts whose KKT system is singular, or another library disagreeing with Pinocchio.
    Says what failed and where, in one line."""


class BuildError(RuntimeError):
    """A compiler or harness failed (exit code 1): says which command and why. A missing
    compiler is an InputError (exit code 2): the environment, not a check, is wrong."""


class UrdfWarning(UserWarning):
    """A URDF oddity that does not change the answers (e.g. an unphysical inertia of a link
    merged into a physical body); the CLI prints it as one line."""


def real_number(what: str, value: object) -> float:
    """``value`` as a float, or an InputError unless it is a real number (not a bool, a string, a
    complex or None: ``math.isfinite`` raised TypeError on those, a bool passed as 0 or 1); its range
    is the caller's to check."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{what} is {value!r}, a {type(value).__name__}; expected a real number")
    return float(value)


def whole_number(what: str, value: object) -> int:
    """``value`` as an int, or an InputError unless it is an integer (not a bool, not a float)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{what} is {value!r}, a {type(value).__name__}; expected a whole number")
    return int(value)
