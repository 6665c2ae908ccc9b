"""Each task kind's options: defaults, ranges, and the names that must exist (controllers from
``control.controllers.CONTROLLERS``, gaits, reference libraries installed), checked before any task."""

from __future__ import annotations

import importlib.util
from typing import Any

from quadruped_dyn.errors import InputError

PRECISIONS = ("double", "float")
#: Largest number of runs / repeats of one task entry: a sweep of a million tasks is a mistake.
MAX_RUNS = 100_000
#: Gait cycles of a validate or control task, at most: the commands' own limits are checked at run time too.
MAX_CYCLES = 100

DEFAULTS: dict[str, dict[str, Any]] = {
    "check": {"states": 20, "seed": 0, "repeats": 1, "libraries": None},  # None: every library installed
    "codegen": {"precisions": PRECISIONS},
    "validate": {"gaits": ("trot", "walk"), "cycles": 2.0},
    "control": {"gaits": ("walk",), "controllers": (), "runs": 1, "seed": 0, "cycles": 10, "perturbations": {}},
}


def installed_libraries() -> tuple[str, ...]:
    """The reference libraries of ``checks.cross_library`` whose package is installed here."""
    from quadruped_dyn.checks.cross_library import LIBRARIES

    return tuple(n for n, (_, package) in LIBRARIES.items() if importlib.util.find_spec(package) is not None)


def _within(key: str, value: int | float, low: float, high: float) -> None:
    if not low <= value <= high:
        raise InputError(f"sweep file: {key} is {value:g}; expected a number from {low:g} to {high:g}")


def _names(key: str, given: tuple[str, ...], known: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    for i, n in enumerate(given):
        if n not in known:
            raise InputError(f"sweep file: {key}[{i}] '{n}' is unknown; expected one of {', '.join(known)}")
    if not given:
        raise InputError(f"sweep file: {key} is empty; expected some of {', '.join(known)}")
    return tuple(dict.fromkeys(given))


def checked_options(kind: str, table: dict[str, Any]) -> dict[str, Any]:
    """The options of task ``kind`` (``table`` has passed the sweep file's key and type check) with defaults."""
    from quadruped_dyn.experiment.gait import GAITS

    o = {**DEFAULTS[kind], **table}
    key = f"tasks.{kind}"
    if kind == "check":
        from quadruped_dyn.checks.sample_counts import MAX_SAMPLES

        _within(f"{key}.states", o["states"], 1, MAX_SAMPLES)
        _within(f"{key}.seed", o["seed"], 0, 2**63 - 1)
        _within(f"{key}.repeats", o["repeats"], 1, MAX_RUNS)
        installed = installed_libraries()
        o["libraries"] = installed if o["libraries"] is None else _installed(f"{key}.libraries", o["libraries"], installed)
    elif kind == "codegen":
        o["precisions"] = _names(f"{key}.precisions", o["precisions"], PRECISIONS)
    elif kind == "validate":
        o["gaits"] = _names(f"{key}.gaits", o["gaits"], list(GAITS))
        _within(f"{key}.cycles", o["cycles"], 0.1, MAX_CYCLES)
    elif kind == "control":
        from quadruped_dyn.control.controllers import CONTROLLERS

        o["gaits"] = _names(f"{key}.gaits", o["gaits"], list(GAITS))
        o["controllers"] = _names(f"{key}.controllers", o["controllers"] or tuple(CONTROLLERS), list(CONTROLLERS))
        _within(f"{key}.runs", o["runs"], 1, MAX_RUNS)
        _within(f"{key}.seed", o["seed"], 0, 2**63 - 1)
        _within(f"{key}.cycles", o["cycles"], 1, MAX_CYCLES)
        from quadruped_dyn.sweep.sampling import check_perturbations

        check_perturbations(f"{key}.perturbations", o["perturbations"])
        horizon = o["cycles"] * min(GAITS[g].period for g in o["gaits"])
        if o["perturbations"].get("push_at_s", (0.0, 0.0))[1] >= horizon:
            raise InputError(f"sweep file: {key}.perturbations.push_at_s reaches {o['perturbations']['push_at_s'][1]:g} s; "
                             f"expected times of the run, before its {horizon:g} s ({o['cycles']} cycles)")
    return o


def _installed(key: str, given: tuple[str, ...], installed: tuple[str, ...]) -> tuple[str, ...]:
    from quadruped_dyn.checks.cross_library import INSTALL_HINT, LIBRARIES

    for i, n in enumerate(given):
        if n not in LIBRARIES:
            raise InputError(f"sweep file: {key}[{i}] '{n}' is unknown; expected some of {', '.join(LIBRARIES)}")
        if n not in installed:
            raise InputError(f"sweep file: {key}[{i}] '{n}' is not installed; expected it installed ({INSTALL_HINT})")
    return tuple(dict.fromkeys(given))
