"""The kind of an argument, checked before its range (``quadruped_dyn.arguments``)."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.arguments import real_number, whole_number
from quadruped_dyn.errors import InputError


@pytest.mark.parametrize("value", [2, 2.5, np.float64(2.5), np.int64(2), float("nan")])
def test_a_real_number_is_a_float(value: object) -> None:
    result = real_number("mu", value)
    assert type(result) is float and (result == float(value) or np.isnan(result))  # type: ignore[arg-type]


@pytest.mark.parametrize(("value", "kind"), [(True, "bool"), ("0.6", "str"), (1j, "complex"), (None, "NoneType")])
def test_anything_else_is_refused_by_name(value: object, kind: str) -> None:
    """A bool passed as 0 or 1, a str or None made ``math.isfinite`` raise TypeError, a complex lost its imaginary part."""
    with pytest.raises(InputError, match=rf"^mu is {value!r}, a {kind}; expected a real number$"):
        real_number("mu", value)


@pytest.mark.parametrize(("value", "kind"), [(2.0, "float"), (False, "bool"), ("3", "str")])
def test_a_whole_number_is_an_integer(value: object, kind: str) -> None:
    assert whole_number("nodes", np.int64(3)) == 3 and type(whole_number("nodes", np.int64(3))) is int
    with pytest.raises(InputError, match=rf"^nodes is {value!r}, a {kind}; expected a whole number$"):
        whole_number("nodes", value)


def test_errors_holds_the_errors_only() -> None:
    """One concept per module: ``errors`` defines the exception and warning classes, nothing else
    (the argument checks were there too)."""
    from quadruped_dyn import errors

    own = {name: obj for name, obj in vars(errors).items() if getattr(obj, "__module__", None) == errors.__name__}
    assert own and all(isinstance(obj, type) and issubclass(obj, Exception | Warning) for obj in own.values()), own
