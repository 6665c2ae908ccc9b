"""URDF validation (docs/reliability.md §2): variants of the paper's URDF, generated here, are rejected
with one line naming the element and the value (exit 2), or load and give the right answers
(continuous joints, an odd inertia on a fixed link, the same file by another path)."""

from __future__ import annotations

import re
import shutil
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from quadruped_dyn.checks.terms import run_check
from quadruped_dyn.cli import main
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.errors import UrdfWarning
from quadruped_dyn.model import paper_robot
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close


def _variant(tmp_path: Path, edit: Callable[[ET.Element], None], name: str = "variant.urdf") -> Path:
    root = ET.fromstring(paper_robot.urdf_text())
    edit(root)
    path = tmp_path / name
    path.write_text(ET.tostring(root, encoding="unicode"))
    return path


def _joint(root: ET.Element, name: str) -> ET.Element:
    return next(j for j in root.iter("joint") if j.get("name") == name)


def _inertial(root: ET.Element, link: str) -> ET.Element:
    return next(x for x in root.iter("link") if x.get("name") == link).find("inertial")  # type: ignore[return-value]


def _set(root: ET.Element, joint: str, child: str, attribute: str, value: str) -> None:
    _joint(root, joint).find(child).set(attribute, value)  # type: ignore[union-attr]


def _mass(value: str) -> Callable[[ET.Element], None]:
    return lambda r: _inertial(r, "FL_shank").find("mass").set("value", value)  # type: ignore[union-attr]


def _inertia(**values: str) -> Callable[[ET.Element], None]:
    def edit(r: ET.Element) -> None:
        element = _inertial(r, "FL_shank").find("inertia")
        for k, v in values.items():
            element.set(k, v)  # type: ignore[union-attr]

    return edit


def _mimic(r: ET.Element) -> None:
    ET.SubElement(_joint(r, "FL_KFE"), "mimic", joint="FL_HFE", multiplier="1")


def _drop_mass(r: ET.Element) -> None:
    inertial = _inertial(r, "FL_shank")
    inertial.remove(inertial.find("mass"))  # type: ignore[arg-type]


#: (case, edit of the paper URDF, expected one-line message)
BAD_URDFS = [
    ("zero axis", lambda r: _set(r, "FL_HFE", "axis", "xyz", "0 0 0"),
     r"joint 'FL_HFE' has <axis xyz=\"0 0 0\">; expected a nonzero direction"),
    ("NaN axis", lambda r: _set(r, "FL_HFE", "axis", "xyz", "nan 0 1"),
     r"joint 'FL_HFE' <axis> has xyz=\"nan 0 1\"; expected finite numbers"),
    ("inf origin", lambda r: _set(r, "FL_HAA", "origin", "xyz", "inf 0.07 0"),
     r"joint 'FL_HAA' <origin> has xyz=\"inf 0.07 0\"; expected finite numbers"),
    ("NaN rpy", lambda r: _set(r, "FL_HAA", "origin", "rpy", "0 nan 0"),
     r"joint 'FL_HAA' <origin> has rpy=\"0 nan 0\"; expected finite numbers"),
    ("1e300 length", lambda r: _set(r, "FL_KFE", "origin", "xyz", "1e300 0 0"),
     r"joint 'FL_KFE' <origin> has xyz=\"1e300 0 0\"; expected magnitudes <= 100"),
    ("non-numeric origin", lambda r: _set(r, "FL_KFE", "origin", "xyz", "a b c"),
     r"joint 'FL_KFE' <origin> has xyz=\"a b c\"; expected 3 number"),
    ("two-number origin", lambda r: _set(r, "FL_KFE", "origin", "xyz", "0.2 0"),
     r"joint 'FL_KFE' <origin> has xyz=\"0.2 0\"; expected 3 number"),
    ("lower > upper", lambda r: _set(r, "FL_KFE", "limit", "lower", "1"),
     r"joint 'FL_KFE' has <limit lower=\"1\" upper=\"-0.3\">; expected lower <= upper"),
    ("NaN limit", lambda r: _set(r, "FL_KFE", "limit", "upper", "nan"),
     r"joint 'FL_KFE' <limit> has upper=\"nan\"; expected finite numbers"),
    ("mimic joint", _mimic,
     r"joint 'FL_KFE' has a <mimic> element \(it copies joint 'FL_HFE'\); expected a leg of 3 independent"),
    ("floating joint", lambda r: _joint(r, "FL_HAA").set("type", "floating"),
     r"joint 'FL_HAA' has type 'floating'; expected revolute or continuous joints in the legs"),
    ("planar joint", lambda r: _joint(r, "FL_HFE").set("type", "planar"),
     r"joint 'FL_HFE' has type 'planar'; expected revolute or continuous"),
    ("NaN mass", _mass("nan"), r"link 'FL_shank' <inertial> <mass> has value=\"nan\"; expected finite numbers"),
    ("1e400 mass", _mass("1e400"), r"link 'FL_shank' <inertial> <mass> has value=\"1e400\"; expected finite numbers"),
    ("1e300 mass", _mass("1e300"), r"<mass> has value=\"1e300\"; expected magnitudes <= 100000"),
    ("negative mass", _mass("-0.15"), r"<mass value=\"-0.15\">; expected a mass >= 0 kg"),
    ("no mass", _drop_mass, r"link 'FL_shank' <inertial> has no <mass>"),
    ("NaN inertia", _inertia(iyy="nan"), r"link 'FL_shank' <inertial> <inertia> has iyy=\"nan\"; expected finite"),
    ("negative inertia", _inertia(ixx="-1"), r"link 'FL_shank' <inertial> <inertia> is not positive semi-definite"),
    ("A + B < C", _inertia(ixx="1e-4", iyy="1e-4", izz="1e-3"),
     r"link 'FL_shank' <inertial> <inertia> breaks the triangle inequality A \+ B >= C: principal moments"),
]


