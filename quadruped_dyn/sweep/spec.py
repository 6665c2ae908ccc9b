"""The sweep file (TOML, docs/sweeps.md): which robots, which tasks with which options. Read and
checked whole before any task runs: an unknown key, a value of the wrong type, no robot, a glob
that matches nothing is an InputError naming the key (``robots.paths[1]``, ``tasks.check.states``).

A range ``[lo, hi]`` is a uniform distribution; a single number is that value.
"""

from __future__ import annotations

import glob
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

try:
    import tomllib
except ImportError:  # Python 3.10: its backport (the sweep extra)
    import tomli as tomllib  # type: ignore[no-redef]

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable

#: Each table's keys and their kinds: "table", "tables" (an array of tables), "int", "float", "str",
#: "strs" (a list of strings), "range" (a number or [lo, hi]).
SCHEMA: dict[str, dict[str, str]] = {
    "": {"sweep": "table", "robots": "table", "tasks": "table"},
    "sweep": {"name": "str"},
    "robots": {"names": "strs", "paths": "strs", "variants": "tables"},
    "robots.variants": {"robot": "str", "count": "int", "seed": "int", "mass_scale": "range", "length_scale": "range",
                        "inertia_scale": "range"},
    "tasks": {"check": "table", "codegen": "table", "validate": "table", "control": "table"},
    "tasks.check": {"states": "int", "seed": "int", "repeats": "int", "libraries": "strs"},
    "tasks.codegen": {"precisions": "strs"},
    "tasks.validate": {"gaits": "strs", "cycles": "float"},
    "tasks.control": {"gaits": "strs", "controllers": "strs", "runs": "int", "seed": "int", "cycles": "int",
                      "perturbations": "table"},
    "tasks.control.perturbations": {"trunk_mass_scale": "range", "link_mass_scale": "range", "mass_scale": "range",
                                    "payload_kg": "range", "payload_offset_x_m": "range", "payload_offset_y_m": "range",
                                    "payload_offset_z_m": "range", "mu": "range", "foot_radius_m": "range",
                                    "push_x_N_s": "range", "push_y_N_s": "range", "push_z_N_s": "range",
                                    "push_at_s": "range", "imu_noise_rad_s": "range", "imu_noise_rad": "range",
                                    "imu_delay_ticks": "range", "step_x_m": "range", "step_height_m": "range"},
}
#: The prefix of a path inside the installed example-robot-data's robots/ folder.
ERD_PREFIX = "example-robot-data:"
#: The sweep file's size limit (bytes): a sweep is a few dozen lines.
MAX_SWEEP_BYTES = 1_000_000


@dataclass(frozen=True)
class Variants:
    robot: str
    count: int
    seed: int
    mass_scale: tuple[float, float]
    length_scale: tuple[float, float]
    inertia_scale: tuple[float, float]


@dataclass(frozen=True)
class SweepSpec:
    name: str
    path: Path
    names: tuple[str, ...] = ()
    paths: tuple[Path, ...] = ()  # every path and every glob's matches, resolved
    variants: tuple[Variants, ...] = ()
    tasks: dict[str, dict[str, Any]] = field(default_factory=dict)  # kind -> options (checked kinds)


def _type_error(key: str, value: object, expected: str) -> InputError:
    return InputError(f"sweep file: {key} is {printable(repr(value))[:80]}, a {type(value).__name__}; expected {expected}")


