"""``quadruped-dyn optimize``: bad input is exit 2 with one line, before any solve."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main


@pytest.mark.parametrize("args, message", [
    (["--mu", "0"], "mu"),
    (["--mu", "-1"], "mu"),
    (["--nodes", "1"], "too few"),
    (["--speed", "9"], "beyond"),
    (["--cycles", "-1"], "cycles"),
])
def test_bad_input_is_exit_2_one_line(tmp_path, args, message) -> None:
    result = CliRunner().invoke(main, ["optimize", "paper", "--out", str(tmp_path), *args])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0] and lines[0].startswith("error:")
