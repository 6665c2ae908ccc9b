"""A robot's identity is its URDF's content: an edited file is a new model in this process
and in the next one, a copy named like a built-in is not that built-in, every derived name is
valid; limits, foot frames, size and parser noise are stated."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import warnings
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from quadruped_dyn.codegen.file_names import robot_stem
from quadruped_dyn.codegen.library import generation_key
from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import MAX_NAME_CHARS, is_safe_name, safe_name
from quadruped_dyn.model.paper_robot import STANDING_Q, URDF_PATH
from quadruped_dyn.model.registry import ROBOT_NAMES
from quadruped_dyn.model.robot import load_robot
from tests.conftest import assert_close

TRUNK_MASS = '<mass value="5.4"/>'  # the paper trunk's mass in its URDF


def _pinocchio_mass_matrix(urdf: Path, robot) -> np.ndarray:
    """M at the robot's standing posture, from a Pinocchio model parsed afresh from ``urdf`` (not
    from the Robot under test), in the Robot's Pinocchio ordering."""
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    q = pin.neutral(model)
    q[robot.idx_q] = robot.standing_q
    return pin.crba(model, model.createData(), q)


def _robot_mass_matrix(robot) -> np.ndarray:
    q = pin.neutral(robot.model)
    q[robot.idx_q] = robot.standing_q
    return pin.crba(robot.model, robot.model.createData(), q)


def _key(robot) -> str:
    return generation_key(robot, "double", ("-O3",), "gcc")


