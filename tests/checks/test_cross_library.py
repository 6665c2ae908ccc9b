"""Cross-library suite (``check --against``): Pinocchio as loaded, MuJoCo, iDynTree, Drake and adam
against Pinocchio and the toolkit (Drake's and adam's conventions: tests/references/test_drake_adam.py).

The library tests need the optional extra ``quadruped_dyn[xlib]`` (``./run test`` installs it)
and skip with that reason otherwise. URDF variants that exercise each model diagnosis are
generated from the paper robot's URDF into tmp_path.
"""

from __future__ import annotations

import importlib.util
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner

from quadruped_dyn.checks import cross_library
from quadruped_dyn.checks.cross_library import run_cross_library
from quadruped_dyn.cli import main
from quadruped_dyn.errors import InputError
from quadruped_dyn.math.compare import relative_error
from quadruped_dyn.model import paper_robot
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.interface import ModelChange, PinocchioTerms, Prepared, max_rel_errors
from quadruped_dyn.references.pinocchio import PinocchioReference
from quadruped_dyn.tolerances import REL_TOL_TERMS
from tests.conftest import assert_close

SAMPLES = 3
_MISSING = "needs the optional extra: pip install 'quadruped_dyn[xlib]'"
needs_mujoco = pytest.mark.skipif(importlib.util.find_spec("mujoco") is None, reason=f"mujoco {_MISSING}")
needs_idyntree = pytest.mark.skipif(importlib.util.find_spec("idyntree") is None, reason=f"idyntree {_MISSING}")
needs_drake_adam = pytest.mark.skipif(importlib.util.find_spec("pydrake") is None or importlib.util.find_spec("adam") is None,
                                      reason=f"drake and adam {_MISSING}")
#: Every library ``check --against all`` compares.
ALL = ("pinocchio", "mujoco", "idyntree", "drake", "adam")
#: Other example-robot-data quadrupeds, given by path.
OTHER_QUADRUPEDS = ("b1_description/urdf/b1.urdf", "laikago_description/urdf/laikago.urdf",
                    "anymal_b_simple_description/robots/anymal.urdf")
#: Built-in robots MuJoCo refuses (a 1e-6 dummy base link, or camera/hatch inertias).
MUJOCO_REFUSES = {"go1", "hyq", "anymal_c"}
#: Built-in robots whose inertias Drake regularises (the same links), and those adam refuses as
#: written (an <inertial> without <origin>: the feet of a1 and go1, hyq's base_link and feet).
DRAKE_REGULARISES = MUJOCO_REFUSES
ADAM_REFUSES = {"a1", "go1", "hyq"}


def _kinds(changes: list[ModelChange], library: str) -> set[str]:
    return {c.kind for c in changes if c.library == library}


def _assert_all_pass(report: cross_library.CrossLibraryReport, libraries: tuple[str, ...]) -> None:
    assert {r.library for r in report.results} == set(libraries) and report.passed
    for r in report.results:
        assert r.passed, r
        assert r.max_rel_err_same_model <= REL_TOL_TERMS, r


# ---------------------------------------------------------------------------- command line, no extra needed
def test_against_names_the_package_to_install_when_missing(monkeypatch):
    real = importlib.util.find_spec
    monkeypatch.setattr(cross_library.importlib.util, "find_spec", lambda n, *a: None if n == "mujoco" else real(n, *a))
    result = CliRunner().invoke(main, ["check", "solo12", "--against", "idyntree,mujoco"])
    assert result.exit_code == 2, result.output
    assert "'mujoco'" in result.stderr and "pip install 'quadruped_dyn[xlib]'" in result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