@pytest.mark.parametrize(("case", "edit", "expected"), BAD_URDFS, ids=[c[0] for c in BAD_URDFS])
def test_bad_urdf_is_one_line_exit_2(case, edit, expected, tmp_path):
    path = _variant(tmp_path, edit)
    for command in (["info", str(path)], ["check", str(path), "--samples", "1"]):
        result = CliRunner().invoke(main, command)
        assert result.exit_code == 2, (case, result.output)
        assert "Traceback" not in result.output
        assert re.search(expected, result.stderr), result.stderr
        assert result.stderr.count("\n") == 1, "expected one line"


def test_odd_inertia_on_a_fixed_link_is_a_warning(tmp_path):
    """A link fixed to the trunk with anymal_c's 'hatch' inertia (A + B < C): one warning line,
    and the robot loads with the merged (physical) trunk."""

    def add_hatch(r: ET.Element) -> None:
        link = ET.SubElement(r, "link", name="hatch")
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "mass", value="0.1")
        ET.SubElement(inertial, "inertia", ixx="0.001", ixy="0.001", ixz="0.001", iyy="0.001", iyz="0.001", izz="0.001")
        joint = ET.SubElement(r, "joint", name="hatch_fixed", type="fixed")
        ET.SubElement(joint, "parent", link="trunk")
        ET.SubElement(joint, "child", link="hatch")

    path = _variant(tmp_path, add_hatch)
    with pytest.warns(UrdfWarning, match=r"link 'hatch' .*triangle inequality.*a fixed link: warned"):
        robot = load_robot(str(path))
    assert robot.trunk.mass == pytest.approx(paper_robot.PARAMS.trunk_mass + 0.1)
    result = CliRunner().invoke(main, ["info", str(path)])
    assert result.exit_code == 0
    assert [line for line in result.stderr.splitlines() if line.startswith("warning:")] == result.stderr.splitlines()