def test_an_edited_urdf_is_a_new_model_in_the_same_process(tmp_path):
    """Edited between two loads, even with the size and the modification time kept: the second
    load has the new dynamics (against Pinocchio on the new file) and a new cache key; the first
    Robot keeps the key of the model it holds."""
    urdf = tmp_path / "robot.urdf"
    text = URDF_PATH.read_text()
    urdf.write_text(text)
    old = load_robot(str(urdf))
    old_key = _key(old)
    stat = urdf.stat()
    for mass in ("7.4", "9.9"):  # same byte count, mtime restored: only the content says it changed
        urdf.write_text(text.replace(TRUNK_MASS, f'<mass value="{mass}"/>'))
        os.utime(urdf, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        new = load_robot(str(urdf))
        assert new is not old and new.trunk.mass == pytest.approx(float(mass))
        assert_close(_robot_mass_matrix(new), _pinocchio_mass_matrix(urdf, new), what=f"M_full, trunk {mass} kg")
        assert _key(new) != old_key
        assert load_robot(str(urdf)) is new, "unchanged content: the cached model"
    assert _key(old) == old_key, "the key follows the model a Robot holds, not the file as it is now"
    assert old.trunk.mass == pytest.approx(5.4)


def test_an_edited_urdf_is_a_new_model_in_the_next_process(tmp_path):
    """A fresh process on the edited file gets the new model and the key this process computes
    for it, never the key of the model loaded before the edit."""
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(URDF_PATH.read_text())
    before = _key(load_robot(str(urdf)))
    urdf.write_text(URDF_PATH.read_text().replace(TRUNK_MASS, '<mass value="10.0"/>'))
    after = load_robot(str(urdf))
    code = ("import sys; from quadruped_dyn.model.robot import load_robot; from quadruped_dyn.codegen.library import "
            "generation_key; r = load_robot(sys.argv[1]); print(r.trunk.mass, generation_key(r, 'double', ('-O3',), 'gcc'))")
    out = subprocess.run([sys.executable, "-W", "ignore", "-c", code, str(urdf)], capture_output=True, text=True, check=True)
    mass, key = out.stdout.split()
    assert float(mass) == pytest.approx(10.0) and key == _key(after) != before


def test_identity_is_content_not_the_file_name(tmp_path):
    """A copy of a built-in's bytes is that robot under any name; other bytes named like a built-in
    (paper.urdf, solo12.urdf) are not it: another name, their own standing posture."""
    edited = URDF_PATH.read_text().replace(TRUNK_MASS, '<mass value="7.4"/>')
    for name in ("paper", "solo12", "go2"):
        (tmp_path / f"{name}.urdf").write_text(edited)
        r = load_robot(str(tmp_path / f"{name}.urdf"))
        assert r.builtin is None and r.name not in ROBOT_NAMES and r.name.startswith(f"{name}_"), r.name
        assert not np.allclose(r.standing_q, np.tile(STANDING_Q, 4))
        assert np.all(r.standing_q >= r.lower) and np.all(r.standing_q <= r.upper)
    for name in ("solo12.urdf", "copy.urdf", "paper (copy).urdf"):
        (tmp_path / name).write_text(URDF_PATH.read_text())
        r = load_robot(str(tmp_path / name))
        assert r.name == r.builtin == "paper" and np.allclose(r.standing_q, np.tile(STANDING_Q, 4))


HOSTILE_STEMS = ["paper (copy)", "..", ".", "Robôt-ünï", "a" * 250, "__x__", "9lives", "x_", "a\x1b[31mb", "日本語",
                 "con", "-rf"]


@pytest.mark.parametrize("stem_text", HOSTILE_STEMS)
def test_every_derived_name_is_valid_and_bounded(stem_text):
    name = safe_name(stem_text)
    assert is_safe_name(name) and len(name) <= MAX_NAME_CHARS and "__" not in name and not name.endswith("_")
    assert ca.Function.check_name(f"qd_{name}_fd_r_FL_FR_BL_BR"), name
    assert safe_name(stem_text) == name, "deterministic"
    assert safe_name(stem_text + "x") != name, "different inputs, different names"


def test_a_hostile_file_name_loads_with_a_safe_name(tmp_path):
    edited = URDF_PATH.read_text().replace(TRUNK_MASS, '<mass value="7.4"/>')
    names = set()
    for stem_text in ["paper (copy)", "..", "Robôt", "a" * 200, "x_"]:
        path = tmp_path / f"{stem_text}.urdf"
        path.write_text(edited)
        r = load_robot(str(path))
        assert is_safe_name(r.name) and ca.Function.check_name(f"{robot_stem(r.name)}_M_full"), r.name
        names.add(r.name)
    assert len(names) == 5


def _edited(tmp_path: Path, name: str, old: str, new: str, count: int = 1) -> Path:
    text = URDF_PATH.read_text()
    assert text.count(old) >= count
    path = tmp_path / name
    path.write_text(text.replace(old, new, count))
    return path


def test_missing_limit_attributes_sample_a_stated_range(tmp_path):
    """<limit effort velocity/> without lower/upper reads as [0, 0]: the joint gets [-pi, pi] (the
    continuous-joint rule) and a warning naming it, for one joint and for all twelve."""
    one = _edited(tmp_path, "one.urdf", 'lower="-2.6" upper="-0.3" ', "")
    with pytest.warns(UrdfWarning, match=r"joint 'FL_KFE' has the limits \[0, 0\].*\[-pi, pi\]"):
        r = load_robot(str(one))
    assert r.lower[2] == -np.pi and r.upper[2] == np.pi and r.lower[1] != -np.pi
    text = re.sub(r'lower="[^"]*" upper="[^"]*" ', "", URDF_PATH.read_text())
    (tmp_path / "all.urdf").write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = load_robot(str(tmp_path / "all.urdf"))
    assert sum("has the limits [0, 0]" in str(w.message) for w in caught) == 12
    assert np.all(r.lower == -np.pi) and np.all(r.upper == np.pi)


def _with_extra_frames(tmp_path: Path, frames: dict[str, float]) -> Path:
    """The paper URDF with extra leaf links on every shank at the given distances (m) along it."""
    text = URDF_PATH.read_text()
    for leg in ("FL", "FR", "BL", "BR"):
        extra = "".join(f'  <link name="{leg}_{n}"/>\n  <joint name="{leg}_{n}_fixed" type="fixed">\n'
                        f'    <origin xyz="{d} 0 0" rpy="0 0 0"/>\n    <parent link="{leg}_shank"/>\n'
                        f'    <child link="{leg}_{n}"/>\n  </joint>\n' for n, d in frames.items())
        text = text.replace("</robot>", extra + "</robot>")
    path = tmp_path / ("extra_" + "_".join(frames) + ".urdf")
    path.write_text(text)
    return path


def test_the_foot_frame_is_stated_and_can_be_named(tmp_path):
    """A force sensor nearer the knee than the toe is not the foot; with several leaf frames the
    choice and the alternatives are a warning; the user can name the feet; a wrong name is an
    InputError."""
    sensor = _with_extra_frames(tmp_path, {"foot_sensor": 0.05})
    with pytest.warns(UrdfWarning, match=r"leg FL: foot frame 'FL_foot' at 0.200 m .*'FL_foot_sensor' \(0.050 m\)"):
        r = load_robot(str(sensor))
    assert [leg.foot_frame for leg in r.legs] == ["FL_foot", "FR_foot", "BL_foot", "BR_foot"]
    assert r.legs[0].foot.p[0] == pytest.approx(0.2)
    toe = _with_extra_frames(tmp_path, {"toe_tip": 0.21, "shin_camera": 0.25})
    with pytest.warns(UrdfWarning, match="farthest leaf frame named like a foot"):
        r = load_robot(str(toe))
    assert r.legs[0].foot_frame == "FL_toe_tip" and r.legs[0].foot.p[0] == pytest.approx(0.21)
    named = load_robot(str(sensor), foot_frames=["FL_foot_sensor", "FR_foot_sensor", "BL_foot_sensor", "BR_foot_sensor"])
    assert named.legs[3].foot_frame == "BR_foot_sensor" and named.legs[3].foot.p[0] == pytest.approx(0.05)
    assert _key(named) != _key(load_robot(str(sensor)))
    by_label = load_robot(str(sensor), foot_frames={"FL": "FL_foot", "FR": "FR_foot", "BL": "BL_foot", "BR": "BR_foot_sensor"})
    assert by_label.legs[3].foot_frame == "BR_foot_sensor" and by_label.legs[0].foot_frame == "FL_foot"
    for bad, message in [(["FL_foot"], "four frame names"), ("a,b,c,d", "foot frame .a. of leg FL is not a frame"),
                         (42, "expected four"),
                         (["FR_foot", "FL_foot", "BL_foot", "BR_foot"], "does not hang from the knee"),
                         ({"FL": "FL_foot"}, "expected \\['FL', 'FR', 'BL', 'BR'\\]")]:
        with pytest.raises(InputError, match=message):
            load_robot(str(sensor), foot_frames=bad)


def test_a_huge_urdf_is_refused_before_parsing(tmp_path):
    """Beyond MAX_URDF_BYTES or MAX_URDF_LINKS: an InputError at once, not minutes of parsing."""
    from quadruped_dyn.model.urdf_rules import MAX_URDF_BYTES, MAX_URDF_LINKS

    links = "".join(f'<link name="l{i}"/>' for i in range(MAX_URDF_LINKS + 1))
    (tmp_path / "links.urdf").write_text(URDF_PATH.read_text().replace("</robot>", links + "</robot>"))
    with pytest.raises(InputError, match=r"has \d+ <link> elements; expected at most"):
        load_robot(str(tmp_path / "links.urdf"), cached=False)
    with open(tmp_path / "big.urdf", "wb") as f:
        f.write(URDF_PATH.read_bytes())
        f.seek(MAX_URDF_BYTES + 10)
        f.write(b"\n")
    with pytest.raises(InputError, match="MB; expected a URDF of at most"):
        load_robot(str(tmp_path / "big.urdf"))


BROKEN = {
    "duplicate link": ('<link name="FL_foot"/>', '<link name="FL_foot"/>\n  <link name="FL_foot"/>'),
    "duplicate joint": ('<joint name="FL_foot_fixed" type="fixed">', '<joint name="FL_HAA" type="fixed">'),
    "missing parent": ('<parent link="FL_shank"/>', '<parent link="no_such_link"/>'),
    "revolute without limit": ('<limit lower="-2.6" upper="-0.3" effort="20" velocity="20"/>', ""),
}


@pytest.mark.parametrize("what", BROKEN)
def test_parser_errors_are_one_line(tmp_path, what):
    """urdfdom prints its own Error: lines on the C++ stderr before Pinocchio raises: the CLI says
    one line (exit 2), the API raises one InputError."""
    old, new = BROKEN[what]
    path = _edited(tmp_path, "broken.urdf", old, new)
    proc = subprocess.run([sys.executable, "-m", "quadruped_dyn.cli", "info", str(path)], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in proc.stderr, proc.stderr
    assert ".;" not in lines[0], lines[0]  # the parser's sentence ends where ours goes on


def test_foot_frames_on_the_command_line(tmp_path):
    """`info --foot-frames` names the feet; a wrong list is one line, exit 2; without it the
    warning says which frame was chosen."""
    import json

    from click.testing import CliRunner

    from quadruped_dyn.cli import main

    sensor = _with_extra_frames(tmp_path, {"foot_sensor": 0.05})
    chosen = CliRunner().invoke(main, ["info", str(sensor), "--json"])
    assert chosen.exit_code == 0 and "warning: leg FL: foot frame 'FL_foot'" in chosen.stderr
    # the commands the warning sends the user to take the option (codegen, validate, ... do not)
    suggested = re.search(r"--foot-frames of ([a-z, ]+?)\)", chosen.stderr)
    assert suggested, chosen.stderr
    for command in re.split(r", | and ", suggested.group(1)):
        assert "foot_frames" in [p.name for p in main.commands[command].params], command
    named = CliRunner().invoke(main, ["info", str(sensor), "--json", "--foot-frames",
                                      "FL_foot_sensor,FR_foot_sensor,BL_foot_sensor,BR_foot_sensor"])
    legs = json.loads(named.stdout)["legs"]
    assert named.exit_code == 0 and [leg["foot_frame"] for leg in legs] == [f"{x}_foot_sensor" for x in ("FL", "FR", "BL", "BR")]
    assert legs[0]["shank_length_m"] == pytest.approx(0.05, abs=1e-9)
    for bad in ("FL_foot", "a,b,c,d"):
        result = CliRunner().invoke(main, ["info", str(sensor), "--foot-frames", bad])
        assert result.exit_code == 2 and result.stderr.count("\n") == 1 and "foot" in result.stderr, result.output
    # the shank's own link frame, at the knee (found by a fresh-clone review: it was a leg of shank length 0)
    at_knee = CliRunner().invoke(main, ["info", "paper", "--foot-frames", "FL_shank,FR_foot,BL_foot,BR_foot"])
    assert at_knee.exit_code == 2 and at_knee.stderr.count("\n") == 1, at_knee.output
    assert "foot frame 'FL_shank' of leg FL is at the knee joint" in at_knee.stderr, at_knee.stderr


def test_the_header_names_the_feet(tmp_path):
    """The generated header states the foot frames its C was generated for (every GRF solve and reduced function
    depends on them), as text that cannot end its comment (a frame name is free text); codegen takes
    --foot-frames and refuses a wrong list before generating."""
    from click.testing import CliRunner

    from quadruped_dyn.cli import main
    from quadruped_dyn.codegen.emit import header_doc

    sensor = _with_extra_frames(tmp_path, {"foot_sensor": 0.05})
    feet = [f"{leg}_foot_sensor" for leg in ("FL", "FR", "BL", "BR")]
    doc = header_doc(load_robot(str(sensor), foot_frames=feet), [], {})
    assert "FL 'FL_foot_sensor', FR 'FR_foot_sensor', BL 'BL_foot_sensor', BR 'BR_foot_sensor'." in doc
    odd = tmp_path / "odd.urdf"
    odd.write_text(sensor.read_text().replace("_foot_sensor", "_foot*/sensor"))
    doc = header_doc(load_robot(str(odd), foot_frames=[f.replace("_foot_sensor", "_foot*/sensor") for f in feet]), [], {})
    assert "FL 'FL_foot* /sensor'" in doc and doc.count("*/") == 1 and doc.endswith("*/\n")  # the comment's own end
    result = CliRunner().invoke(main, ["codegen", str(sensor), "--out", str(tmp_path / "gen"), "--foot-frames", "a,b,c,d"])
    assert result.exit_code == 2 and "foot frame 'a' of leg FL is not a frame" in result.stderr, result.output
    assert not (tmp_path / "gen").exists() or not any((tmp_path / "gen").iterdir())
