"""The console entry point (``quadruped-dyn``, ``python -m quadruped_dyn.cli``): Ctrl-C is one line
and exit 130 from the start (SIGTERM the same, exit 143, its partial outputs removed as on Ctrl-C),
also while the commands' modules are imported (click and the commands: ~0.2 s; the
commands import their work when they run). Light on purpose: it imports them only inside ``main``, once the
interrupt is handled."""

from __future__ import annotations

import signal
import sys
from types import FrameType
from typing import NoReturn

from quadruped_dyn.interrupts import interrupt, raise_until_seen

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports it; click's "Aborted!" was exit 1, a failed check
EXIT_TERMINATED = 143  # 128 + SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a job's time limit) raised like Ctrl-C, so that ``finally`` blocks run: a command's
    partial outputs (``files.safe_write``, the report's staging folder) are removed as on Ctrl-C (the
    default action ended the process where it stood and left them)."""


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise_until_seen(Terminated, frame)


def interrupted(e: BaseException | None = None) -> NoReturn:
    """``error: interrupted`` on stderr, exit 130: what Ctrl-C does, before and during a command;
    ``error: terminated``, exit 143, for SIGTERM (``e`` a ``Terminated``)."""
    terminated = isinstance(e, Terminated)
    try:
        sys.stderr.write("error: terminated\n" if terminated else "error: interrupted\n")
        sys.stderr.flush()
    except OSError:
        pass
    sys.exit(EXIT_TERMINATED if terminated else EXIT_INTERRUPTED)


def main() -> None:
    """Import the commands, then run the group (``cli.app``, which maps errors to exit codes)."""
    signal.signal(signal.SIGTERM, _terminate)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not where it is ignored (a background job)
        signal.signal(signal.SIGINT, interrupt)  # never dropped by CasADi's C++ (interrupts.raise_until_seen)
    try:
        from quadruped_dyn.cli.commands import main as group
    except KeyboardInterrupt as e:
        interrupted(e)
    group()
