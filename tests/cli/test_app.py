"""cli.app: shared options."""

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main


@pytest.mark.parametrize("value", ["FL_foot,FR_foot,BL_foot", ",FR_foot,BL_foot,BR_foot", "a,b,c,d,", ""])
def test_foot_frames_of_the_wrong_shape_is_bad_input_naming_the_option(value):
    """The message named load_robot's parameter 'foot_frames', not the option the user gave."""
    run = CliRunner().invoke(main, ["info", "paper", "--foot-frames", value])
    assert run.exit_code == 2
    assert "--foot-frames" in run.output and "expected four frame names" in run.output
    assert "Traceback" not in run.output
