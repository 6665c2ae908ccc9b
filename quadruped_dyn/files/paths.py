"""Output and cache directories: created and proven writable before any work is done."""

from __future__ import annotations

import tempfile
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable


def writable_dir(path: str | Path, what: str) -> Path:
    """Create ``path`` (with its parents) and prove a file can be written in it; an InputError
    naming ``what`` (e.g. "--out 'gen'") otherwise: a file in the way, /proc, a read-only directory."""
    if str(path).strip() == "":  # Path("") is the current directory: never what an empty argument means
        raise InputError(f"{printable(what)} is an empty path; expected a directory name")
    out = Path(path)
    expected = "expected a writable directory"
    for p in (out, *out.parents):
        if p.exists() and not p.is_dir():
            raise InputError(f"{printable(what)}: '{printable(p)}' is a file; {expected}")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as e:
        raise InputError(f"{printable(what)} is not writable ({e.strerror}); {expected}") from e
    return out
