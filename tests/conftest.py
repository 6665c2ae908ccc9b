"""Shared fixtures: robots (session-scoped, parametrised), Pinocchio references, one
``assert_close`` helper with the project's named tolerances."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn.codegen.library import CompiledLibrary, compiled_library
from quadruped_dyn.math.compare import relative_error, scale_of, within
from quadruped_dyn.model.registry import ROBOT_NAMES, example_robot_data_dir
from quadruped_dyn.model.robot import Robot, load_robot
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_TERMS

SEEDS = (0, 1)

#: Robots whose whole generated C is compiled in the default suite (the ``library`` fixture): the
#: bundled robot and one of another size and geometry. Compiling a robot's C takes ~2 min cold on
#: two cores; the other robots' compiled C is checked in the slow suite, their symbolic terms (which
#: CasADi prints to C the same way for every robot) in the default one (tests/dynamics/).
COMPILED_IN_DEFAULT = ("paper", "solo12")


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        params = getattr(item, "callspec", None)
        if "library" in getattr(item, "fixturenames", ()) and params and params.params.get("robot") not in COMPILED_IN_DEFAULT:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session", params=ROBOT_NAMES)
def robot(request: pytest.FixtureRequest) -> Robot:
    return load_robot(request.param)


@pytest.fixture(scope="session")
def paper() -> Robot:
    return load_robot("paper")


@pytest.fixture(scope="session")
def ref(robot: Robot) -> PinocchioReference:
    return PinocchioReference(robot)


@pytest.fixture(scope="session")
def library(robot: Robot) -> CompiledLibrary:
    """The robot's generated C, compiled once (and cached across runs)."""
    return compiled_library(robot)


@pytest.fixture(scope="session")
def erd() -> object:
    return example_robot_data_dir()


def assert_close(actual: np.ndarray, expected: np.ndarray, rel: float = REL_TOL_TERMS, what: str = "") -> None:
    """|actual - expected|_max <= rel * |expected|_max (the scale is 1 where expected is all zero);
    a NaN or inf on either side fails (``quadruped_dyn.math.compare``)."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != {expected.shape}"
    err = relative_error(actual, expected)
    assert within(err, rel), f"{what}: max relative error {err:.3e} > {rel:.1e} (scale {scale_of(expected):.3e})"
