"""The parametric library: compiled once per family, then 100 variants of go1 and a1 with no further build, each
against Pinocchio on its own URDF."""

from __future__ import annotations

import numpy as np
import pytest

from quadruped_dyn import load_robot
from quadruped_dyn.codegen.parametric_library import parametric_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.cache import cache_dir
from quadruped_dyn.model.parameters import N_INERTIAL
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close
from tests.variants import variant

N_VARIANTS = 100


def _check(library, function, robot, seed: int) -> None:
    ref, p = PinocchioReference(robot), library.parameters(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    assert_close(function("M_full")(s.q, p)[0], ref.mass_matrix(s.q), what=f"{robot.name} M_full")
    R = rotation(s.q)
    expected = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
    w_res, tau = function("id_full")(s.q, s.v, s.a, s.f.ravel(), p)
    assert_close(np.concatenate([w_res, tau]), expected, what=f"{robot.name} id_full")
    Y = function("regressor_full")(s.q, s.v, s.a, p)[0]
    assert_close(Y @ p[:N_INERTIAL], ref.rnea(s.q, s.v, s.a), what=f"{robot.name} tau = Y pi")


def test_one_build_serves_the_family(tmp_path):
    go1 = load_robot("go1")
    library = parametric_library(go1)  # built here, or by an earlier run
    built = library.library.path.stat()
    entries = sorted(cache_dir().iterdir())
    function = {name: library.function(name) for name in ("M_full", "id_full", "regressor_full")}.__getitem__
    for seed in range(N_VARIANTS):
        robot = variant(go1, seed, tmp_path)
        assert parametric_library(robot).library.path == library.library.path
        _check(library, function, robot, seed)
    a1 = load_robot("a1")
    assert parametric_library(a1).library.path == library.library.path
    _check(library, function, a1, 0)
    assert sorted(cache_dir().iterdir()) == entries, "a variant or a1 built something"
    assert library.library.path.stat().st_mtime_ns == built.st_mtime_ns, "the library was rebuilt"
    with pytest.raises(InputError, match="joint .* has the"):
        library.parameters(load_robot("paper"))
