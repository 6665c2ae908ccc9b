"""Drake's and adam's conventions, converted by their adapters (references/drake.py, adam.py),
checked against Pinocchio on a moving state (non-zero trunk twist and acceleration), and what
each does to a URDF: a root-link inertia, continuous joints, a URDF it refuses.

Every built-in robot against both: tests/checks/test_cross_library.py (``--against all``). The
sweep over example-robot-data's quadrupeds by path is slow. The extra ``quadruped_dyn[xlib]``
installs both (``./run test`` does); without it these tests skip with that reason."""

from __future__ import annotations

import importlib.util
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner

from quadruped_dyn.checks import cross_library
from quadruped_dyn.checks.cross_library import LIBRARIES, run_cross_library
from quadruped_dyn.cli import main
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.registry import example_robot_data_dir
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import NV_FULL, classical_from_spatial, random_state, rotation
from quadruped_dyn.references.interface import PinocchioTerms, terms_at
from quadruped_dyn.tolerances import REL_TOL_TERMS
from tests.checks.test_cross_library import _continuous_knees, _dummy_root, _variant, new_root
from tests.conftest import assert_close

_MISSING = "needs the optional extra: pip install 'quadruped_dyn[xlib]'"
needs_drake = pytest.mark.skipif(importlib.util.find_spec("pydrake") is None, reason=f"drake {_MISSING}")
needs_adam = pytest.mark.skipif(importlib.util.find_spec("adam") is None, reason=f"adam {_MISSING}")
SAMPLES = 2


def _moving_state(robot, seed: int):
    """A random state whose trunk twist and acceleration are far from zero (|v_b|, |omega_b| ~ 1)."""
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    assert min(np.linalg.norm(s.v[:3]), np.linalg.norm(s.v[3:6]), np.linalg.norm(s.a[:6])) > 0.3
    return s


def _assert_terms_match(lib, robot, s, what: str) -> None:
    ref = PinocchioTerms(robot)
    terms = [t for t in cross_library.TERMS if t not in lib.cannot]
    ours, theirs = terms_at(lib, s, terms), terms_at(ref, s, terms)
    for t in terms:
        assert_close(ours[t], theirs[t], what=f"{what}: {t}")


# ---------------------------------------------------------------------------- Drake
@needs_drake
def test_drake_conventions_on_a_moving_state(paper):
    """Quaternion w x y z then p; velocities (omega_W, v_W) in the world frame; vdot_D = T a + Tdot v:
    Drake's own pose, twist and acceleration of the trunk are the project's state, converted."""
    from quadruped_dyn.references.drake import DrakeReference, load_plant

    plant, _ = load_plant(paper.urdf.read_text())
    lib = DrakeReference(plant, paper)
    s = _moving_state(paper, 11)
    _assert_terms_match(lib, paper, s, "Drake")
    T, Tdot_v = lib._set(s.q, s.v)
    R, ctx, base = rotation(s.q), lib.context, lib.base
    assert_close(plant.GetPositions(ctx)[:4], np.r_[s.q[6], s.q[3:6]] / np.linalg.norm(s.q[3:7]), what="quaternion wxyz")
    assert_close(plant.EvalBodyPoseInWorld(ctx, base).rotation().matrix(), R, what="R")
    twist = plant.EvalBodySpatialVelocityInWorld(ctx, base)
    assert_close(twist.rotational(), R @ s.v[3:6], what="omega_W")
    assert_close(twist.translational(), R @ s.v[:3], what="v_W")
    A = plant.CalcSpatialAccelerationsFromVdot(ctx, T @ s.a + Tdot_v)[base.index()]
    assert_close(A.translational(), R @ classical_from_spatial(s.v[3:6], s.v[:3], s.a[:3]), what="classical a_W")
    assert_close(A.rotational(), R @ s.a[3:6], what="alpha_W")
    body_values = np.zeros(NV_FULL)  # the body-frame (omega_b, v_b) given as if Drake took them
    body_values[lib.v_start : lib.v_start + 6] = np.r_[s.v[3:6], s.v[:3]]
    body_values[lib.dof_idx] = s.v[6:]
    plant.SetVelocities(ctx, body_values)
    raw = plant.CalcBiasTerm(ctx) - plant.CalcGravityGeneralizedForces(ctx)
    assert np.abs(T.T @ raw - lib.nonlinear_effects(s.q, s.v)).max() > 1e-3, "Drake's velocities are not body-frame"