@pytest.mark.parametrize(("against", "expected"), [
    ("bullet", "unknown library 'bullet' in --against; expected all, or a comma-separated subset of: pinocchio, mujoco, "
               "idyntree, drake, adam"),
    ("mujoco,bullet", "unknown library 'bullet'"),
    ("all,drake", "--against 'all,drake' names all beside libraries"),
    (",", "--against is empty; expected all, or a comma-separated subset of"),
])
def test_against_bad_library_list_is_exit_2_before_loading(against, expected):
    result = CliRunner().invoke(main, ["check", "no-such-robot", "--against", against])
    assert result.exit_code == 2
    assert expected in result.stderr and result.stderr.count("\n") == 1, result.stderr


def test_rel_err_fails_on_non_finite():
    """The cross-library comparison's error (``interface.max_rel_errors``) is compare.relative_error."""
    assert relative_error(np.array([np.nan]), np.array([1.0])) == np.inf
    assert relative_error(np.array([1.0]), np.array([np.inf])) == np.inf
    assert relative_error(np.array([1.0 + 1e-12]), np.array([1.0])) == pytest.approx(1e-12, rel=1e-3)


# ---------------------------------------------------------------------------- every robot, both libraries
@needs_mujoco
@needs_idyntree
@needs_drake_adam
@pytest.mark.parametrize("name", ROBOT_NAMES)
def test_builtin_robots_agree_or_explain(name):
    report = run_cross_library(load_robot(name), ALL, SAMPLES, seed=1)
    _assert_all_pass(report, ALL)
    for r in report.results:  # only Drake's regularised inertias change a built-in robot's dynamics
        if r.library == "drake" and name in DRAKE_REGULARISES and r.term in ("M", "C+G", "inverse dynamics"):
            assert r.max_rel_err > REL_TOL_TERMS and r.explained_by == ["regularised_inertia"], r
            assert r.max_rel_err_same_model <= REL_TOL_TERMS, r
        else:
            assert r.max_rel_err <= REL_TOL_TERMS and r.max_rel_err_vs_quadruped_dyn <= REL_TOL_TERMS, r
    assert ("refused" in _kinds(report.changes, "mujoco")) == (name in MUJOCO_REFUSES)
    assert ("regularised_inertia" in _kinds(report.changes, "drake")) == (name in DRAKE_REGULARISES)
    assert ("refused" in _kinds(report.changes, "adam")) == (name in ADAM_REFUSES)
    assert "refused" not in _kinds(report.changes, "idyntree") | _kinds(report.changes, "drake")
    damped = [j for j in ET.parse(load_robot(name).urdf).getroot().findall("joint")
              if float(j.find("dynamics").get("damping", "0") if j.find("dynamics") is not None else 0.0) != 0.0]
    assert ("joint_damping" in _kinds(report.changes, "drake")) == bool(damped)  # named, left out of every term
    assert {lib: list(terms) for lib, terms in report.not_computed.items()} == {"adam": ["inverse dynamics"]}


@needs_mujoco
@needs_idyntree
@pytest.mark.parametrize("relative", OTHER_QUADRUPEDS)
def test_other_quadrupeds_by_path(relative, erd):
    report = run_cross_library(load_robot(str(erd / relative)), ("mujoco", "idyntree"), SAMPLES, seed=2)
    _assert_all_pass(report, ("mujoco", "idyntree"))
    refused = "refused" in _kinds(report.changes, "mujoco")
    assert refused == ("laikago" not in relative)  # b1, anymal_b: the 1e-6 dummy base


@needs_mujoco
def test_anymal_c_diagnosis_names_every_change_with_its_size():
    """docs/results.md, other libraries: cameras break A + B >= C, the hatch is singular, 'base' has no inertial."""
    report = run_cross_library(load_robot("anymal_c"), ("mujoco",), SAMPLES, seed=0)
    changes = {c.kind: c for c in report.changes}
    assert {"hatch", "depth_camera_front_camera"} <= set(changes["refused"].links)
    assert 1e-6 < changes["balanceinertia"].size["M"] < 1e-3  # measured 3e-5..4e-5
    assert changes["merged_inertial"].size["M"] <= REL_TOL_TERMS  # the comparison's copy is exact
    geometry = changes["inertiafromgeom"]
    assert geometry.links == ["base"] and "29.38 kg" in geometry.detail and geometry.size["M"] > 0.1
    assert not geometry.in_comparison and not changes["balanceinertia"].in_comparison


