"""Output and cache directories: created and proven writable before any work is done."""

from __future__ import annotations

import tempfile
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable


def writable_dir(path: str | Path, what: str, expected: str = "a writable directory") -> Path:
    """Create ``path`` (with its parents) and prove a file can be written in it; an InputError
    naming ``what`` (e.g. "--out 'gen'") and saying ``expected`` otherwise: a file or a dangling
    symbolic link in the way, /proc, a read-only directory, an empty path (Path("") would be the current directory)."""
    if str(path).strip() == "":
        raise InputError(f"{printable(what)} is an empty path; expected a directory name")
    out = Path(path)
    expected = f"expected {expected}"
    for p in (out, *out.parents):
        if p.is_symlink() and not p.exists():
            raise InputError(f"{printable(what)}: '{printable(p)}' is a symbolic link to "
                             f"'{printable(str(p.readlink()))}', which does not exist; {expected}")
        if p.exists() and not p.is_dir():
            raise InputError(f"{printable(what)}: '{printable(p)}' is a file; {expected}")
    try:
        out.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as e:
        raise InputError(f"{printable(what)} is not writable ({e.strerror}); {expected}") from e
    return out
