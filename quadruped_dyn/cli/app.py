"""The ``quadruped-dyn`` group: exit codes (0 success, 1 a check or a computation failed, 2 bad input), one-line errors
and warnings, progress on stderr. Each command lives in its own module of this package."""

from __future__ import annotations

import shutil
import sys
import warnings
from typing import Any

import click

from quadruped_dyn.errors import BuildError, InputError, NumericalError, UrdfWarning

EXIT_CHECK_FAILED = 1
EXIT_BAD_INPUT = 2


def _warn_one_line(message: Warning | str, category: type[Warning], *args: object, **kwargs: object) -> None:
    click.echo(f"warning: {message}", err=True)


class _Group(click.Group):
    """Maps InputError and click's usage errors to exit code 2 and BuildError and NumericalError to 1, with a one-line
    message and no traceback; prints UrdfWarnings as one line each."""

    def invoke(self, ctx: click.Context) -> Any:
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("always", UrdfWarning)
                warnings.showwarning = _warn_one_line
                return super().invoke(ctx)
        except InputError as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except click.UsageError as e:
            click.echo(f"error: {e.format_message()}", err=True)
            sys.exit(EXIT_BAD_INPUT)
        except (BuildError, NumericalError) as e:
            click.echo(f"error: {e}", err=True)
            sys.exit(EXIT_CHECK_FAILED)


def require_tools(*tools: str) -> None:
    missing = [t for t in tools if shutil.which(t) is None]
    if missing:
        raise InputError(f"{', '.join(missing)} not found; expected on PATH (Debian: apt-get install gcc g++)")


class _ProgressLines:
    """Progress as one stderr line per ~10 % (click's bar draws nothing when stderr is not a terminal)."""

    def __init__(self, label: str, length: int) -> None:
        self.label, self.length, self.done = label, length, 0

    def __enter__(self) -> _ProgressLines:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def update(self, n: int) -> None:
        self.done += n
        if self.done % max(1, self.length // 10) == 0 or self.done == self.length:
            click.echo(f"{self.label}: {self.done}/{self.length}", err=True)


def progress(label: str, length: int) -> Any:
    if sys.stderr.isatty():
        return click.progressbar(length=length, label=label, file=sys.stderr)
    return _ProgressLines(label, length)


@click.group(cls=_Group)
def main() -> None:
    """quadruped_dyn: the paper's quadruped Newton-Euler dynamics, checked against Pinocchio."""