def _number(key: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise _type_error(key, value, "a finite number")
    return float(value)


def _value(key: str, kind: str, value: object) -> Any:
    """``value`` checked against ``kind`` (see SCHEMA)."""
    if kind in ("table", "tables"):
        ok = isinstance(value, dict) if kind == "table" else isinstance(value, list) and all(isinstance(v, dict) for v in value)
        if not ok:
            raise _type_error(key, value, "a table" if kind == "table" else "an array of tables ([[...]])")
        return value
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise _type_error(key, value, "a whole number")
        return value
    if kind == "float":
        return _number(key, value)
    if kind == "str":
        if not isinstance(value, str):
            raise _type_error(key, value, "a string")
        return value
    if kind == "strs":
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise _type_error(key, value, "a list of strings")
        return tuple(value)
    if kind == "range":
        if isinstance(value, list):
            if len(value) != 2:
                raise _type_error(key, value, "a number or a range [lo, hi]")
            lo, hi = (_number(f"{key}[{i}]", v) for i, v in enumerate(value))
            if lo > hi:
                raise InputError(f"sweep file: {key} is [{lo:g}, {hi:g}]; expected lo <= hi")
            return (lo, hi)
        x = _number(key, value)
        return (x, x)
    raise AssertionError(kind)


def _checked(table: dict[str, Any], where: str) -> dict[str, Any]:
    """The table's keys and values checked against SCHEMA[where], recursively (sub-tables by dotted key)."""
    allowed = SCHEMA[where]
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{where}.{k}" if where else k
        if k not in allowed:
            raise InputError(f"sweep file: unknown key '{key}'; expected one of {', '.join(allowed)}")
        kind = allowed[k]
        v = _value(key, kind, v)
        if kind == "table" and key in SCHEMA:
            v = _checked(v, key)
        elif kind == "tables":
            v = [_checked(t, key) for t in v]
        out[k] = v
    return out


def _positive(key: str, value: int, low: int = 1) -> int:
    if value < low:
        raise InputError(f"sweep file: {key} is {value}; expected a whole number >= {low}")
    return value


def _resolve_paths(patterns: tuple[str, ...], base: Path, key: str = "robots.paths") -> tuple[Path, ...]:
    """Each path or glob (relative to the sweep file's folder; ``example-robot-data:`` for the installed package's
    robots) as the files it names, in order, without repeats; InputError for one that names no file."""
    from quadruped_dyn.model.registry import example_robot_data_dir

    found: list[Path] = []
    for i, pattern in enumerate(patterns):
        text = pattern
        if text.startswith(ERD_PREFIX):
            text = str(example_robot_data_dir() / text[len(ERD_PREFIX):])
        full = Path(text).expanduser()
        full = full if full.is_absolute() else base / full
        matches = sorted(Path(p) for p in glob.glob(str(full), recursive=True) if Path(p).is_file())
        if not matches:
            what = "matches no file" if glob.has_magic(str(full)) else "is not a file"
            where = key if key != "robots.paths" else f"{key}[{i}]"
            raise InputError(f"sweep file: {where} '{printable(pattern)}' {what}; expected URDF files")
        found += [m.resolve() for m in matches if m.resolve() not in found]
    return tuple(found)


def _variants(tables: list[dict[str, Any]], base: Path) -> tuple[Variants, ...]:
    from quadruped_dyn.model.registry import ROBOT_NAMES

    out = []
    for i, t in enumerate(tables):
        key = f"robots.variants[{i}]"
        if "robot" not in t:
            raise InputError(f"sweep file: {key}.robot is missing; expected a built-in robot name or a URDF path")
        robot = t["robot"] if t["robot"] in ROBOT_NAMES else str(_resolve_paths((t["robot"],), base, f"{key}.robot")[0])
        count = _positive(f"{key}.count", t.get("count", 1))
        for scale in ("mass_scale", "length_scale", "inertia_scale"):
            lo, _ = t.get(scale, (1.0, 1.0))
            if lo <= 0:
                raise InputError(f"sweep file: {key}.{scale} starts at {lo:g}; expected scales > 0")
        out.append(Variants(robot, count, _positive(f"{key}.seed", t.get("seed", 0), 0),
                            t.get("mass_scale", (1.0, 1.0)), t.get("length_scale", (1.0, 1.0)),
                            t.get("inertia_scale", (1.0, 1.0))))
    return tuple(out)


def read_spec(path: str | Path) -> SweepSpec:
    """The sweep file at ``path``, checked (see the module docstring)."""
    p = Path(path)
    try:
        if p.stat().st_size > MAX_SWEEP_BYTES:
            raise InputError(f"sweep file '{printable(p)}' is over {MAX_SWEEP_BYTES:,} bytes; expected a sweep file")
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except OSError as e:
        raise InputError(f"cannot read the sweep file '{printable(p)}' ({e.strerror}); expected a readable TOML file") from e
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise InputError(f"sweep file '{printable(p)}' is not TOML ({printable(str(e))}); expected a TOML file") from e
    top = _checked(data, "")
    robots, tasks = top.get("robots", {}), top.get("tasks", {})
    names = robots.get("names", ())
    from quadruped_dyn.model.registry import ROBOT_NAMES

    for i, n in enumerate(names):
        if n not in ROBOT_NAMES:
            raise InputError(f"sweep file: robots.names[{i}] '{printable(n)}' is not a built-in robot; expected one of "
                             f"{', '.join(ROBOT_NAMES)} (a URDF goes in robots.paths)")
    paths = _resolve_paths(robots.get("paths", ()), p.parent)
    variants = _variants(robots.get("variants", []), p.parent)
    if not (names or paths or variants):
        raise InputError("sweep file: robots is empty; expected robots.names, robots.paths or robots.variants")
    if not tasks:
        raise InputError("sweep file: tasks is empty; expected at least one of tasks.check, tasks.codegen, "
                         "tasks.validate, tasks.control")
    from quadruped_dyn.sweep.options import checked_options

    options = {kind: checked_options(kind, table) for kind, table in tasks.items()}
    name = top.get("sweep", {}).get("name", p.stem)
    return SweepSpec(name, p.resolve(), names, paths, variants, options)
