"""Design variants (``urdf_edit.scale_urdf``) against Pinocchio on the original URDF: total mass, foot
positions and the centroidal inertia scale as a body scaled geometrically does."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.urdf_edit import parse_urdf_text, scale_urdf, to_text
from quadruped_dyn.tolerances import REL_TOL_TERMS


def _variant(tmp_path, robot, **scales):
    root = parse_urdf_text(robot.urdf.read_text())
    scale_urdf(root, **scales)
    path = tmp_path / "variant.urdf"
    path.write_text(to_text(root))
    return load_robot(str(path), cached=False)


def _at_neutral(robot):
    model = robot.model
    data = model.createData()
    q = pin.neutral(model)
    pin.framesForwardKinematics(model, data, q)
    pin.ccrba(model, data, q, np.zeros(model.nv))
    Ig = data.Ig.inertia.copy()  # rotational inertia about the centre of mass
    return pin.computeTotalMass(model), np.array([data.oMf[f].translation for f in robot.foot_frame_ids]), Ig


@pytest.mark.parametrize("name", ["paper", "go2"])
def test_mass_and_length_scale_as_a_geometric_body(tmp_path, name):
    robot = load_robot(name)
    m, l = 1.3, 0.9
    mass, feet, Ig = _at_neutral(robot)
    mass2, feet2, Ig2 = _at_neutral(_variant(tmp_path, robot, mass=m, length=l))
    assert mass2 == pytest.approx(m * mass, rel=REL_TOL_TERMS)
    np.testing.assert_allclose(feet2, l * feet, atol=REL_TOL_TERMS * np.abs(feet).max())
    np.testing.assert_allclose(Ig2, m * l**2 * Ig, atol=REL_TOL_TERMS * np.abs(Ig).max())


def test_inertia_scale_scales_each_bodys_rotational_inertia_only(tmp_path, paper):
    variant = _variant(tmp_path, paper, inertia=1.5)
    for a, b in zip(paper.model.inertias, variant.model.inertias):
        assert b.mass == pytest.approx(a.mass, rel=REL_TOL_TERMS)
        np.testing.assert_allclose(b.lever, a.lever, atol=REL_TOL_TERMS)
        np.testing.assert_allclose(b.inertia, 1.5 * a.inertia, atol=REL_TOL_TERMS * max(np.abs(a.inertia).max(), 1e-300))


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), True])
def test_bad_scale_is_input_error(bad):
    with pytest.raises(InputError, match="mass scale"):
        scale_urdf(parse_urdf_text("<robot name='r'/>"), mass=bad)