# ---------------------------------------------------------------------------- conventions
@needs_mujoco
def test_mujoco_conventions(paper):
    """Quaternion w x y z; free-joint linear velocity in the world frame (so the raw bias differs)."""
    import mujoco

    from quadruped_dyn.references.mujoco import MuJoCoOptions, MuJoCoReference, compile_model

    mj = MuJoCoReference(compile_model(ET.parse(paper.urdf).getroot(), paper, MuJoCoOptions()), paper)
    ref = PinocchioReference(paper)
    s = random_state(paper.lower, paper.upper, np.random.default_rng(3))
    nle = mj.nonlinear_effects(s.q, s.v)
    assert_close(nle, ref.nonlinear_effects(s.q, s.v), what="C+G converted")
    root = mj.model.jnt_bodyid[0]
    assert_close(mj.data.xquat[root], np.r_[s.q[6], s.q[3:6]] / np.linalg.norm(s.q[3:7]), what="quaternion wxyz")
    foot_world = np.array([mj.data.site_xpos[i] for i in mj.sites])
    assert_close(foot_world, ref.foot_positions(s.q) @ rotation(s.q).T + s.q[:3], what="foot sites in the world")
    mj.data.qvel[:] = 0.0
    mj.data.qvel[:6] = s.v[:6]  # body-frame linear velocity given as if MuJoCo took it
    mj.data.qvel[mj.dof_idx] = s.v[6:]
    mujoco.mj_forward(mj.model, mj.data)
    raw = np.concatenate([mj.data.qfrc_bias[:6], mj.data.qfrc_bias[mj.dof_idx]])
    assert np.abs(raw - nle).max() > 1e-3 * np.abs(nle).max(), "MuJoCo's free joint should not take v_b"


@needs_idyntree
def test_idyntree_body_fixed_representation(paper):
    """BODY_FIXED matches the project's v; iDynTree's default MIXED (linear velocity in the world) does not."""
    import idyntree.bindings as idt

    from quadruped_dyn.references.idyntree import IDynTreeReference, load_model

    lib = IDynTreeReference(load_model(paper.urdf.read_text()), paper)
    ref = PinocchioReference(paper)
    s = random_state(paper.lower, paper.upper, np.random.default_rng(4))
    assert_close(lib.mass_matrix(s.q), ref.mass_matrix(s.q), what="M, BODY_FIXED")
    lib.kin_dyn.setFrameVelocityRepresentation(idt.MIXED_REPRESENTATION)
    M_mixed = lib.mass_matrix(s.q)
    assert np.abs(M_mixed - ref.mass_matrix(s.q)).max() > 1e-3 * np.abs(M_mixed).max()


@needs_mujoco
@needs_idyntree
def test_joints_mapped_by_name():
    """anymal_c: Pinocchio orders the legs LF, LH, RF, RH, the project FL, FR, BL, BR."""
    from quadruped_dyn.references.idyntree import prepare as idyntree_prepare

    robot = load_robot("anymal_c")
    assert list(robot.idx_v) != sorted(robot.idx_v)
    states = [random_state(robot.lower, robot.upper, np.random.default_rng(5))]
    lib = idyntree_prepare(robot, states, PinocchioTerms(robot)).reference
    assert lib is not None
    errors = max_rel_errors(lib, PinocchioTerms(robot), states)
    assert max(errors.values()) <= REL_TOL_TERMS, errors


# ---------------------------------------------------------------------------- generated variants, one per diagnosis
def _variant(tmp_path, name: str, edit) -> str:
    root = ET.fromstring(paper_robot.urdf_text())
    edit(root)
    path = tmp_path / f"{name}.urdf"
    path.write_text(ET.tostring(root, encoding="unicode"))
    return str(path)


