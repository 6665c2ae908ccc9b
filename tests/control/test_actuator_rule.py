"""control and optimize refuse the same joints (model.robot.actuator_limits): a zero, negative or missing effort or
velocity limit, before any work."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.control.closed_loop import prepare
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.optimal_control.transcription import Options
from tests.model.test_physical_range import paper_variant

EXPECTED = r"{kind} limits \[.*\] {unit}; expected a positive finite <limit {kind}> on every leg joint"


def _limit(kind: str, value: str):
    def edit(root: ET.Element) -> None:
        next(j for j in root.iter("joint") if j.get("name") == "BR_KFE").find("limit").set(kind, value)  # type: ignore[union-attr]
    return edit


@pytest.mark.parametrize(("kind", "value", "unit"), [("velocity", "0", "rad/s"),
                                                     ("effort", "0", "N m")])
def test_control_and_optimize_refuse_the_same_joint(kind, value, unit, tmp_path):
    path = paper_variant(tmp_path, _limit(kind, value), f"limit_{kind}_{value.strip('-')}.urdf")
    expected = EXPECTED.format(kind=kind, unit=re.escape(unit))
    messages = []
    for command in ("control", "optimize"):
        result = CliRunner().invoke(main, [command, str(path), "--out", str(tmp_path / command)])
        assert result.exit_code == 2, result.output
        assert result.stderr.count("\n") == 1 and re.search(expected, result.stderr), result.stderr
        assert not (tmp_path / command).exists() or not any((tmp_path / command).iterdir())
        messages.append(result.stderr)
    assert messages[0] == messages[1], "one rule, one message"
    robot = load_robot(str(path), cached=False)
    with pytest.raises(InputError, match=expected):
        prepare(robot, "walk")
    from quadruped_dyn.experiment.gait import GAITS

    with pytest.raises(InputError, match=expected):
        Options().check(robot, GAITS["trot"])
