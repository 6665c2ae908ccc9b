"""JSON files and payloads: strict JSON, where NaN and inf do not exist."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from quadruped_dyn.files.safe_write import write_text


def json_safe(x: Any) -> Any:
    """``x`` as plain JSON types: dicts and lists (tuples and arrays become lists) recursively, numpy
    scalars as Python ones, and a non-finite float as None (so it never appears as a number)."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_safe(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_safe(x.tolist())
    if isinstance(x, bool | np.bool_):
        return bool(x)
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


def write_json(path: Path, data: dict[str, Any]) -> None:
    """``data`` through ``json_safe``, indented, into ``path`` (``safe_write``: create-new + atomic
    rename, never through a link)."""
    write_text(path, json.dumps(json_safe(data), indent=2, allow_nan=False))
