"""Bad input: exit code 2 and a one-line message saying what was found and what was expected."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.model import paper_robot


def _info(path: str) -> tuple[int, str]:
    result = CliRunner().invoke(main, ["info", path])
    assert "Traceback" not in result.output
    return result.exit_code, result.stderr


def _paper_variant(tmp_path, old: str, new: str) -> str:
    text = paper_robot.urdf_text()
    assert old in text
    path = tmp_path / "variant.urdf"
    path.write_text(text.replace(old, new, 1))
    return str(path)


SHANK_MASS = f'<mass value="{paper_robot.PARAMS.shank_mass:g}"/>'


@pytest.mark.parametrize(
    ("case", "expected"),
    [
        ("missing", r"no such file.*expected a URDF path or one of"),
        ("malformed", r"not well-formed XML.*expected a URDF"),
        ("not_urdf", r"root element <html>.*expected a URDF <robot>"),
        ("two_dof_legs", r"4 joint chains from the trunk with \[2, 2, 2, 2\] joints; expected a quadruped"),
        ("humanoid", r"joint chains from the trunk.*expected a quadruped"),
        ("fixed_base_arm", r"joint chains from the trunk.*expected a quadruped"),
        ("prismatic", r"leg joint 'FL_HAA' is JointModelP.*expected revolute"),
        ("zero_mass", r"moved by joint 'FL_KFE' has mass 0 kg.*expected a positive mass"),
        ("non_pd_inertia", r"link 'FL_shank' <inertial> <inertia> is not positive semi-definite.*expected a physical rigid body"),
    ],
)
def test_bad_urdf(case, expected, tmp_path, erd):
    paths = {
        "missing": str(tmp_path / "nope.urdf"),
        "two_dof_legs": str(erd / "quadruped_description/urdf/quadruped.urdf"),
        "humanoid": str(erd / "simple_humanoid_description/urdf/simple_humanoid.urdf"),
        "fixed_base_arm": str(erd / "ur_description/urdf/ur5_robot.urdf"),
    }
    if case == "malformed":
        (tmp_path / "bad.urdf").write_text("<robot><link name='a'></robot>")
        paths[case] = str(tmp_path / "bad.urdf")
    elif case == "not_urdf":
        (tmp_path / "page.urdf").write_text("<html></html>")
        paths[case] = str(tmp_path / "page.urdf")
    elif case == "prismatic":
        paths[case] = _paper_variant(tmp_path, '<joint name="FL_HAA" type="revolute">', '<joint name="FL_HAA" type="prismatic">')
    elif case == "zero_mass":
        paths[case] = _paper_variant(tmp_path, SHANK_MASS, '<mass value="0"/>')
    elif case == "non_pd_inertia":
        text = paper_robot.urdf_text()
        shank = text.index('<link name="FL_shank">')
        ixx = re.search(r'ixx="[^"]+"', text[shank:]).group(0)
        paths[case] = _paper_variant(tmp_path, text[shank : text.index(ixx, shank) + len(ixx)],
                                     text[shank : text.index(ixx, shank)] + 'ixx="-1"')
    code, err = _info(paths[case])
    assert code == 2, err
    assert re.search(expected, err), err
    assert err.count("\n") == 1, "expected a one-line message"


def test_unknown_command_line_argument_is_exit_2():
    assert CliRunner().invoke(main, ["info"]).exit_code == 2


def test_cli_subprocess_has_no_traceback(tmp_path):
    """The installed entry point, as a user runs it."""
    proc = subprocess.run(
        [sys.executable, "-m", "quadruped_dyn.cli", "info", str(tmp_path / "missing.urdf")],
        capture_output=True, text=True, check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: no such file") and "Traceback" not in proc.stderr
