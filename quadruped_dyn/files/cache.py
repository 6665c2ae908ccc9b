"""A cache of built artefacts (compiled libraries, the benchmark harness) that verifies
before it trusts.

Each entry is a directory ``<cache>/<key>/`` holding one artefact and ``<artefact>.sha256``,
the SHA-256 of its bytes written when it was built. ``cached_build`` returns the artefact's
path only after its bytes match that hash, so a truncated, zero-length or altered file is
never handed to ``dlopen`` (a truncated library mapped into a process dies with SIGBUS);
such an entry is rebuilt, with a one-line note on stderr.

Builds of one entry are serialised by an exclusive ``flock`` on ``<key>/.lock``; each build
writes under a per-process temporary name and renames into place (atomic), then writes the
hash the same way. A killed build leaves at most a temporary file (removed by the next build
of that entry, which holds the lock, so no other build owns it) or an artefact without its
hash (not trusted, rebuilt). Where: ``$QUADRUPED_DYN_CACHE``, else
``$XDG_CACHE_HOME/quadruped_dyn``, else ``~/.cache/quadruped_dyn``.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import os
import sys
from collections.abc import Callable
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.paths import writable_dir

HASH_SUFFIX = ".sha256"
PARTIAL_MARK = ".partial-"  # in the name of a file being written; never trusted


def cache_dir() -> Path:
    """$QUADRUPED_DYN_CACHE, else $XDG_CACHE_HOME/quadruped_dyn, else ~/.cache/quadruped_dyn."""
    if "QUADRUPED_DYN_CACHE" in os.environ:
        if not os.environ["QUADRUPED_DYN_CACHE"].strip():  # Path("") would be the current directory
            raise InputError("QUADRUPED_DYN_CACHE is set but empty; expected a directory (or unset it for the default)")
        return Path(os.environ["QUADRUPED_DYN_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "quadruped_dyn"


def writable_cache() -> Path:
    """The cache directory, created; InputError (one line) unless a file can be written there. Commands that
    build C call it before their first progress line: a read-only cache is then the only line they print."""
    return writable_dir(cache_dir(), f"the cache directory '{printable(cache_dir())}' (QUADRUPED_DYN_CACHE)")


def file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verified(artefact: Path) -> bool:
    """True if ``artefact`` exists and its bytes match the hash recorded when it was built."""
    recorded = artefact.with_name(artefact.name + HASH_SUFFIX)
    try:
        return artefact.is_file() and recorded.read_text().strip() == file_sha256(artefact)
    except OSError:
        return False


def _write_atomic(path: Path, write: Callable[[Path], object]) -> None:
    partial = path.with_name(f"{path.name}{PARTIAL_MARK}{os.getpid()}")
    try:
        write(partial)
        partial.replace(path)
    finally:
        partial.unlink(missing_ok=True)


def cached_build(key: str, name: str, build: Callable[[Path], None]) -> Path:
    """The verified artefact ``<cache>/<key>/<name>``, built by ``build(path)`` (which must
    write the artefact at ``path``) when it is missing or fails verification.

    Raises InputError (one line) if the cache is not a writable directory when a build is
    needed; whatever ``build`` raises propagates, and nothing of that build is kept."""
    entry = cache_dir() / key
    artefact = entry / name
    if verified(artefact):  # entries are replaced only by atomic renames: no lock needed to read
        return artefact
    writable_dir(entry, f"the cache (QUADRUPED_DYN_CACHE) entry '{entry}'")
    try:
        lock = open(entry / ".lock", "a")  # noqa: SIM115 -- held for the whole build
    except OSError as e:
        raise InputError(f"cannot lock the cache entry '{entry}' ({e.strerror}); expected a writable directory") from e
    with lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # another process building this entry: wait for it
        if verified(artefact):
            return artefact
        for stray in entry.glob(f"*{PARTIAL_MARK}*"):  # left by a killed build (we hold the lock)
            stray.unlink(missing_ok=True)
        recorded = artefact.with_name(name + HASH_SUFFIX)
        if artefact.exists():
            why = "does not match its recorded hash" if recorded.exists() else "has no recorded hash"
            print(f"cache: '{artefact}' {why}; rebuilding it", file=sys.stderr)
        recorded.unlink(missing_ok=True)  # first: the old artefact must not stay trusted
        _raise_if_full(entry)  # before ``build`` prints its progress note: a full cache is then the only line
        try:
            _write_atomic(artefact, build)
            digest = file_sha256(artefact)
            _write_atomic(recorded, lambda p: p.write_text(digest + "\n"))
        except Exception as e:  # a compiler's own message for a full disk names a missing .partial file instead
            _raise_if_full(entry, e)
            raise
    return artefact


#: A build that fails with less than this free on the cache's filesystem failed for want of space: a compiled
#: library is 0.1-20 MB, its objects and the stored symbolic models a few MB each.
MIN_FREE_BYTES = 64 * 2**20


def _raise_if_full(entry: Path, error: Exception | None = None) -> None:
    """InputError naming the cache and its path as full, if ``error`` is ENOSPC or the cache's filesystem has
    less than MIN_FREE_BYTES free (one line: checked before a build and after a failed one)."""
    try:
        stat = os.statvfs(entry)
        free = stat.f_bavail * stat.f_frsize
    except OSError:
        return
    if getattr(error, "errno", None) == errno.ENOSPC or free < MIN_FREE_BYTES:
        raise InputError(f"the cache (QUADRUPED_DYN_CACHE) at '{printable(cache_dir())}' is full ({free / 1e6:.1f} MB free "
                         f"on its filesystem); expected at least {MIN_FREE_BYTES / 2**20:.0f} MB free there, or "
                         "QUADRUPED_DYN_CACHE set to a directory with room") from error