@needs_drake
def test_drake_names_the_inertia_it_regularises(tmp_path):
    """A 1e-6 dummy root link (b1, go1, anymal_b): Drake replaces it by a valid inertia; the change
    is named, measured, and the comparison's Pinocchio runs on a copy carrying Drake's inertia."""
    robot = load_robot(_variant(tmp_path, "dummy", _dummy_root))
    report = run_cross_library(robot, ("drake",), SAMPLES, seed=3)
    assert report.passed
    change = next(c for c in report.changes if c.kind == "regularised_inertia")
    assert change.links == ["base"] and change.in_comparison and "rotational inertia" in change.detail
    assert 1e-9 < change.size["M"] < 1e-5  # a 1e-6 kg m^2 inertia on a ~10 kg trunk
    for r in report.results:
        assert r.max_rel_err_same_model <= REL_TOL_TERMS, r
        assert (r.explained_by == ["regularised_inertia"]) and (r.max_rel_err > REL_TOL_TERMS) == (r.model_change > REL_TOL_TERMS)


# ---------------------------------------------------------------------------- adam
@needs_adam
@pytest.mark.parametrize("representation", ["body_fixed", "mixed", "inertial_fixed"])
def test_adam_representations_on_a_moving_state(paper, representation):
    """Each of adam's velocity representations, converted (T, Tdot v), gives Pinocchio's terms on
    a moving state; its raw mass matrix in MIXED / INERTIAL_FIXED is not Pinocchio's."""
    from quadruped_dyn.references.adam import AdamReference, load_kin_dyn, pose

    lib = AdamReference(load_kin_dyn(paper.urdf.read_text(), paper, representation), paper, representation)
    s = _moving_state(paper, 12)
    _assert_terms_match(lib, paper, s, f"adam {representation}")
    raw = np.array(lib.M(pose(s.q), s.q[7:]))
    differs = np.abs(raw - PinocchioTerms(paper).mass_matrix(s.q)).max() > 1e-3 * np.abs(raw).max()
    assert differs == (representation != "body_fixed")
    with pytest.raises(NotImplementedError, match="no inverse dynamics"):
        lib.inverse_dynamics(s.q, s.v, s.a)


@needs_adam
def test_adam_refusal_of_an_inertial_without_origin_is_reported():
    """go1: adam 0.5 fails on <inertial> without <origin>; reported as a refusal of the URDF as
    written, then compared on a copy with the URDF default origin (exact)."""
    from quadruped_dyn.references.adam import AdamRefusal, load_kin_dyn

    robot = load_robot("go1")
    with pytest.raises(AdamRefusal, match="AttributeError"):
        load_kin_dyn(robot.urdf.read_text(), robot)
    report = run_cross_library(robot, ("adam",), SAMPLES, seed=4)
    kinds = {c.kind: c for c in report.changes}
    assert not kinds["refused"].in_comparison and kinds["origin_added"].in_comparison
    assert report.passed and all(r.max_rel_err <= REL_TOL_TERMS for r in report.results)


# ---------------------------------------------------------------------------- both, on URDF variants
def _inertial_root(root: ET.Element) -> None:
    """A new root link 'base' with a real 1.5 kg inertia (off-centre, rotated), welded to the trunk."""
    new_root(root, '<inertial><origin xyz="0.03 -0.01 0.02" rpy="0.1 0.2 0.3"/><mass value="1.5"/><inertia ixx="0.004" '
             'ixy="0.0002" ixz="0" iyy="0.005" iyz="0.0001" izz="0.007"/></inertial>', xyz="0.01 0 -0.02")


@needs_drake
@needs_adam
@pytest.mark.parametrize("edit", [_inertial_root, _continuous_knees])
def test_root_link_inertia_and_continuous_joints(tmp_path, paper, edit):
    """No library drops an inertia on the root link (M's mass entry grows by 1.5 kg) and each reads
    continuous joints as an angle; every term agrees with Pinocchio on the URDF as written."""
    robot = load_robot(_variant(tmp_path, edit.__name__, edit))
    report = run_cross_library(robot, ("drake", "adam"), SAMPLES, seed=5)
    assert report.passed and {r.library for r in report.results} == {"drake", "adam"}
    assert all(r.max_rel_err <= REL_TOL_TERMS for r in report.results)
    added = 1.5 if edit is _inertial_root else 0.0
    q = random_state(robot.lower, robot.upper, np.random.default_rng(0)).q
    assert PinocchioTerms(robot).mass_matrix(q)[0, 0] == pytest.approx(paper.total_mass + added, rel=1e-12)


