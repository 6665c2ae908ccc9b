"""Ctrl-C (SIGINT) and SIGTERM held back while a block must not be cut short (files renamed into place, a worker
process ended) or must end in its own way (IPOPT, which swallows the handler's exception), then raised by the
handlers they had (``KeyboardInterrupt``; ``cli.entry.Terminated`` for SIGTERM under the command line)."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any, NoReturn


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


def raise_until_seen(exception: type[BaseException], frame: FrameType | None) -> NoReturn:
    """Raise ``exception`` from a signal handler, and again at the next line of Python the main thread runs if
    the first was dropped. CasADi's C++ checks for signals while it builds a Function (``PyErr_CheckSignals``, which
    runs the handler), then drops the exception and carries on: Ctrl-C during a symbolic step was lost and the
    step ran to its end (tens of seconds). Every frame on the stack is traced until one of them runs a line: in an
    ``except`` or ``finally`` block of the exception it was seen, else it is raised there; then the previous trace
    function (a debugger's, coverage's) is back."""
    if frame is None:  # no Python frame to watch
        raise exception
    previous = sys.gettrace()
    frames: list[FrameType] = []
    above: FrameType | None = frame
    while above is not None:
        frames.append(above)
        above = above.f_back
    saved = [(f, f.f_trace, f.f_trace_lines) for f in frames]

    def done() -> None:
        sys.settrace(previous)
        for f, trace, lines in saved:
            f.f_trace, f.f_trace_lines = trace, lines

    def trace(f: FrameType, event: str, arg: Any) -> Any:
        if event == "call":  # a frame called later (from C, too: SWIG's callbacks): not traced, raising there is dropped
            return None
        if event == "line":  # a frame of the stack runs a line: in an except or finally block of the exception, it
            done()  # was seen; else it was dropped below (an 'exception' event proves nothing: C may drop it after)
            if not isinstance(sys.exc_info()[1], exception):
                raise exception
        return trace

    for f in frames:
        f.f_trace, f.f_trace_lines = trace, True
    sys.settrace(trace)
    raise exception


def interrupt(signum: int, frame: FrameType | None) -> NoReturn:
    """SIGINT's handler under the command line: KeyboardInterrupt, never lost (``raise_until_seen``)."""
    raise_until_seen(KeyboardInterrupt, frame)