def test_continuous_joints_keep_working(tmp_path):
    """All 12 joints continuous ((cos, sin) in Pinocchio's q): every term still agrees with
    Pinocchio, and M equals the revolute robot's at the same angles."""

    def continuous(r: ET.Element) -> None:
        for joint in r.iter("joint"):
            if joint.get("type") == "revolute":
                joint.set("type", "continuous")

    robot = load_robot(str(_variant(tmp_path, continuous)))
    assert (robot.joint_nq == 2).all()
    report = run_check(robot, samples=2, seed=0)
    assert report.passed, report.table()
    paper = load_robot("paper")
    s = random_state(paper.lower, paper.upper, np.random.default_rng(0))
    assert_close(np.asarray(full_dynamics(robot).M_full_walker_orin(s.q)), PinocchioReference(paper).mass_matrix(s.q), what="M")


def test_one_robot_identity(tmp_path, monkeypatch):
    """The built-in name, a relative path, a copy and a symlink of the paper URDF are one robot."""
    copy = tmp_path / "copy.urdf"
    shutil.copy(paper_robot.URDF_PATH, copy)
    (tmp_path / "link.urdf").symlink_to(paper_robot.URDF_PATH)
    monkeypatch.chdir(paper_robot.URDF_PATH.parent)
    robots = [load_robot(x) for x in ("paper", paper_robot.URDF_PATH.name, str(copy), str(tmp_path / "link.urdf"))]
    for r in robots:
        assert r.name == "paper"
        assert np.array_equal(r.standing_q, robots[0].standing_q)
    outputs = {CliRunner().invoke(main, ["info", x, "--json"]).output.replace(str(copy), "URDF")
               for x in ("paper", str(copy))}
    assert len({re.sub(r'"urdf": "[^"]*"', "", o) for o in outputs}) == 1


def test_edited_copy_is_another_robot(tmp_path):
    path = _variant(tmp_path, _mass("0.2"), name="heavier.urdf")
    robot = load_robot(str(path))
    assert robot.name == "heavier"


def test_no_parser_noise_at_the_file_descriptor_level(tmp_path):
    """Pinocchio's C++ parser printed 4-6 lines straight to fd 2 for a NaN origin; validation
    now rejects the file before the parser sees it (a subprocess sees all of stderr)."""
    import subprocess
    import sys

    path = _variant(tmp_path, lambda r: _set(r, "FL_HAA", "origin", "xyz", "nan 0 0"))
    proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "info", str(path)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: joint 'FL_HAA' <origin>"), proc.stderr


