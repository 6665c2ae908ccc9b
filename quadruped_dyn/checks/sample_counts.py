"""The sample counts of the term check (``checks.terms.run_check``), checked before anything is built; light to
import (the command line reads them for its options)."""

from __future__ import annotations

from quadruped_dyn.errors import InputError

#: Random states ``run_check`` accepts: ~15 states/s once the models are built, so this is about two hours;
#: more is refused before the minutes of model building start.
MAX_SAMPLES = 100_000


#: Random states of the report's term check (``report --samples``): ~1 s each on this 2-core machine
#: (the Pinocchio-built reduced reference of four stance sets), so 50 keep the step near a minute;
#: the README's numbers are ``check paper --samples 200``.
CHECK_SAMPLES = 50


def check_samples(samples: object) -> None:
    """InputError unless 1 <= samples <= MAX_SAMPLES (an integer)."""
    if isinstance(samples, bool) or not isinstance(samples, int) or not 1 <= samples <= MAX_SAMPLES:
        raise InputError(f"samples is {samples!r}; expected an integer from 1 to {MAX_SAMPLES:,}")
