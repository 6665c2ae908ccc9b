"""The console entry point: Ctrl-C is one line and exit 130 from the start, also while the
commands' modules (scipy, CasADi, Pinocchio) are still being imported."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def _script_code() -> str:
    """What the installed ``quadruped-dyn`` script runs: pip's wrapper of the entry point in pyproject.toml."""
    module, function = re.search(r'^quadruped-dyn = "([\w.]+):(\w+)"', PYPROJECT.read_text(), re.M).groups()
    return f"import sys; from {module} import {function}; sys.exit({function}())"


@pytest.mark.parametrize("launch", [["-m", "quadruped_dyn.cli"], ["-c", _script_code()]], ids=["module", "script"])
def test_ctrl_c_while_importing_is_one_line_and_exit_130(launch: list[str]) -> None:
    """Found by a review (2026-12-06): Ctrl-C in the first ~2 s of any command, while the CLI imported
    its heavy modules, printed a KeyboardInterrupt traceback. The signal is sent while numpy imports (the
    first of them; ``-X importtime`` lines on stderr say when), long before Pinocchio's import ends."""
    proc = subprocess.Popen([sys.executable, "-X", "importtime", *launch, "robots"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    lines = []
    for line in proc.stderr:  # type: ignore[union-attr]
        lines.append(line)
        if re.search(r"\|\s+numpy[.\w]*$", line):
            break
    proc.send_signal(signal.SIGINT)
    stdout, rest = proc.communicate(timeout=120)
    stderr = "".join(lines) + rest
    assert not re.search(r"\|\s+pinocchio$", stderr, re.M), "the signal came too late to test the imports"
    assert proc.returncode == 130, stderr[-3000:]
    assert "Traceback" not in stderr, stderr[-3000:]
    said = [line for line in stderr.splitlines() if not line.startswith("import time:")]
    assert said == ["error: interrupted"], said
    assert stdout == ""
