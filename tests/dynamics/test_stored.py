"""Symbolic models stored in the verified cache (dynamics/stored.py): built once, read back equal,
never read when the bytes or the robot differ."""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.dynamics import stored
from quadruped_dyn.files.cache import HASH_SUFFIX, file_sha256
from quadruped_dyn.math.rigid import LinkInertia
from quadruped_dyn.model.robot import load_robot

NAMES = ("square", "scaled")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(tmp_path))
    return tmp_path


def _builder(calls: list[int], scale: float = 3.0):
    def build() -> dict[str, ca.Function]:
        calls.append(1)
        x = ca.SX.sym("x", 2)
        return {"square": ca.Function("square", [x], [x * x + 1.0 / 3.0]),
                "scaled": ca.Function("scaled", [x], [scale * ca.sin(x)])}
    return build


def _entry(cache):
    (entry,) = [p for p in cache.iterdir() if p.name.startswith("symbolic-")]
    return entry / "functions.casadi"


def test_built_once_then_read_back_bit_for_bit(cache):
    robot, calls = load_robot("paper"), []
    first = stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    again = stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    assert len(calls) == 1 and tuple(again) == NAMES
    x = np.array([0.3, -1.7])
    for name in NAMES:
        assert np.array_equal(np.asarray(first[name](x)), np.asarray(again[name](x)))  # the same graph, not a copy's round-off


def test_altered_bytes_are_rebuilt_not_read(cache, capsys):
    robot, calls = load_robot("paper"), []
    stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    path = _entry(cache)
    path.write_bytes(path.read_bytes()[:-7])  # truncated: no longer matches its recorded hash
    stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    assert len(calls) == 2 and "does not match its recorded hash" in capsys.readouterr().err


def test_verified_bytes_that_are_not_the_functions_are_rebuilt(cache):
    robot, calls = load_robot("paper"), []
    stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    path = _entry(cache)
    path.write_bytes(b"not a CasADi serialisation")
    path.with_name(path.name + HASH_SUFFIX).write_text(file_sha256(path) + "\n")  # verified, yet not readable
    functions = stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    assert len(calls) == 2 and float(functions["square"](np.array([2.0, 0.0]))[0]) == 4.0 + 1.0 / 3.0


def test_a_robot_changed_in_memory_gets_its_own_entry(cache):
    """The key is the robot's symbolic content, not its name or URDF file: a Robot whose link
    inertia was changed in memory (as a test may) never reads the original's Functions."""
    robot, calls = load_robot("paper"), []
    leg = robot.legs[0]
    heavier = dataclasses.replace(leg, links=(LinkInertia(leg.links[0].mass * 1.5, leg.links[0].com, leg.links[0].inertia),
                                              *leg.links[1:]))
    variant = dataclasses.replace(robot, legs=(heavier, *robot.legs[1:]))
    assert stored.model_fingerprint(variant) != stored.model_fingerprint(robot)
    stored.stored_functions(robot, "probe", NAMES, _builder(calls))
    stored.stored_functions(variant, "probe", NAMES, _builder(calls))
    assert len(calls) == 2


def test_an_unwritable_cache_builds_in_memory(tmp_path, monkeypatch):
    blocker = tmp_path / "a file"
    blocker.write_text("")
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(blocker))  # not a directory: cannot be written
    calls: list[int] = []
    functions = stored.stored_functions(load_robot("paper"), "probe", NAMES, _builder(calls))
    assert len(calls) == 1 and tuple(functions) == NAMES


def test_the_stored_reduced_model_equals_a_fresh_build(cache):
    """The reduced model read from the store gives bit-identical values to one built from the symbols."""
    from quadruped_dyn.dynamics.reduced import MODEL_FUNCTIONS, _model_functions
    from quadruped_dyn.model.stance import stance_set

    robot, stance = load_robot("paper"), stance_set("FL+BR")
    fresh = _model_functions(robot, stance)
    stored.stored_functions(robot, "reduced model FL+BR", MODEL_FUNCTIONS, lambda: _model_functions(robot, stance))
    read = stored.stored_functions(robot, "reduced model FL+BR", MODEL_FUNCTIONS, lambda: pytest.fail("built again"))
    rng = np.random.default_rng(1)
    q, qd = np.append(robot.standing_q, 0.05), rng.normal(size=13)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    assert np.array_equal(np.asarray(read["M_r"](q, quat)), np.asarray(fresh["M_r"](q, quat)))
    assert np.array_equal(np.asarray(read["C_r"](q, qd, quat)), np.asarray(fresh["C_r"](q, qd, quat)))
