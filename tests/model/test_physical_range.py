"""The physical range (model/physical_range.py): refused and warned models, by URDF (CLI and API) and by parameters."""

from __future__ import annotations

import dataclasses
import re
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.dynamics.derivatives import full_derivatives
from quadruped_dyn.errors import InputError, NumericalError, UrdfWarning
from quadruped_dyn.model import paper_robot
from quadruped_dyn.model import robot as robot_module
from quadruped_dyn.model.physical_range import BodyParameters, check_physical_range, robot_bodies
from quadruped_dyn.model.registry import ROBOT_NAMES, example_robot_data_dir
from quadruped_dyn.model.robot import load_robot

#: Every quadruped example-robot-data ships (by path), beside the built-in robots (by name).
ERD_QUADRUPEDS = ("a1_description/urdf/a1.urdf", "anymal_b_simple_description/robots/anymal.urdf",
                  "anymal_c_simple_description/urdf/anymal.urdf", "b1_description/urdf/b1.urdf",
                  "go1_description/urdf/go1.urdf", "go2_description/urdf/go2.urdf",
                  "hyq_description/robots/hyq_no_sensors.urdf", "laikago_description/urdf/laikago.urdf",
                  "solo_description/robots/solo12.urdf")


def paper_variant(tmp_path: Path, edit: Callable[[ET.Element], None], name: str = "variant.urdf") -> Path:
    root = ET.fromstring(paper_robot.urdf_text())
    edit(root)
    path = tmp_path / name
    path.write_text(ET.tostring(root, encoding="unicode"))
    return path


def shank(link: str = "FL_shank", mass: str | None = None, scale_inertia: float = 1.0,
          com: str | None = None) -> Callable[[ET.Element], None]:
    """An edit of one link's <inertial>: its mass, its inertia scaled, its CoM moved."""
    def edit(root: ET.Element) -> None:
        inertial = next(x for x in root.iter("link") if x.get("name") == link).find("inertial")
        if mass is not None:
            inertial.find("mass").set("value", mass)  # type: ignore[union-attr]
        inertia = inertial.find("inertia")  # type: ignore[union-attr]
        for key in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"):
            inertia.set(key, repr(float(inertia.get(key, "0")) * scale_inertia))  # type: ignore[union-attr]
        if com is not None:
            inertial.find("origin").set("xyz", com)  # type: ignore[union-attr]
    return edit


@pytest.mark.parametrize("robot", [*ROBOT_NAMES, *ERD_QUADRUPEDS])
def test_every_shipped_quadruped_is_inside_the_range(robot):
    path = robot if robot in ROBOT_NAMES else str(example_robot_data_dir() / robot)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        loaded = load_robot(path)
    assert not [w for w in caught if "reliability.md §2" in str(w.message)]
    assert check_physical_range(robot_bodies(loaded.trunk, loaded.legs)) == []


#: (case, edit, expected message): refused before any work, one line, exit 2
OUTSIDE = [
    ("1e-300 kg link", shank(mass="1e-300", scale_inertia=1e-300),
     r"the link moved by joint 'FL_KFE' has a mass / the robot's total mass of 1\.\d+e-301; expected at least 1e-06"),
    ("1e-8 kg link", shank(mass="1e-8"), r"'FL_KFE' has a mass / the robot's total mass of 1.02e-09; expected at least"),
    ("inertia 1e12 x", shank(scale_inertia=1e12), r"'FL_KFE' has a radius of gyration / the robot's size of .*; "
     r"expected at most 10000"),
    ("tiny inertia", shank(scale_inertia=1e-12), r"'FL_KFE' has a smallest principal moment / \(total mass x size\^2\)"
     r" of .*; expected at least 1e-12"),
    ("CoM 20 m away", shank(com="20 0 0"), r"'FL_KFE' has a CoM distance / the robot's size of .*; expected at most 10"),
    ("trunk of 1e5 kg", shank(link="trunk", mass="99999"), r"the robot's total mass is 1e\+05 kg; expected in \[0.001"),
]


@pytest.mark.parametrize(("case", "edit", "expected"), OUTSIDE, ids=[c[0] for c in OUTSIDE])
def test_outside_the_range_is_refused_before_any_work(case, edit, expected, tmp_path):
    path = paper_variant(tmp_path, edit)
    for command in (["info", str(path)], ["check", str(path), "--samples", "1"]):
        result = CliRunner().invoke(main, command)
        assert result.exit_code == 2, (case, result.output)
        assert re.search(expected, result.stderr), result.stderr
        assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
    with pytest.raises(InputError, match=expected):
        load_robot(str(path), cached=False)


def test_outside_the_warned_range_is_one_warning(tmp_path):
    path = paper_variant(tmp_path, shank(scale_inertia=1e3))
    with pytest.warns(UrdfWarning, match=r"'FL_KFE' has a radius of gyration / the robot's size of 4\.\d+, outside what "
                                         r"a quadruped has \(at most 1"):
        load_robot(str(path), cached=False)
    result = CliRunner().invoke(main, ["info", str(path)])
    assert result.exit_code == 0 and result.stderr.count("radius of gyration") == 1


def test_parameters_are_checked_by_the_same_validator(paper):
    """A parametric robot's bodies (not from a URDF) go through the same rules."""
    bodies = robot_bodies(paper.trunk, paper.legs)
    assert check_physical_range(bodies) == []
    foot = next(k for k, b in enumerate(bodies) if b.foot is not None)
    cases = [
        (dataclasses.replace(bodies[1], mass=float("nan")), 1, "total mass is nan"),
        (dataclasses.replace(bodies[foot], foot=np.array([0.0, 0.0, -1e-6])), foot, "its foot at 1e-06 m from the knee"),
        (dataclasses.replace(bodies[2], joint_offset=np.array([500.0, 0.0, 0.0])), 2, "the robot's size (hips' span, leg "
         "chains) is 500 m; expected in [0.001, 100]"),
        (dataclasses.replace(bodies[1], mass=0.0), 1, "mass / the robot's total mass of 0; expected at least 1e-06"),
    ]
    for body, k, expected in cases:
        with pytest.raises(InputError, match=re.escape(expected)):
            check_physical_range([*bodies[:k], body, *bodies[k + 1:]])
    lighter = [dataclasses.replace(bodies[1], mass=bodies[1].mass * 1e-2), *bodies[2:]]
    assert any("mass / the robot's total mass" in w for w in check_physical_range([bodies[0], *lighter]))
    assert isinstance(bodies[0], BodyParameters)


def test_an_ill_conditioned_m_is_a_numerical_error_not_1e305(tmp_path, monkeypatch):
    """The full model's forward dynamics and derivatives say when M is numerically singular (as fd_r does),
    for a model the range would refuse (the range switched off here to reach one)."""
    monkeypatch.setattr(robot_module, "check_physical_range", lambda bodies: [])
    path = paper_variant(tmp_path, shank(mass="1e-300", scale_inertia=1e-300))
    robot = load_robot(str(path), cached=False)
    d = full_derivatives(robot)
    q = np.concatenate([[0, 0, 0.3, 0, 0, 0, 1], robot.standing_q])
    for call in (lambda: d.dfd_full(q, np.zeros(18), np.ones(18)), lambda: d.fd_full(q, np.zeros(18), np.ones(18))):
        with pytest.raises(NumericalError, match=r"M has condition number .* here; the full model's forward dynamics "
                                                 r"and its derivatives are numerically singular"):
            call()
