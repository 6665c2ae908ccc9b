"""Comparing numbers, the one place: a NaN or inf on either side is an infinite error.

``max(0.0, nan)`` is 0.0 and ``nan <= tol`` is False but ``not nan > tol`` is True: comparisons
written inline let a NaN pass as a perfect match. Every check compares through here.
"""

from __future__ import annotations

import numpy as np


def max_abs_error(ours: object, reference: object) -> float:
    """max |ours - reference| over entries (0 for empty arrays); inf if the shapes differ or
    any entry on either side is NaN or inf."""
    a = np.asarray(ours, dtype=float)
    b = np.asarray(reference, dtype=float)
    if a.squeeze().shape != b.squeeze().shape:
        return float("inf")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return float("inf")
    return float(np.abs(a.squeeze() - b.squeeze()).max(initial=0.0))


def scale_of(reference: object) -> float:
    """max |reference| (1 where it is all zero or empty, so the error stays absolute);
    inf if it is not finite."""
    b = np.asarray(reference, dtype=float)
    if not np.all(np.isfinite(b)):
        return float("inf")
    return float(np.abs(b).max(initial=0.0)) or 1.0


def relative_error(ours: object, reference: object, scale: float | None = None) -> float:
    """max |ours - reference| / scale (default: ``scale_of(reference)``); inf for any NaN or
    inf on either side or in the scale, so ``relative_error(...) <= tol`` never passes them."""
    err = max_abs_error(ours, reference)
    s = scale_of(reference) if scale is None else (float(scale) or 1.0)
    if not (np.isfinite(err) and np.isfinite(s)):
        return float("inf")
    return err / s


def within(error: float, tol: float) -> bool:
    """True only for a finite error <= tol."""
    return bool(np.isfinite(error) and error <= tol)
