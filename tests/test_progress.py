"""The progress display without a terminal: a line at the start, one per LINE_PERIOD_S, one at the end."""

from __future__ import annotations

import io

import quadruped_dyn.progress as progress
from quadruped_dyn.progress import Bar, Steps


def test_bar_prints_start_and_end_lines_with_runs(monkeypatch):
    stream = io.StringIO()
    monkeypatch.setattr(progress, "LINE_PERIOD_S", 0.0)  # every advance prints
    with Bar("simulating", 4.0, "s simulated", runs=4, stream=stream) as bar:
        for _ in range(8):
            bar.advance(0.5)
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("simulating: 0/4 s simulated, 0/4 runs done (0 %")
    assert lines[-1].startswith("simulating: 4/4 s simulated, 4/4 runs done (100 %")
    assert any("2/4 runs done" in line for line in lines) and len(lines) == 10


def test_bar_is_quiet_between_periods_and_never_overshoots():
    stream = io.StringIO()
    with Bar("checking", 10, stream=stream) as bar:
        for _ in range(12):
            bar.update(1)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2 and lines[-1].startswith("checking: 10/10 (100 %")


def test_steps_number_the_steps_and_close_their_bars():
    stream = io.StringIO()
    steps = Steps(2, stream=stream)
    done = steps.step("first")
    steps.count(3, 6)
    done()
    steps.step("second")()
    text = stream.getvalue()
    assert "[1/2] first ..." in text and "[2/2] second:" in text and "3/6" in text


def test_disabled_prints_nothing():
    stream = io.StringIO()
    steps = Steps(1, enabled=False, stream=stream)
    steps.step("x")()
    with Bar("y", 1, enabled=False, stream=stream) as bar:
        bar.advance(1)
    assert stream.getvalue() == ""
