"""Writing output files: only under the output directory, never through an existing link, never
half-written, and every failure one line.

``output_path(out_dir, name)`` is ``out_dir / name`` for a plain file name (one component: no
separator, not ``.``/``..``, no NUL), so it lies in ``out_dir`` itself (a link at that name is
replaced by the write, not followed). ``write_bytes`` /
``write_text`` create a new temporary file beside the target (``O_CREAT | O_EXCL``: never an
existing file or link) and rename it over the target atomically: a symlink already at the target
is replaced, not written through, and a reader never sees a partial file; anything else that is not
a regular file (a directory, a device such as /dev/full, a FIFO) is refused, never replaced. An OSError (a full disk,
a read-only directory, a directory in the way) is an ``InputError`` naming the file.

The files of one result (a run's JSON, CSV and plots) are written inside ``output_set()``: they
are renamed into place together when the block ends, so an interrupted or failed run (Ctrl-C while
the plots are drawn, a full disk at the last file) leaves the previous run's files as they were,
never its new JSON beside the old CSV (Ctrl-C or SIGTERM while they are renamed takes effect after the last).
``remove`` inside the set removes a file of the previous
result when the set ends; ``publish`` moves a folder of files written elsewhere first (a report,
whose steps read their files back) into place as one set.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from pathlib import Path

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.interrupts import interrupts_deferred


def output_path(out_dir: str | Path, name: str) -> Path:
    """``out_dir / name``, or an InputError if ``name`` is not one plain file name or the result
    does not lie under ``out_dir`` (resolved: a symlinked parent does not count as under it)."""
    if (not name or name in (".", "..") or "/" in name or os.sep in name or "\0" in name
            or (os.altsep is not None and os.altsep in name)):
        raise InputError(f"output file name '{printable(name)}' is not a plain file name; expected one path component")
    path = Path(out_dir) / name
    if path.parent != Path(out_dir) or path.name != name:  # one component: the file lies in out_dir itself
        raise InputError(f"output file '{printable(path)}' would not lie in '{printable(out_dir)}'; expected a file under --out")
    return path


#: (temporary, target) of each file written inside ``output_set``, renamed when it ends; ("", target)
#: for a file ``remove``d then.
_PENDING: ContextVar[list[tuple[str, Path]] | None] = ContextVar("_PENDING", default=None)


def _rename(tmp: str, path: Path) -> None:
    try:
        if tmp:
            os.replace(tmp, path)  # replaces a link at ``path``; never follows it
        else:
            path.unlink(missing_ok=True)  # a link is removed, not followed
    except OSError as e:
        raise InputError(f"cannot write '{printable(path)}' ({e.strerror}); expected a writable file path") from e


@contextlib.contextmanager
def output_set() -> Iterator[None]:
    """Every ``write_bytes`` in the block is kept under its temporary name until the block ends
    without an error, then all are renamed into place; an error or an interrupt removes them all. A set
    inside another joins it: its files are renamed when the outermost set ends (a command adds a file,
    such as the provenance record, to a writer's set)."""
    if _PENDING.get() is not None:
        yield
        return
    pending: list[tuple[str, Path]] = []
    token = _PENDING.set(pending)
    try:
        try:
            yield
        finally:
            _PENDING.reset(token)
        with interrupts_deferred():  # an interrupt between two renames would leave a mix of the two results
            while pending:
                _rename(*pending[0])
                pending.pop(0)
    finally:
        for tmp, _ in pending:
            if tmp:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(tmp)


def remove(path: str | Path) -> None:
    """Remove the file or link at ``path`` if there is one (never a directory: ``replaceable``); inside
    ``output_set`` when the set ends, after its files are in place."""
    path = Path(path)
    replaceable([path])
    pending = _PENDING.get()
    if pending is None:
        _rename("", path)
    else:
        pending.append(("", path))


def publish(staging: Path, target: Path, replaces: Iterable[Path] = ()) -> list[Path]:
    """Every file under ``staging`` written (``write_bytes``) to the same place under ``target``, its
    subfolders made by ``output_dir``; then each file (or link) of ``replaces`` that was not written ``remove``d.
    Inside ``output_set`` all of it happens when the set ends, or none of it. The files written, in ``target``."""
    written = []
    for src in sorted(p for p in staging.rglob("*") if p.is_file()):
        folder = target
        for part in src.relative_to(staging).parent.parts:
            folder = output_dir(folder, part)
        written.append(write_bytes(output_path(folder, src.name), src.read_bytes()))
    for old in sorted(set(map(Path, replaces)) - set(written)):
        if old.is_file() or old.is_symlink():  # a folder of the same pattern is not the previous result's
            remove(old)
    return written


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def replaceable(paths: Iterable[str | Path]) -> None:
    """InputError if any of ``paths`` exists and is not a regular file or a link (a directory, a
    device, a FIFO: never replaced). Commands call it on their output files before the work, so
    that a directory in the way is not found after minutes of it."""
    for path in map(Path, paths):
        if path.exists() and not path.is_symlink() and not path.is_file():
            raise InputError(f"cannot write '{printable(path)}': it exists and is not a regular file; expected a file path")


def write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` by create-new + atomic rename (see the module docstring)."""
    path = Path(path)
    replaceable([path])
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name[:100]}.", suffix=".partial")
    except OSError as e:
        raise InputError(f"cannot write '{printable(path)}' ({e.strerror}); expected a writable directory") from e
    pending = _PENDING.get()
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
        os.chmod(tmp, 0o666 & ~_umask())
        if pending is None:
            _rename(tmp, path)
        else:
            pending.append((tmp, path))
            tmp = ""  # output_set renames or removes it
    except OSError as e:
        raise InputError(f"cannot write '{printable(path)}' ({e.strerror}); expected a writable file path") from e
    finally:
        if tmp:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(tmp)
    return path


def write_text(path: str | Path, text: str) -> Path:
    return write_bytes(path, text.encode("utf-8"))


@contextlib.contextmanager
def text_writer(path: str | Path) -> Iterator[io.StringIO]:
    """A text buffer written to ``path`` (``write_text``) when the block ends without an error."""
    buf = io.StringIO(newline="")
    yield buf
    write_text(path, buf.getvalue())


def save_figure(fig: object, path: str | Path, **savefig_kwargs: object) -> Path:
    """A Matplotlib figure saved as PNG to ``path`` through ``write_bytes``."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", **savefig_kwargs)  # type: ignore[attr-defined]
    return write_bytes(path, buf.getvalue())


def output_dir(parent: str | Path, name: str) -> Path:
    """The subdirectory ``parent / name`` (a plain name, ``output_path``), created if missing; an
    InputError if a symlink or a file is in its place (writes must not leave ``parent``)."""
    path = dir_place(parent, name)
    try:
        path.mkdir(exist_ok=True)
    except OSError as e:
        raise InputError(f"cannot create '{printable(path)}' ({e.strerror}); expected a writable directory") from e
    if not path.is_dir():
        raise InputError(f"'{printable(path)}' is a file; expected a directory")
    return path


def dir_place(parent: str | Path, name: str) -> Path:
    """``parent / name`` if ``output_dir`` can make or use it there: an InputError if a symlink or a
    file (anything but a directory) is in its place. Creates nothing: commands call it before the work."""
    path = output_path(parent, name)
    if path.is_symlink():
        raise InputError(f"'{printable(path)}' is a symbolic link; expected a directory inside "
                         f"'{printable(parent)}' (remove the link)")
    if path.exists() and not path.is_dir():
        raise InputError(f"'{printable(path)}' is a file; expected a directory")
    return path