def _link(root: ET.Element, name: str) -> ET.Element:
    return next(x for x in root.findall("link") if x.get("name") == name)


def _welded(root: ET.Element, name: str, parent: str, inertial: str | None, collision: str | None = None) -> None:
    """Add link ``name`` welded to ``parent`` 5 cm above its origin."""
    link = ET.SubElement(root, "link", name=name)
    if inertial:
        link.append(ET.fromstring(inertial))
    if collision:
        link.append(ET.fromstring(collision))
    joint = ET.SubElement(root, "joint", name=f"{parent}_to_{name}", type="fixed")
    ET.SubElement(joint, "origin", xyz="0.02 0 0.05", rpy="0 0.5 0")
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=name)


def new_root(root: ET.Element, inertial: str, xyz: str | None = None) -> None:
    """A new root link 'base' with this inertial, welded to the trunk (without an <origin>, or at xyz)."""
    link = ET.Element("link", name="base")
    link.append(ET.fromstring(inertial))
    root.insert(0, link)
    joint = ET.SubElement(root, "joint", name="base_to_trunk", type="fixed")
    if xyz is not None:
        ET.SubElement(joint, "origin", xyz=xyz, rpy="0 0 0")  # the toolkit takes the trunk unrotated
    ET.SubElement(joint, "parent", link="base")
    ET.SubElement(joint, "child", link="trunk")


def _dummy_root(root: ET.Element) -> None:
    """A new root link 'base' with the 1e-6 dummy inertia of b1/go1/anymal_b (rank 1), welded to the trunk."""
    new_root(root, '<inertial><mass value="1e-6"/><inertia ixx="1e-6" ixy="1e-6" ixz="1e-6" iyy="1e-6" iyz="1e-6" '
             'izz="1e-6"/></inertial>')


_CAMERA = ('<inertial><origin xyz="-0.021 -0.002 0.025" rpy="0 0 0"/><mass value="0.16"/><inertia ixx="0.000637051" '
           'ixy="0.000484569" ixz="0.000424211" iyy="0.000929402" iyz="5.138e-06" izz="0.000484569"/></inertial>')


def _camera(root: ET.Element) -> None:
    _welded(root, "camera", "trunk", _CAMERA)


def _thigh_breaks_triangle(root: ET.Element) -> None:
    """FL_thigh (between two revolute joints: no welded neighbour) positive definite but A + B < C."""
    inertia = _link(root, "FL_thigh").find("inertial/inertia")
    assert inertia is not None
    inertia.attrib.update(ixx="1e-4", iyy="1e-4", izz="1e-3")


def _box_without_inertial(root: ET.Element) -> None:
    _welded(root, "sensor_box", "trunk", None,
            '<collision><origin xyz="0 0 0.1"/><geometry><box size="0.1 0.2 0.05"/></geometry></collision>')


@needs_mujoco
@needs_idyntree
@pytest.mark.parametrize(("edit", "mujoco_kinds"), [
    (_dummy_root, {"refused", "merged_inertial"}),
    (_camera, {"refused", "balanceinertia", "merged_inertial"}),
])
def test_refused_welded_inertia_is_merged_exactly(tmp_path, edit, mujoco_kinds):
    robot = load_robot(_variant(tmp_path, edit.__name__, edit))
    report = run_cross_library(robot, ("mujoco", "idyntree"), SAMPLES, seed=6)
    _assert_all_pass(report, ("mujoco", "idyntree"))
    changes = {c.kind: c for c in report.changes if c.library == "mujoco"}
    assert mujoco_kinds <= set(changes)
    assert changes["merged_inertial"].size["M"] <= REL_TOL_TERMS
    assert "accepted_as_is" in _kinds(report.changes, "idyntree")
    for r in report.results:
        assert r.max_rel_err <= REL_TOL_TERMS, r  # same dynamics as the original: exact merge, iDynTree as written
    if "balanceinertia" in mujoco_kinds:  # MuJoCo's own fix would change M: measured, named, not used
        assert changes["balanceinertia"].size["M"] > 1e-8