def test_validate_runs_on_a_copy_of_the_paper_urdf(tmp_path):
    """The trot experiment used to refuse any copy of the paper URDF (identity by unresolved path)."""
    copy = tmp_path / "copy.urdf"
    shutil.copy(paper_robot.URDF_PATH, copy)
    result = CliRunner().invoke(main, ["validate", str(copy), "--horizon", "0.01", "--dt", "0.001",
                                       "--out", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out" / "paper_trot_validation.json").is_file()


def _world_root(xyz: str, rpy: str) -> Callable[[ET.Element], None]:
    """A 'world' link as the URDF's root, the trunk welded to it at (xyz, rpy)."""

    def edit(r: ET.Element) -> None:
        joint = ET.Element("joint", name="world_to_trunk", type="fixed")
        ET.SubElement(joint, "origin", xyz=xyz, rpy=rpy)
        ET.SubElement(joint, "parent", link="world")
        ET.SubElement(joint, "child", link="trunk")
        r.insert(0, joint)
        r.insert(0, ET.Element("link", name="world"))

    return edit


def _pinocchio_mass_matrix(path: Path, joint_names: list[str], q: np.ndarray) -> np.ndarray:
    """Pinocchio's M of the URDF at ``path`` with a free-flyer root, built here (not by the loader),
    rows and columns in the order (base, ``joint_names``) of the revolute joints, at the project's q."""
    import pinocchio as pin

    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    q_pin = np.concatenate([q[:7], np.zeros(model.nq - 7)])
    order = list(range(6))
    for k, name in enumerate(joint_names):
        joint = model.joints[model.getJointId(name)]
        q_pin[joint.idx_q] = q[7 + k]
        order.append(joint.idx_v)
    M = pin.crba(model, model.createData(), q_pin)
    M = np.triu(M) + np.triu(M, 1).T
    return M[np.ix_(order, order)]


def test_trunk_welded_to_a_world_root_with_an_offset(tmp_path):
    """A 'world' root link with the trunk welded 0.3 m forward and 0.2 m right of it: the legs are
    labelled about the hips' centre (they were not: both right hips are in the FR quadrant of
    'world', an InputError), and M agrees with Pinocchio's model of the same file."""
    path = _variant(tmp_path, _world_root("0.3 -0.2 0.5", "0 0 0"))
    robot = load_robot(str(path))
    assert robot.joint_names == load_robot("paper").joint_names  # FL_HAA ... BR_KFE: each leg where its name says
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    assert_close(np.asarray(full_dynamics(robot).M_full_walker_orin(s.q)), _pinocchio_mass_matrix(path, robot.joint_names, s.q),
                 what="M")


@pytest.mark.parametrize(("rpy", "said"), [("0 0 3.141592653589793", "[0.     0.     3.1416]"),
                                           ("3.141592653589793 0 0", "[3.1416 0.     0.    ]"),
                                           ("0 0 1.5707963267948966", "[0.     0.     1.5708]"),
                                           ("0 0 1e-6", "[0.e+00 0.e+00 1.e-06]")])
def test_trunk_welded_rotated_to_a_world_root_is_refused(rpy, said, tmp_path):
    """The trunk welded turned by a yaw of 180 deg (or upside down, or 90 deg) to a 'world' root link:
    the model's frame b is the root's, so legs labelled in it were the wrong legs, silently (FL was the
    trunk's back-right leg). Now one line, exit 2, naming the links."""
    path = _variant(tmp_path, _world_root("0 0 0.4", rpy))
    for command in (["info", str(path)], ["check", str(path), "--samples", "1"]):
        result = CliRunner().invoke(main, command)
        assert result.exit_code == 2, result.output
        assert re.search(r"the legs hang from link 'trunk', which the URDF's root link 'world' holds rotated",
                         result.stderr), result.stderr
        assert f"(rpy {said} through fixed joints)" in result.stderr, result.stderr  # 1e-6 rad was printed as 0
        assert result.stderr.count("\n") == 1, "expected one line"


def test_a_deep_tree_is_refused_before_pinocchio_recurses_into_it(tmp_path):
    """A chain of 4,500 fixed links below the trunk (within MAX_URDF_LINKS): Pinocchio's parser
    recursed once per level and the process died of SIGSEGV (no message, exit -11). Now one line,
    exit 2, before the parser (a subprocess sees the signal, and all of stderr)."""
    import subprocess
    import sys

    def deep_chain(r: ET.Element) -> None:
        parent = "trunk"
        for k in range(4500):
            ET.SubElement(r, "link", name=f"bracket{k}")
            joint = ET.SubElement(r, "joint", name=f"bracket{k}_fixed", type="fixed")
            ET.SubElement(joint, "origin", xyz="0 0 0.0001")
            ET.SubElement(joint, "parent", link=parent)
            ET.SubElement(joint, "child", link=f"bracket{k}")
            parent = f"bracket{k}"

    path = _variant(tmp_path, deep_chain)
    proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "info", str(path)],
                          capture_output=True, text=True, check=False, timeout=600)
    assert proc.returncode == 2, (proc.returncode, proc.stderr[-300:])
    assert proc.stderr.count("\n") == 1, proc.stderr
    expected = "error: 'variant.urdf' has a chain of 4500 joints from its root link; expected at most"
    assert proc.stderr.startswith(expected), proc.stderr


