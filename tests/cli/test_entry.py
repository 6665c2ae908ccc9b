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
    """Found by a review: Ctrl-C in the first ~2 s of any command, while the CLI imported
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


def test_sigterm_is_one_line_exit_143_and_removes_the_partial_outputs(tmp_path: Path) -> None:
    """SIGTERM (kill, a job's time limit) ended the process where it stood: a report left its hidden staging
    folder (``.report.*.partial``) and its warm process ran on. Now it unwinds as Ctrl-C does: the staging
    folder removed, the warm process ended, one line, exit 143. The signal is sent once the staging folder exists."""
    import time

    folder = tmp_path / "paper"
    proc = subprocess.Popen([sys.executable, "-m", "quadruped_dyn.cli", "report", "paper", "--fast", "--out",
                             str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not list(folder.glob(".report.*.partial")) and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, "the report ended before its staging folder was seen"
    assert list(folder.glob(".report.*.partial")), "no staging folder within 120 s"
    while not _children(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    warm = _children(proc.pid)
    assert warm, "no warm process started"
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=120)  # not the warm process's minutes of work
    stop = time.monotonic() + 10  # multiprocessing's resource tracker ends when it reads its parent's end
    while [pid for pid in warm if Path(f"/proc/{pid}").exists()] and time.monotonic() < stop:
        time.sleep(0.05)
    assert not [pid for pid in warm if Path(f"/proc/{pid}").exists()], "a child outlived the command"
    assert proc.returncode == 143, stderr[-3000:]
    assert "Traceback" not in stderr, stderr[-3000:]
    assert stderr.splitlines()[-1] == "error: terminated", stderr[-3000:]
    assert not list(folder.glob(".*.partial")), list(folder.iterdir())


def _children(pid: int) -> list[int]:
    """The process ids of ``pid``'s children (Linux)."""
    return [int(child) for task in Path(f"/proc/{pid}/task").iterdir()
            for child in (task / "children").read_text().split()]