@needs_mujoco
def test_moving_link_breaking_triangle_is_balanced_as_mujoco_does(tmp_path, monkeypatch):
    """No welded neighbour: the comparison carries MuJoCo's balanceinertia rule, written into the copy
    (principal moments -> their mean). MuJoCo with balanceinertia on the original equals Pinocchio on
    that copy, so the difference from the original is the named change, and it is large.
    The toolkit itself refuses such a leg link (docs/reliability.md §2, urdf_rules); the comparison is
    exercised with that validation bypassed."""
    import quadruped_dyn.model.leg_discovery
    import quadruped_dyn.model.urdf_parsing

    path = _variant(tmp_path, "thigh", _thigh_breaks_triangle)
    with pytest.raises(InputError, match=r"link 'FL_thigh' .*triangle inequality"):
        load_robot(path)
    monkeypatch.setattr(quadruped_dyn.model.urdf_parsing, "validate_urdf", lambda path, data=None: [])
    monkeypatch.setattr(quadruped_dyn.model.leg_discovery, "inertia_problem", lambda moments: None)  # the merged-body check
    robot = load_robot(path, cached=False)
    report = run_cross_library(robot, ("mujoco",), SAMPLES, seed=7)
    _assert_all_pass(report, ("mujoco",))
    changes = {c.kind: c for c in report.changes}
    assert changes["balanced_inertia"].links == ["FL_thigh"] and changes["balanced_inertia"].in_comparison
    m = next(r for r in report.results if r.term == "M")
    assert m.max_rel_err > 1e-6 and m.explained_by == ["balanced_inertia"]
    # MuJoCo's own fix (measured against the original) has the same size as the change we wrote
    assert changes["balanceinertia"].size["M"] == pytest.approx(m.model_change, rel=1e-6)


@needs_mujoco
def test_inertia_from_geometry_is_measured_not_used(tmp_path):
    robot = load_robot(_variant(tmp_path, "box", _box_without_inertial))
    report = run_cross_library(robot, ("mujoco",), SAMPLES, seed=8)
    _assert_all_pass(report, ("mujoco",))
    geometry = next(c for c in report.changes if c.kind == "inertiafromgeom")
    box_mass = 1000.0 * 0.1 * 0.2 * 0.05  # MuJoCo's default density, kg/m^3, times the box's volume
    assert geometry.links == ["sensor_box"] and f"{box_mass:.2f} kg" in geometry.detail
    assert geometry.size["M"] > 1e-3 and not geometry.in_comparison


# ---------------------------------------------------------------------------- an unexplained difference fails
@needs_mujoco
@pytest.mark.parametrize("corruption", [1.0 + 1e-7, np.nan])
def test_unexplained_difference_fails(monkeypatch, paper, corruption):
    from quadruped_dyn.references import mujoco as mujoco_ref

    real_prepare = mujoco_ref.prepare

    def corrupted(robot, states, pin_ref) -> Prepared:
        prepared = real_prepare(robot, states, pin_ref)
        lib = prepared.reference
        assert lib is not None
        real_mass_matrix = lib.mass_matrix
        lib.mass_matrix = lambda q: real_mass_matrix(q) * corruption  # type: ignore[method-assign]
        return prepared

    monkeypatch.setattr(mujoco_ref, "prepare", corrupted)
    report = run_cross_library(paper, ("mujoco",), SAMPLES, seed=9)
    failed = [r.term for r in report.results if not r.passed]
    assert failed == ["M"] and not report.passed
    result = CliRunner().invoke(main, ["check", "paper", "--samples", "1", "--against", "mujoco"])
    assert result.exit_code == 1 and "SOME DIFFERENCES UNEXPLAINED" in result.output


