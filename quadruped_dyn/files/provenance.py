"""Which URDF a robot's outputs in a directory came from.

Outputs are named after the robot (``<out>/<name>_trot_validation.json``, ``<out>/<name>/report.html``,
``<out>/qd_<name>.c``), and two URDFs can share a name: ``/a/robot.urdf`` and ``/b/robot.urdf`` are
both ``robot`` (``model.robot``: a URDF by path is named after its file's stem). Each command that
writes a robot's outputs records their URDF beside them, in ``<out>/<name>.source.json`` (its path
and SHA-256), and before its work refuses (``InputError``) to write where the record names another
URDF: another path and other bytes. The same file edited (same path) or a copy of it (same bytes)
writes over its own outputs; a directory without a record (outputs of an older version) is written
as before. A built-in robot needs no record: its name is its own (a URDF by path is never given a
built-in's name), so its outputs (``results/paper/...``) are as they were.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Protocol

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.files.safe_write import output_path, write_text

#: A record is a few hundred bytes (its URDF's path is at most PATH_MAX); a larger file is not one.
MAX_RECORD_BYTES = 64 * 1024


class Source(Protocol):
    """What a record says about a robot (``model.robot.Robot`` is one)."""

    @property
    def name(self) -> str: ...

    @property
    def urdf(self) -> Path: ...

    @property
    def urdf_sha256(self) -> str: ...

    @property
    def builtin(self) -> str | None: ...


def record_path(out_dir: Path, name: str) -> Path:
    """``<out_dir>/<name>.source.json`` (no output of a robot is named so: theirs are ``<name>_...``)."""
    return output_path(out_dir, f"{name}.source.json")


def check_source(out_dir: Path, robot: Source) -> None:
    """InputError if ``out_dir`` holds outputs named ``robot.name`` recorded from another URDF (another
    path and other bytes), naming the folder, that URDF and the ``--out`` to pass instead."""
    path = record_path(out_dir, robot.name)
    if robot.builtin is not None or not path.exists():
        return
    try:
        if not path.is_file():  # a directory, a FIFO (its read would block), a device (/dev/zero: endless)
            raise ValueError("not a regular file")
        with path.open("rb") as f:
            data = f.read(MAX_RECORD_BYTES + 1)
        if len(data) > MAX_RECORD_BYTES:
            raise ValueError("too large")
        recorded = json.loads(data)
        urdf, sha256 = str(recorded["urdf"]), str(recorded["urdf_sha256"])
    except (OSError, ValueError, TypeError, KeyError, RecursionError) as e:  # RecursionError: '[[[[...' nested
        raise InputError(f"'{printable(path)}' does not say which URDF the outputs of '{robot.name}' came from; "
                         "expected the JSON quadruped-dyn writes there (remove the file, or pass another --out)") from e
    if urdf != str(robot.urdf) and sha256 != robot.urdf_sha256:
        raise InputError(f"--out '{printable(out_dir)}' holds the outputs of '{robot.name}' from another URDF, "
                         f"'{printable(urdf)}' (SHA-256 {sha256[:12]}), and '{printable(robot.urdf)}' is named "
                         f"'{robot.name}' too (its file name); expected another --out for it, e.g. --out "
                         f"'{printable(out_dir / f'{robot.name}_{robot.urdf_sha256[:8]}')}'")


def record_source(out_dir: Path, robot: Source) -> Path | None:
    """Write ``robot``'s record (``write_text``: inside an ``output_set``, with its outputs); None for a
    built-in robot."""
    if robot.builtin is not None:
        return None
    data = {"robot": robot.name, "urdf": str(robot.urdf), "urdf_sha256": robot.urdf_sha256}
    return write_text(record_path(out_dir, robot.name), json.dumps(data, indent=2) + "\n")
