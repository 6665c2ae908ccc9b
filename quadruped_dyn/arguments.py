"""The check of an argument's kind that every option's own range check starts with: a real number
or a whole number, not a bool, a string, a complex or None (an InputError naming the argument)."""

import numbers

from quadruped_dyn.errors import InputError


def real_number(what: str, value: object) -> float:
    """``value`` as a float, or an InputError unless it is a real number (not a bool, a string, a
    complex or None: ``math.isfinite`` raised TypeError on those, a bool passed as 0 or 1); its range
    is the caller's to check."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{what} is {value!r}, a {type(value).__name__}; expected a real number")
    if type(value).__name__ == "float16":  # NumPy's half: 3 significant digits
        raise InputError(f"{what} is {value!r}, a float16; expected a real number of float32 or float64 precision "
                         "(every computation is in double precision)")
    return float(value)


def whole_number(what: str, value: object) -> int:
    """``value`` as an int, or an InputError unless it is an integer (not a bool, not a float)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InputError(f"{what} is {value!r}, a {type(value).__name__}; expected a whole number")
    return int(value)