def test_trunk_frame_origin_outside_the_hips(tmp_path):
    """The trunk frame's origin 0.5 m behind and 0.3 m right of the body (a CAD export's origin): every
    hip has x > 0 and y > 0 in it. The legs are labelled about the hips' centre (it was an InputError,
    "two legs have their hip in the FL quadrant", for a valid robot), and M agrees with Pinocchio."""

    def shift_trunk_origin(r: ET.Element) -> None:
        for element in [*r.iter("joint"), next(x for x in r.iter("link") if x.get("name") == "trunk").find("inertial")]:
            parent = element.find("parent")
            if element.tag == "joint" and parent is not None and parent.get("link") != "trunk":
                continue
            origin = element.find("origin")
            xyz = np.array([float(x) for x in origin.get("xyz", "0 0 0").split()]) + [0.5, 0.3, 0.0]  # type: ignore[union-attr]
            origin.set("xyz", " ".join(repr(float(x)) for x in xyz))  # type: ignore[union-attr]

    path = _variant(tmp_path, shift_trunk_origin)
    robot = load_robot(str(path))
    assert robot.joint_names == load_robot("paper").joint_names  # FL_HAA ... BR_KFE: each leg where its name says
    assert (robot.legs[0].hip[:2] > 0).all() and (robot.legs[3].hip[:2] > 0).all()  # BR's hip too, in this frame
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    assert_close(np.asarray(full_dynamics(robot).M_full_walker_orin(s.q)), _pinocchio_mass_matrix(path, robot.joint_names, s.q),
                 what="M")


def _payload(mass: str) -> Callable[[ET.Element], None]:
    """A battery welded to the trunk, its mass written as ``mass``."""

    def edit(r: ET.Element) -> None:
        link = ET.SubElement(r, "link", name="battery")
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "origin", xyz="0 0 0.05", rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=mass)
        ET.SubElement(inertial, "inertia", ixx="0.002", ixy="0", ixz="0", iyy="0.004", iyz="0", izz="0.005")
        joint = ET.SubElement(r, "joint", name="battery_fixed", type="fixed")
        ET.SubElement(joint, "parent", link="trunk")
        ET.SubElement(joint, "child", link="battery")

    return edit


def test_a_mass_pinocchio_cannot_read_is_refused(tmp_path):
    """<mass value="2.0 "> (a trailing space) on a battery welded to the trunk: the validation read 2.0,
    Pinocchio's parser (urdfdom) dropped the whole <inertial>, said so on stderr, which was swallowed,
    and the robot loaded 2 kg light (exit 0, every check passing against the same light model).
    Now one line, exit 2, naming the element."""
    path = _variant(tmp_path, _payload("2.0 "))
    for command in (["info", str(path)], ["check", str(path), "--samples", "1"]):
        result = CliRunner().invoke(main, command)
        assert result.exit_code == 2, result.output
        assert re.search(r"parser skipped part of .*mass \[2\.0 \] is not a float", result.stderr), result.stderr
        assert result.stderr.count("\n") == 1, "expected one line"


def test_pinocchio_reads_the_xml_the_validation_read(tmp_path):
    """A Latin-1 file with a non-ASCII link name: Pinocchio's parser was given the bytes decoded as UTF-8
    and read 'batterie_\xe4' as U+FFFD. Now it reads the XML as the validation did: the name is kept,
    and M equals Pinocchio's of the same robot written in UTF-8."""
    plain = _variant(tmp_path, _payload("2.0"), name="plain.urdf")
    latin1 = tmp_path / "latin1.urdf"
    latin1.write_bytes(('<?xml version="1.0" encoding="iso-8859-1"?>\n'
                        + plain.read_text().replace('"battery"', '"batterie_\xe4"')).encode("latin-1"))
    robot = load_robot(str(latin1))
    assert robot.model.existFrame("batterie_\xe4")
    assert robot.total_mass == pytest.approx(load_robot("paper").total_mass + 2.0, rel=1e-12)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    assert_close(np.asarray(full_dynamics(robot).M_full_walker_orin(s.q)), _pinocchio_mass_matrix(plain, robot.joint_names, s.q),
                 what="M")


def test_an_xml_entity_is_refused(tmp_path):
    """The battery's mass through a DTD entity (&battery; = 2.0): Python's parser expanded it for the
    validation, Pinocchio's parser (and MuJoCo's, and the benchmark's C++ Pinocchio, reading the file)
    did not, dropped the <inertial>, and the robot loaded 2 kg light, silently. Now one line, exit 2."""
    plain = _variant(tmp_path, _payload("2.0"), name="plain.urdf")
    path = tmp_path / "entity.urdf"
    path.write_text('<?xml version="1.0"?>\n<!DOCTYPE robot [<!ENTITY battery "2.0">]>\n'
                    + plain.read_text().replace('value="2.0"', 'value="&battery;"'))
    result = CliRunner().invoke(main, ["info", str(path)])
    assert result.exit_code == 2, result.output
    assert "'entity.urdf' declares the XML entity 'battery'; expected a URDF without <!ENTITY> declarations" in result.stderr
    assert result.stderr.count("\n") == 1, "expected one line"


