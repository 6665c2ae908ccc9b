"""Symbolic models stored on disk: a robot's CasADi Functions built once per machine, not once per process.

Building the reduced model of one stance set (every Walker & Orin column through the GRF solve,
then CSE) takes 2-4 s of CPU, the GRF solves of all stance sets ~4 s; the report, its warm
process, the tests and every command would build the same ones again. ``stored_functions``
keeps the Functions of one build, serialised by CasADi (``StringSerializer``, zlib-compressed), in the verified
build cache (``files/cache.py``) under a key of everything they are built from:

- the robot's symbolic content (``model_fingerprint``: the trunk and every leg's joints, links
  and foot, bit for bit), not its name or file: a Robot changed in memory gets its own entry;
- what was built (``what``, e.g. the stance set) and the Function names;
- the sources of the layers a build runs (``SOURCE_PACKAGES``: dynamics/, model/, math/, and the
  modules below them) and CasADi's version.

The cache verifies the stored bytes against their SHA-256 before they are read; an entry that
fails verification, or that does not deserialise to exactly the Functions named, is rebuilt,
never used. Where the cache cannot be written the Functions are built in memory, as before.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import zlib
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.cache import HASH_SUFFIX, cached_build
from quadruped_dyn.model.robot import Robot

PACKAGE = Path(__file__).resolve().parents[1]

#: The package's sources a symbolic build depends on (subpackages and modules, relative to the package).
SOURCE_PACKAGES = ("dynamics", "model", "math", "errors.py", "tolerances.py")

#: Bump when the stored format changes.
STORED_VERSION = "stored-functions-1"


@functools.cache
def sources_digest() -> str:
    """SHA-256 of every source file in ``SOURCE_PACKAGES`` (path and bytes)."""
    h = hashlib.sha256()
    for entry in SOURCE_PACKAGES:
        path = PACKAGE / entry
        for source in sorted(path.rglob("*.py")) if path.is_dir() else [path]:
            h.update(str(source.relative_to(PACKAGE)).encode() + b"\0" + source.read_bytes())
    return h.hexdigest()


def _feed(h: hashlib._Hash, value: object) -> None:
    """Every number of ``value`` bit for bit (dataclasses, tuples, arrays, floats, strings, None)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        h.update(type(value).__name__.encode())
        for f in dataclasses.fields(value):
            h.update(f.name.encode())
            _feed(h, getattr(value, f.name))
    elif isinstance(value, tuple | list):
        h.update(f"[{len(value)}".encode())
        for item in value:
            _feed(h, item)
    elif isinstance(value, np.ndarray):
        h.update(f"{value.dtype}{value.shape}".encode() + np.ascontiguousarray(value).tobytes())
    elif isinstance(value, float | int | np.floating | np.integer):
        h.update(float(value).hex().encode())
    elif isinstance(value, str):
        h.update(b"s" + value.encode())
    elif value is None:
        h.update(b"None")
    else:
        raise TypeError(f"cannot fingerprint a {type(value).__name__}")


def model_fingerprint(robot: Robot) -> str:
    """SHA-256 of what the symbolic models are built from: the trunk's inertia and every leg (joint
    placements, axes, limits, link inertias, foot placement and frame name)."""
    h = hashlib.sha256()
    _feed(h, (robot.trunk, robot.legs))
    return h.hexdigest()


def _decoded(path: Path, names: tuple[str, ...]) -> dict[str, ca.Function] | None:
    """The Functions stored at ``path``, or None unless they are exactly ``names`` in that order."""
    try:
        unpacked = ca.StringDeserializer(zlib.decompress(path.read_bytes()).decode()).unpack()
    except Exception:  # noqa: BLE001 -- whatever CasADi raises on bytes it did not write: not used
        return None
    if not (isinstance(unpacked, list) and len(unpacked) == len(names)
            and all(isinstance(f, ca.Function) for f in unpacked)):
        return None
    return dict(zip(names, unpacked))


def stored_functions(robot: Robot, what: str, names: tuple[str, ...],
                     build: Callable[[], dict[str, ca.Function]]) -> dict[str, ca.Function]:
    """``build()`` (a dict of Functions with exactly the keys ``names``, in that order) for ``robot``,
    from the verified cache when an entry of the same key exists (see the module docstring)."""
    key = hashlib.sha256("\n".join((STORED_VERSION, model_fingerprint(robot), what, ",".join(names), sources_digest(),
                                    ca.CasadiMeta.version())).encode()).hexdigest()[:20]
    built: dict[str, ca.Function] = {}

    def write(path: Path) -> None:
        functions = build()
        if tuple(functions) != names:
            raise ValueError(f"{what}: built {tuple(functions)}, expected {names}")
        built.update(functions)
        serializer = ca.StringSerializer()
        serializer.pack(list(functions.values()))
        path.write_bytes(zlib.compress(serializer.encode().encode(), 1))

    try:
        for _ in range(2):
            path = cached_build(f"symbolic-{key}", "functions.casadi", write)
            if built:
                return built
            stored = _decoded(path, names)
            if stored is not None:
                return stored
            # verified bytes that are not these Functions: drop the entry's hash so it is rebuilt
            path.with_name(path.name + HASH_SUFFIX).unlink(missing_ok=True)
    except InputError:  # the cache cannot be written here (or build() refused its input: raised again below)
        pass
    return built or build()
