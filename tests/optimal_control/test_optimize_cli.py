"""``quadruped-dyn optimize``: bad input is exit 2 with one line, before any solve."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main


@pytest.mark.parametrize("args, message", [
    (["--mu", "0"], "mu"),
    (["--mu", "-1"], "mu"),
    (["--mu", "1e300"], "expected 0 < mu <= 1000"),
    (["--nodes", "1"], "expected 3 to 40 collocation nodes per phase"),
    (["--speed", "9"], "beyond"),
    (["--cycles", "-1"], "cycles"),
])
def test_bad_input_is_exit_2_one_line(tmp_path, args, message) -> None:
    result = CliRunner().invoke(main, ["optimize", "paper", "--out", str(tmp_path), *args])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and message in lines[0] and lines[0].startswith("error:")


def test_a_replay_shorter_than_one_step_is_refused_before_the_solve(tmp_path, monkeypatch) -> None:
    """replay_rigid checks its times (simulate.check_times): --cycles 1e-9 must not reach it after the solve."""
    from quadruped_dyn.optimal_control import transcription

    def tripwire(*a, **k):
        raise AssertionError("the solve started before the arguments were checked")

    monkeypatch.setattr(transcription, "transcribe", tripwire)
    result = CliRunner().invoke(main, ["optimize", "paper", "--out", str(tmp_path), "--cycles", "1e-9"])
    assert result.exit_code == 2, result.output
    assert result.output.splitlines() == ["error: --cycles 1e-09 of the 0.6 s cycle is shorter than one replay step "
                                          "(0.002 s); expected 0 (no replay) or at least 0.00333"]


def test_no_convergence_is_exit_1_with_ipopt_status(tmp_path, monkeypatch) -> None:
    """IPOPT stopped after 2 iterations: exit 1, one error line with its status, no result written."""
    from quadruped_dyn.optimal_control import solve

    monkeypatch.setitem(solve.IPOPT_OPTIONS, "max_iter", 2)
    result = CliRunner().invoke(main, ["optimize", "paper", "--nodes", "3", "--cycles", "0", "--out", str(tmp_path)])
    assert result.exit_code == 1, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Maximum_Iterations_Exceeded" in errors[0]
    assert not list(tmp_path.iterdir())


def test_effort_change_has_its_sign(tmp_path) -> None:
    """The effort line's percentage is the change from the plan, signed as such (it said "+4.9 % lower")."""
    import re

    result = CliRunner().invoke(main, ["optimize", "paper", "--nodes", "3", "--cycles", "0", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    m = re.search(r"effort (\S+) N\^2 m\^2 s vs the plan's (\S+) \(([+-]\d+\.\d) %\);", result.output)
    assert m, result.output
    optimised, plan, change = map(float, m.groups())
    assert (change < 0) == (optimised < plan) and change == pytest.approx(100 * (optimised / plan - 1), abs=1.0)  # 3 digits


def test_ipopt_writes_nothing_to_stdout() -> None:
    """IPOPT prints its banner on file descriptor 1 once per process, whatever print_level says,
    which broke `optimize --json` (stdout no longer JSON); "sb" suppresses it. A fresh process, as
    the banner is printed only by the first solve of a process; a one-variable NLP."""
    import subprocess
    import sys

    code = ("import casadi as ca\n"
            "from quadruped_dyn.optimal_control.solve import IPOPT_OPTIONS\n"
            "x = ca.SX.sym('x')\n"
            "ca.nlpsol('s', 'ipopt', {'x': x, 'f': (x - 1) ** 2}, {'ipopt': IPOPT_OPTIONS, 'print_time': False})(x0=0)\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stdout == "", run.stdout


@pytest.mark.parametrize("kind", ["effort", "velocity"])
def test_a_zero_actuator_limit_is_exit_2_one_line(tmp_path, kind) -> None:
    """A URDF whose leg joints have <limit effort="0"> (or velocity): control refused it, optimize
    ran IPOPT into 'Not_Enough_Degrees_Of_Freedom' (exit 1, a CasADi warning). Both read the limits
    through model.robot.actuator_limit."""
    from pathlib import Path

    urdf = Path(__file__).resolve().parents[2] / "quadruped_dyn" / "urdf" / "paper_quadruped.urdf"
    edited = tmp_path / f"zero_{kind}.urdf"
    edited.write_text(urdf.read_text().replace(f'{kind}="20"', f'{kind}="0"'))
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["optimize", str(edited), "--nodes", "3", "--cycles", "0", "--out", str(out)])
    assert result.exit_code == 2, result.output
    lines = [line for line in result.output.splitlines() if line.strip()]
    assert len(lines) == 1 and f"expected a positive finite <limit {kind}>" in lines[0], result.output


@pytest.mark.parametrize("cycles, message", [
    (0.0, "cycles 0.0 is not a positive finite number"),
    (float("nan"), "cycles nan is not a positive finite number"),
    (1e-9, "cycles × period 6e-10 s is shorter than one step"),
])
def test_replay_rigid_names_cycles_not_horizon(cycles, message) -> None:
    """Its time errors said "horizon", a parameter replay_rigid does not have. Checked before any use of
    the solution (only its gait's period is read), so a solution with just a gait stands in for a solve."""
    from types import SimpleNamespace

    from quadruped_dyn.errors import InputError
    from quadruped_dyn.experiment.gait import TROT
    from quadruped_dyn.optimal_control.replay import replay_rigid

    solution = SimpleNamespace(transcription=SimpleNamespace(gait=TROT))
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        replay_rigid(solution, cycles=cycles)  # type: ignore[arg-type]
