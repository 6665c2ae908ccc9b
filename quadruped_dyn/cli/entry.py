"""The console entry point (``quadruped-dyn``, ``python -m quadruped_dyn.cli``): Ctrl-C is one line
and exit 130 from the start, also while the commands' modules are imported (click and the commands: ~0.2 s; the
commands import their work when they run). Light on purpose: it imports them only inside ``main``, once the
interrupt is handled."""

from __future__ import annotations

import sys
from typing import NoReturn

EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports it; click's "Aborted!" was exit 1, a failed check


def interrupted() -> NoReturn:
    """``error: interrupted`` on stderr, exit 130: what Ctrl-C does, before and during a command."""
    try:
        sys.stderr.write("error: interrupted\n")
        sys.stderr.flush()
    except OSError:
        pass
    sys.exit(EXIT_INTERRUPTED)


def main() -> None:
    """Import the commands, then run the group (``cli.app``, which maps errors to exit codes)."""
    try:
        from quadruped_dyn.cli.commands import main as group
    except KeyboardInterrupt:
        interrupted()
    group()
