"""The ``quadruped-dyn`` group: exit codes (0 success, 1 a check or a computation failed, 2 bad input; 130
interrupted, ``entry``), one-line errors and warnings, progress on stderr. Each command lives in its own module
of this package."""

from __future__ import annotations

import os
import shutil
import sys
import warnings
from typing import Any

import click

from quadruped_dyn import __version__
from quadruped_dyn.cli.entry import interrupted
from quadruped_dyn.errors import BuildError, InputError, NumericalError, UrdfWarning
from quadruped_dyn.files.names import printable

EXIT_CHECK_FAILED = 1
EXIT_BAD_INPUT = 2


def _warn_one_line(message: Warning | str, category: type[Warning], *args: object, **kwargs: object) -> None:
    click.echo(f"warning: {printable(message)}", err=True)


def _error(message: object, code: int) -> None:
    """One line on stderr (control characters escaped: names from input may carry terminal
    escape sequences), then exit with ``code``."""
    try:
        click.echo(f"error: {printable(message)}", err=True)
    except OSError:
        pass
    sys.exit(code)


def _flush_stdout() -> None:
    """Flush stdout now, so that a write failure (``> /dev/full``, a closed pipe) is one line
    here and not a traceback at interpreter exit."""
    try:
        sys.stdout.flush()
    except OSError as e:
        devnull = os.open(os.devnull, os.O_WRONLY)  # the interpreter's final flush must not fail again
        os.dup2(devnull, sys.stdout.fileno())
        _error(f"cannot write to standard output ({e.strerror}); expected a writable output", EXIT_BAD_INPUT)


class _Group(click.Group):
    """Maps InputError, click's usage errors and failed reads or writes to exit code 2 and
    BuildError and NumericalError to 1, with a one-line message and no traceback; prints
    UrdfWarnings as one line each."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("always", UrdfWarning)
                warnings.showwarning = _warn_one_line
                result = super().invoke(ctx)
            _flush_stdout()
            return result
        except InputError as e:
            _error(e, EXIT_BAD_INPUT)
        except click.UsageError as e:
            _error(e.format_message(), EXIT_BAD_INPUT)
        except (BuildError, NumericalError) as e:
            _error(e, EXIT_CHECK_FAILED)
        except OSError as e:  # a write to stdout or a file that failed (full disk, closed pipe)
            where = f" '{e.filename}'" if e.filename else " to standard output"
            _flush_stdout_quietly()
            _error(f"cannot write{where} ({e.strerror or e}); expected a writable output", EXIT_BAD_INPUT)
        except KeyboardInterrupt as e:  # Ctrl-C, or SIGTERM (cli.entry.Terminated)
            _flush_stdout_quietly()
            interrupted(e)
        except SystemExit:
            _flush_stdout()
            raise


def _flush_stdout_quietly() -> None:
    try:
        sys.stdout.flush()
    except OSError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def echo(text: object) -> None:
    """A command's output on stdout, control characters escaped within each of its lines (names
    from input may carry terminal escape sequences; click strips only CSI ones, and only off a
    terminal). Every command prints through here; a path in a multi-line text is ``printable``
    already, or its newlines would break the lines."""
    click.echo("\n".join(printable(line) for line in str(text).split("\n")))


def foot_frames_option(command: Any) -> Any:
    """``--foot-frames FL,FR,BL,BR``: the contact frames ``load_robot`` takes instead of those it chooses (its
    warning names the commands that have this option)."""
    return click.option("--foot-frames", default=None, metavar="FL,FR,BL,BR", callback=_four_names,
                        help="The foot frame of each leg (comma-separated, leg order FL, FR, BL, BR) instead of the "
                             "chosen ones.")(command)


def _four_names(_ctx: Any, _param: Any, value: str | None) -> str | None:
    """``--foot-frames`` as given if ``load_robot`` takes it; else bad input naming the option (before any work)."""
    if value is not None:
        from quadruped_dyn.model.foot_frames import foot_frame_names

        foot_frame_names(value, "--foot-frames")
    return value


def require_tools(*tools: str) -> None:
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        raise InputError(f"{', '.join(missing)} not found; expected on PATH (Debian: apt-get install gcc g++)")


def progress(label: str, length: int) -> Any:
    """A counted step on stderr (``quadruped_dyn.progress.Bar``: a live bar on a terminal,
    periodic lines otherwise)."""
    from quadruped_dyn.progress import Bar

    return Bar(label, length)


@click.group(cls=_Group)
@click.version_option(__version__, "--version", prog_name="quadruped-dyn", message="%(prog)s %(version)s")
def main() -> None:
    """quadruped_dyn: the paper's quadruped Newton-Euler dynamics, checked against Pinocchio."""
