"""The counts a benchmark accepts (calls per timing run, timing runs), checked before anything is built."""

from __future__ import annotations

from quadruped_dyn.errors import InputError

#: The harnesses read both counts as a C int; beyond these a bench takes hours (20,000 x 9 is the default).
MAX_CALLS = 10_000_000
MAX_REPS = 1_000


def check_counts(calls: object, reps: object) -> None:
    """InputError unless 1 <= calls <= MAX_CALLS and 1 <= reps <= MAX_REPS (integers)."""
    for what, value, most in (("calls", calls, MAX_CALLS), ("reps", reps, MAX_REPS)):
        if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= most:
            raise InputError(f"{what} is {value!r}; expected an integer from 1 to {most:,}")