@pytest.mark.parametrize(("lower", "upper"), [(3.5, 4.0), (-4.0, -3.5)])
def test_a_joint_range_beyond_pi_is_kept(lower, upper, tmp_path):
    """FL KFE limited to [3.5, 4.0] rad (valid: lower <= upper): clipping each limit to [-pi, pi] made
    the range [3.5, 3.14], and check refused the robot after its symbolic build ("joint limits at
    joints [2] are not a finite range"). The URDF's range is kept, and every term agrees with Pinocchio."""
    path = _variant(tmp_path, lambda r: (_set(r, "FL_KFE", "limit", "lower", str(lower)),
                                         _set(r, "FL_KFE", "limit", "upper", str(upper))))
    robot = load_robot(str(path))
    assert (robot.lower[2], robot.upper[2]) == (lower, upper)
    assert lower <= robot.standing_q[2] <= upper
    report = run_check(robot, samples=2, seed=0)
    assert report.passed, report.table()


def _second_parent(r: ET.Element) -> None:
    joint = ET.SubElement(r, "joint", name="strut", type="fixed")
    ET.SubElement(joint, "parent", link="trunk")
    ET.SubElement(joint, "child", link="FL_thigh")


@pytest.mark.parametrize(("case", "edit", "expected"), [
    ("loop", lambda r: _set(r, "FL_KFE", "child", "link", "trunk"),
     r"the joints make a loop through link '(trunk|FL_hip|FL_thigh)'; expected a tree of links hanging from one root"),
    ("two parents", _second_parent,
     r"link 'FL_thigh' is the child of joints 'FL_HFE' and 'strut'; expected a tree: each link the child of one joint"),
])
def test_links_that_are_not_a_tree_are_named(case, edit, expected, tmp_path):
    """FL_KFE's child set to the trunk (a loop) was "'variant.urdf' has 0 joint chains from the trunk";
    a second joint to FL_thigh, which Pinocchio's parser accepted, was "6 joint chains from the trunk with
    [3, 3, 1, 1, 3, 1] joints": one line naming the loop, or the link and its two joints."""
    path = _variant(tmp_path, edit)
    result = CliRunner().invoke(main, ["info", str(path)])
    assert result.exit_code == 2, (case, result.output)
    assert re.search(expected, result.stderr), result.stderr
    assert result.stderr.count("\n") == 1, "expected one line"


def test_a_colour_pinocchio_cannot_read_is_harmless(tmp_path):
    """A top-level <material name="grey"/> without a colour: urdfdom says "Material [grey] color has no
    rgba" and parses on. Only what the dynamics read is refused when the parser skips it: the robot
    loads, and M equals the paper robot's."""
    path = _variant(tmp_path, lambda r: r.insert(0, ET.Element("material", name="grey")))
    robot = load_robot(str(path))
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    assert_close(np.asarray(full_dynamics(robot).M_full_walker_orin(s.q)),
                 _pinocchio_mass_matrix(paper_robot.URDF_PATH, robot.joint_names, s.q), what="M")


def test_a_prismatic_leg_joint_is_named_as_the_urdf_names_it(tmp_path):
    """FL_KFE of type prismatic was "leg joint 'FL_KFE' is JointModelPZ" (Pinocchio's class, not the URDF's type)."""
    path = _variant(tmp_path, lambda r: _joint(r, "FL_KFE").set("type", "prismatic"))
    result = CliRunner().invoke(main, ["info", str(path)])
    assert result.exit_code == 2, result.output
    assert re.search(r"leg joint 'FL_KFE' is prismatic \(JointModelP\w*\); expected revolute joints only", result.stderr), \
        result.stderr
    assert result.stderr.count("\n") == 1, "expected one line"
