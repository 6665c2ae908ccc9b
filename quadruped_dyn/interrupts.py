"""Ctrl-C (SIGINT) and SIGTERM held back while a block must not be cut short (files renamed into place, a worker
process ended) or must end in its own way (IPOPT, which swallows the handler's exception), then raised by the
handlers they had (``KeyboardInterrupt``; ``cli.entry.Terminated`` for SIGTERM under the command line)."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def interrupts_deferred(stop: bool = False) -> Iterator[None]:
    """SIGINT and SIGTERM that arrive in the block take effect when it ends, by the handlers they had; with
    ``stop``, each also raises KeyboardInterrupt at once inside the block, to end a computation that catches it
    (CasADi's IPOPT returns 'NonIpopt_Exception_Thrown') — the signal's own handler still has the last word.
    Python runs signal handlers in the main thread only: elsewhere the block runs as it is. A signal without
    a Python handler (set outside Python) is left as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []

    def held(signum: int, _frame: object) -> None:
        caught.append(signum)
        if stop:
            raise KeyboardInterrupt

    previous = {signum: handler for signum in (signal.SIGINT, signal.SIGTERM)
                if (handler := signal.getsignal(signum)) is not None}  # None: set outside Python, not restorable
    for signum in previous:
        signal.signal(signum, held)
    try:
        yield
    finally:
        try:
            for signum, handler in previous.items():
                signal.signal(signum, handler)
        finally:  # a signal as soon as its handler is back raises out of the loop: the others' are put back still
            for signum, handler in previous.items():
                if signal.getsignal(signum) is not handler:
                    signal.signal(signum, handler)
        for caught_signum in dict.fromkeys(caught):  # each signal once, in the order they came
            signal.raise_signal(caught_signum)  # its own handler now: raises, or ends the process (SIG_DFL)