# ---------------------------------------------------------------------------- refusals and the command line
@needs_drake
@needs_adam
@pytest.mark.parametrize("refusing", ["drake", "adam"])
def test_a_refusing_library_is_not_compared_never_a_pass(monkeypatch, paper, refusing):
    from quadruped_dyn.references import adam as adam_ref
    from quadruped_dyn.references import drake as drake_ref

    def refuse(*args, **kwargs):
        raise (drake_ref.DrakeRefusal if refusing == "drake" else adam_ref.AdamRefusal)("no such model")

    monkeypatch.setattr(drake_ref if refusing == "drake" else adam_ref,
                        "load_plant" if refusing == "drake" else "load_kin_dyn", refuse)
    report = run_cross_library(paper, ("mujoco", refusing), SAMPLES)
    assert not report.passed and list(report.not_compared) == [refusing]
    assert report.conformance()[refusing]["M"]["status"] == "not compared"
    assert f"NOT COMPARED: {refusing}" in report.table()


@pytest.mark.parametrize(("missing", "asked", "named"), [("pydrake", "drake", "'drake'"), ("adam", "all", "'adam-robotics'")])
def test_missing_library_is_exit_2_naming_the_extra(monkeypatch, missing, asked, named):
    real = importlib.util.find_spec
    monkeypatch.setattr(cross_library.importlib.util, "find_spec", lambda n, *a: None if n == missing else real(n, *a))
    result = CliRunner().invoke(main, ["check", "solo12", "--against", asked])
    assert result.exit_code == 2, result.output
    assert named in result.stderr and "pip install 'quadruped_dyn[xlib]'" in result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


def test_all_means_every_library():
    assert cross_library.parse_libraries("all") == tuple(LIBRARIES) == ("pinocchio", "mujoco", "idyntree", "drake", "adam")
    with pytest.raises(InputError, match="names all beside libraries"):
        cross_library.parse_libraries("drake,all")


@needs_drake
@needs_adam
def test_conformance_table_explains_every_disagreement(tmp_path):
    """``check --against all --json``'s conformance table on a robot Drake regularises and MuJoCo
    refuses: per library and term the worst error and a status; nothing unexplained."""
    robot = load_robot(_variant(tmp_path, "dummy", _dummy_root))
    data = json.loads(json.dumps(run_cross_library(robot, tuple(LIBRARIES), SAMPLES, seed=6).as_dict()))
    table = data["conformance"]
    assert set(table) == set(LIBRARIES) and data["cross_library_unexplained"] == 0 and data["cross_library_passed"]
    assert table["drake"]["M"]["status"] == "explained" and table["drake"]["M"]["explained_by"] == ["regularised_inertia"]
    assert table["drake"]["M"]["worst_rel_err_same_model"] <= REL_TOL_TERMS < table["drake"]["M"]["worst_rel_err"]
    assert table["adam"]["inverse dynamics"] == {"worst_rel_err": None, "status": "not computed",
                                                 "why": table["adam"]["inverse dynamics"]["why"]}
    others = [row for lib, terms in table.items() for term, row in terms.items() if lib != "drake"
              and (lib, term) != ("adam", "inverse dynamics")]
    assert others and all(row["status"] == "agrees" and row["worst_rel_err"] <= REL_TOL_TERMS for row in others)


# ---------------------------------------------------------------------------- every example-robot-data quadruped (slow)
def _erd_quadrupeds() -> list[str]:
    """Every URDF example-robot-data ships that loads as a quadruped, relative to its robots/ folder."""
    out = []
    for path in sorted(example_robot_data_dir().rglob("*.urdf")):
        try:
            load_robot(str(path))
        except InputError:
            continue
        out.append(str(path.relative_to(example_robot_data_dir())))
    return out


@pytest.mark.slow
@needs_drake
@needs_adam
def test_every_example_robot_data_quadruped_by_path(erd):
    """docs/conventions.md §10 gives the per-robot worst errors of this sweep."""
    paths = _erd_quadrupeds()
    assert {"b1_description/urdf/b1.urdf", "laikago_description/urdf/laikago.urdf",
            "anymal_b_simple_description/robots/anymal.urdf"} <= set(paths)
    for relative in paths:
        report = run_cross_library(load_robot(str(erd / relative)), tuple(LIBRARIES), 5, seed=0)
        assert report.passed, (relative, report.table())
        for r in report.results:
            assert r.max_rel_err_same_model <= REL_TOL_TERMS, (relative, r)
