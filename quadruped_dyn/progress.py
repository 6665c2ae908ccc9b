"""Progress on stderr, for every command step that takes more than a few seconds.

One display, built on ``rich``: on a terminal a live bar (done / total in the step's unit,
elapsed, remaining); when stderr is not a terminal (CI logs, pipes) one plain line at the start,
then one every ``LINE_PERIOD_S`` seconds and one at the end, so a log shows that a long step is
moving. ``Bar(label, total, unit)`` counts in any unit (samples checked, seconds simulated);
``runs`` (optional) turns a simulated-time total into "run k of N" as well, every run being
``total / runs`` long. ``Steps(n)`` numbers the steps of a job ("[k/N] what ... 12.3 s"), and
``Steps.bar`` gives a step its own bar; a step's last line has its wall time and this process's
CPU time (on a shared machine the wall time is mostly waiting: the CPU time is the work).
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import TextIO

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TaskID, TextColumn, TimeElapsedColumn, TimeRemainingColumn

#: Without a terminal, a progress line every this many seconds (and at the start and the end).
LINE_PERIOD_S = 10.0


def _stream() -> TextIO:
    return sys.stderr


class Bar:
    """A counted step: ``advance(n)`` adds n of ``total`` (in ``unit``); a context manager."""

    def __init__(self, label: str, total: float, unit: str = "", runs: int | None = None, enabled: bool = True,
                 stream: TextIO | None = None) -> None:
        self.label, self.total, self.unit, self.runs, self.enabled = label, float(total), unit, runs, enabled
        self.stream = stream or _stream()
        self.done = 0.0
        self.status = ""  # a note after the count (``set_status``), e.g. what is running and failing
        self.live = enabled and self.stream.isatty()
        self._progress: Progress | None = None
        self._task: TaskID | None = None
        self._start = self._last_line = time.monotonic()

    def _describe(self) -> str:
        text = f"{self.label}: {self.done:.4g}/{self.total:.4g}{(' ' + self.unit) if self.unit else ''}"
        if self.runs:
            per_run = self.total / self.runs
            done_runs = min(self.runs, int(self.done / per_run + 1e-9)) if per_run > 0 else 0
            text += f", {done_runs}/{self.runs} runs done"
        pct = 100.0 * self.done / self.total if self.total > 0 else 100.0
        return f"{text} ({pct:.0f} %, {time.monotonic() - self._start:.0f} s){', ' + self.status if self.status else ''}"

    def __enter__(self) -> Bar:
        if self.live:
            columns = [TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn() if not self.unit
                       else TextColumn("{task.completed:.3g}/{task.total:.3g} " + self.unit),
                       TextColumn("{task.fields[runs]}"), TimeElapsedColumn(), TimeRemainingColumn(),
                       TextColumn("{task.fields[status]}")]
            self._progress = Progress(*columns, console=Console(file=self.stream), transient=False)
            self._progress.start()
            self._task = self._progress.add_task(self.label, total=self.total, runs="", status=self.status)
        elif self.enabled:
            print(self._describe(), file=self.stream, flush=True)
        return self

    def advance(self, n: float = 1.0) -> None:
        self.done = min(self.total, self.done + n)
        if self._progress is not None and self._task is not None:
            runs = ""
            if self.runs:
                per_run = self.total / self.runs
                runs = f"run {min(self.runs, int(self.done / per_run + 1e-9) + 1)}/{self.runs}" if per_run > 0 else ""
            self._progress.update(self._task, completed=self.done, runs=runs, status=self.status)
        elif self.enabled and time.monotonic() - self._last_line >= LINE_PERIOD_S:
            self._last_line = time.monotonic()
            print(self._describe(), file=self.stream, flush=True)

    update = advance  # the name click's bars use

    def set_status(self, status: str) -> None:
        """The note shown after the count from the next update on."""
        self.status = status

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if self._progress is not None:
            self._progress.stop()
        elif self.enabled:
            print(self._describe() + ("" if exc_type is None else " -- stopped"), file=self.stream, flush=True)


class Steps:
    """Numbered steps of one job: ``done = steps.step(what)`` prints "[k/N] what ...", ``done()``
    appends the seconds it took (wall, and this process's CPU); ``steps.bar(total, unit)`` counts
    inside the current step."""

    def __init__(self, total: int, enabled: bool = True, stream: TextIO | None = None) -> None:
        self.total, self.k, self.enabled = total, 0, enabled
        self.stream = stream or _stream()
        self.line = ""
        self._bar: Bar | None = None

    def step(self, what: str) -> Callable[[], None]:
        self.k += 1
        start, cpu = time.monotonic(), time.process_time()
        self.line = f"[{self.k}/{self.total}] {what}"
        if self.enabled:
            print(f"{self.line} ...", file=self.stream, flush=True)

        def done() -> None:
            if self._bar is not None:
                self._bar.__exit__(None, None, None)
                self._bar = None
            if self.enabled:
                print(f"{self.line}: {time.monotonic() - start:.1f} s ({time.process_time() - cpu:.1f} s CPU)",
                      file=self.stream, flush=True)

        return done

    def bar(self, total: float, unit: str = "", runs: int | None = None) -> Bar:
        """A bar for the current step (closed by the step's ``done``)."""
        if self._bar is None:
            self._bar = Bar(f"  {self.line}", total, unit, runs, self.enabled, self.stream).__enter__()
        return self._bar

    def count(self, n: float, total: float) -> None:
        """The current step has done n of total (a running count, not an increment)."""
        bar = self.bar(total)
        bar.advance(n - bar.done)