@needs_mujoco
def test_a_merge_that_changes_the_dynamics_is_not_an_explanation(monkeypatch, tmp_path):
    """Merging welded inertials must be exact; a merge that moved mass would be caught, not excused."""
    from quadruped_dyn.references import mujoco as mujoco_ref

    real_merge = mujoco_ref.merge_inertial

    def heavier_merge(root: ET.Element, link: str) -> str | None:
        neighbour = real_merge(root, link)
        mass = _link(root, neighbour or "").find("inertial/mass")
        assert mass is not None
        mass.set("value", repr(1.01 * float(mass.get("value", "0"))))
        return neighbour

    monkeypatch.setattr(mujoco_ref, "merge_inertial", heavier_merge)
    report = run_cross_library(load_robot(_variant(tmp_path, "dummy", _dummy_root)), ("mujoco",), SAMPLES, seed=10)
    assert {r.term for r in report.results if not r.passed} == {"M", "C+G", "G", "inverse dynamics"}


def _continuous_knees(root: ET.Element) -> None:
    for joint in root.findall("joint"):
        if joint.get("name", "").endswith("KFE"):
            joint.set("type", "continuous")


@needs_mujoco
@needs_idyntree
@needs_drake_adam
def test_continuous_joints_and_json_report(tmp_path):
    """Continuous knees: (cos, sin) in Pinocchio's q, an angle in the other libraries'; the JSON
    report (``--against all``) carries one `cross_library` entry per library and term it computes,
    and the conformance table every library and term."""
    import json

    path = _variant(tmp_path, "continuous", _continuous_knees)
    assert list(load_robot(path).joint_nq) == [1, 1, 2] * 4
    result = CliRunner().invoke(main, ["check", path, "--samples", "2", "--json", "--against", "all"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    entries = data["cross_library"]
    assert {(e["library"], e["term"]) for e in entries} == {(lib, t) for lib in ALL for t in cross_library.TERMS} - {
        ("adam", "inverse dynamics")}
    assert all(e["passed"] and e["max_rel_err"] <= REL_TOL_TERMS for e in entries)
    assert data["passed"] and {c["kind"] for c in data["model_changes"]} >= {"fused_links", "welded_bodies"}
    statuses = {(lib, t): row["status"] for lib, terms in data["conformance"].items() for t, row in terms.items()}
    assert len(statuses) == len(ALL) * len(cross_library.TERMS) and data["cross_library_unexplained"] == 0
    assert statuses.pop(("adam", "inverse dynamics")) == "not computed" and set(statuses.values()) == {"agrees"}


@pytest.mark.parametrize("against", ["mujoco,idyntree", "mujoco", "idyntree,mujoco"])
def test_a_library_asked_for_and_not_compared_fails(monkeypatch, paper, against):
    """MuJoCo refusing the URDF and its edited copy compares nothing: the check fails (exit 1) and
    says which library was not compared and why, in the table and the JSON; iDynTree's rows alone
    are not a pass."""
    import json

    from quadruped_dyn.references import mujoco as mujoco_ref

    def refuse(*args, **kwargs):
        raise mujoco_ref.MuJoCoRefusal("Error: mass and inertia of moving bodies must be larger than mjMINVAL")

    monkeypatch.setattr(mujoco_ref, "compile_model", refuse)
    report = run_cross_library(paper, against.split(","), samples=2)
    assert not report.passed and list(report.not_compared) == ["mujoco"]
    assert "refuses the edited copy too" in report.not_compared["mujoco"]
    assert "mujoco    (nothing)         not compared: MuJoCo refuses" in report.table()
    assert "NOT COMPARED: mujoco" in report.table()
    if against != "mujoco,idyntree":
        return  # the command line once (it runs the whole term check first)
    result = CliRunner().invoke(main, ["check", "paper", "--samples", "2", "--json", "--against", against])
    assert result.exit_code == 1, result.output
    data = json.loads(result.stdout)
    assert data["cross_library_passed"] is False and data["passed"] is False
    assert list(data["cross_library_not_compared"]) == ["mujoco"]
    assert {e["library"] for e in data["cross_library"]} == {"idyntree"}
