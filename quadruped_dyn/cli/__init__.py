"""The ``quadruped-dyn`` command line: ``main`` and its commands, one module per command.
Exit codes: 0 success, 1 a check or a computation failed, 2 bad input (one line on stderr, no traceback),
130 interrupted, 143 terminated (SIGTERM).
Importing the package is light (``main`` is imported on first use): ``entry`` handles Ctrl-C before the commands import."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "app": ("EXIT_BAD_INPUT", "EXIT_CHECK_FAILED"),
    "commands": ("main",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
