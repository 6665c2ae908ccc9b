"""The parametric terms (dynamics/parametric.py) with a variant's p against Pinocchio on the variant's own URDF,
the regressor against Pinocchio's, and the layout's bad input."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn import load_robot
from quadruped_dyn.dynamics.parametric import parametric_dynamics
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.parameters import (
    BODIES,
    N_INERTIAL,
    check_family,
    check_parameters,
    family_of,
    parameters_of,
)
from quadruped_dyn.model.registry import example_robot_data_dir
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import ROBOT_NAMES, assert_close
from tests.variants import variant

#: Variants per robot in the default suite (the slow test takes 20 on every robot).
DEFAULT_VARIANTS = 2


def _pin_ids(robot) -> list[int]:
    """Pinocchio joint id of each body in the layout's order (the trunk's free flyer, then the project's joints)."""
    return [1, *(robot.model.getJointId(name) for name in robot.joint_names)]


def check_variant(family, robot, seed: int) -> None:
    """Every parametric function with p = parameters_of(robot) against Pinocchio on the robot's own model."""
    D, ref, p = parametric_dynamics(family), PinocchioReference(robot), check_parameters(parameters_of(robot))
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    G = ref.gravity(s.q)
    assert_close(np.asarray(D.M_full(s.q, p)), ref.mass_matrix(s.q), what=f"{robot.name} M_full")
    assert_close(np.asarray(D.G_full(s.q, p)).ravel(), G, what=f"{robot.name} G_full")
    nle = ref.nonlinear_effects(s.q, s.v)
    assert_close(np.asarray(D.nle_full(s.q, s.v, p)).ravel(), nle, what=f"{robot.name} nle_full")
    assert_close(np.asarray(D.C_full(s.q, s.v, p)).ravel(), nle - G, what=f"{robot.name} C_full")
    R = rotation(s.q)
    expected = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
    w_res, tau = D.id_full(s.q, s.v, s.a, s.f.ravel(), p)
    assert_close(np.concatenate([np.asarray(w_res).ravel(), np.asarray(tau).ravel()]), expected, what="id_full")
    # the regressor: Pinocchio's, its rows in the project's order, its columns in the layout's bodies
    Y_pin = pin.computeJointTorqueRegressor(robot.model, ref.data, ref.pin_q(s.q), ref.pin_v(s.v), ref.pin_v(s.a))
    columns = np.concatenate([np.arange(10 * (j - 1), 10 * j) for j in _pin_ids(robot)])
    Y = np.asarray(D.regressor_full(s.q, s.v, s.a, p))
    assert_close(Y, Y_pin[np.ix_(robot.v_perm, columns)], what=f"{robot.name} regressor")
    assert_close(Y @ p[:N_INERTIAL], ref.rnea(s.q, s.v, s.a), what=f"{robot.name} tau = Y pi")


def test_layout_is_pinocchios(paper):
    """The inertial part of p is Pinocchio's toDynamicParameters, body by body."""
    pi = np.concatenate([paper.model.inertias[j].toDynamicParameters() for j in _pin_ids(paper)])
    assert len(BODIES) * 10 == N_INERTIAL
    assert_close(parameters_of(paper)[:N_INERTIAL], pi, what="inertial parameters")


def test_go1_and_a1_share_a_family():
    go1, a1 = load_robot("go1"), load_robot("a1")
    assert family_of(go1).key == family_of(a1).key
    check_family(family_of(go1), a1)


@pytest.mark.parametrize("name", ("paper", "go1"))
def test_variants_against_pinocchio(name, tmp_path):
    robot = load_robot(name)
    for seed in range(DEFAULT_VARIANTS):
        check_variant(family_of(robot), variant(robot, seed, tmp_path), seed)


#: example-robot-data quadrupeds given by path, beside the built-in robots
BY_PATH = ("b1_description/urdf/b1.urdf", "anymal_b_simple_description/robots/anymal.urdf")


@pytest.mark.slow
@pytest.mark.parametrize("name", (*ROBOT_NAMES, *BY_PATH))
def test_twenty_variants_every_robot(name, tmp_path):
    robot = load_robot(str(example_robot_data_dir() / name) if name in BY_PATH else name)
    family = family_of(robot)
    for seed in range(20):
        v = variant(robot, seed, tmp_path)
        check_family(family, v)
        check_variant(family, v, seed)


def test_other_family_refused():
    with pytest.raises(InputError, match=r"joint \w+_\w+ has the (axis|placement rotation)"):
        check_family(family_of(load_robot("go1")), load_robot("paper"))


def _p_with(robot, body: str, change) -> np.ndarray:
    p = parameters_of(robot).copy()
    b = BODIES.index(body)
    p[10 * b: 10 * b + 10] = change(p[10 * b: 10 * b + 10])
    return p


def test_non_physical_parameters_refused(paper):
    with pytest.raises(InputError, match="FL_KFE has mass -1 kg"):
        check_parameters(_p_with(paper, "FL_KFE", lambda pi: np.concatenate([[-1.0], pi[1:]])))
    # Izz > Ixx + Iyy about the CoM (the CoM at the origin: m c = 0)
    broken = np.array([1.0, 0, 0, 0, 0.01, 0, 0.01, 0, 0, 0.05])
    with pytest.raises(InputError, match="triangle inequality"):
        check_parameters(_p_with(paper, "FR_HFE", lambda pi: broken))
    with pytest.raises(InputError, match="physical range"):
        check_parameters(_p_with(paper, "trunk", lambda pi: pi * 1e9))
    with pytest.raises(InputError, match="expected 178 finite numbers"):
        check_parameters(np.full(178, np.nan))


def test_no_division_by_a_mass(paper):
    """The bodies' first moments m c enter as p has them (``LinkInertia.origin``): no term divides by a mass. The
    only division left is the quaternion's, in the terms with gravity."""
    import casadi as ca

    from quadruped_dyn.dynamics.newton_euler import gravity_in_trunk

    def divisions(f: ca.Function) -> int:
        return sum(f.instruction_id(k) == ca.OP_DIV for k in range(f.n_instructions()))

    q = ca.SX.sym("q", 19)
    quaternion = divisions(ca.Function("g", [q], [gravity_in_trunk(q)]))
    for f in parametric_dynamics(family_of(paper)).functions():
        assert divisions(f) == (0 if f.name() in ("M_full", "C_full") else quaternion), f.name()
