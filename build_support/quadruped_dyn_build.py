"""The build backend: setuptools' own, run on a temporary copy of the source tree for a wheel or
an sdist, so that ``pip install .`` leaves no ``build/`` or ``*.egg-info`` in the checkout.

The editable install (``pip install -e .``, ``./run``'s setup) is setuptools' unchanged: it must
point at this tree, not at a copy.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from setuptools import build_meta as _setuptools
from setuptools.build_meta import (  # noqa: F401  (the editable install's hooks, unchanged)
    build_editable,
    get_requires_for_build_editable,
    prepare_metadata_for_build_editable,
)

_NOT_SOURCE = shutil.ignore_patterns(".git", ".venv", "build", "dist", "*.egg-info", "results", "__pycache__",
                                     ".*_cache", ".hypothesis")


@contextmanager
def _in_copy() -> Iterator[None]:
    """The hook runs in a copy of the current directory (the source tree), removed afterwards."""
    here = Path.cwd()
    with tempfile.TemporaryDirectory(prefix="quadruped_dyn-build-") as tmp:
        copy = Path(tmp) / "src"
        shutil.copytree(here, copy, ignore=_NOT_SOURCE)
        os.chdir(copy)
        try:
            yield
        finally:
            os.chdir(here)


def build_wheel(wheel_directory: str, config_settings: Any = None, metadata_directory: str | None = None) -> str:
    wheel_directory = os.path.abspath(wheel_directory)
    with _in_copy():
        return _setuptools.build_wheel(wheel_directory, config_settings, metadata_directory)


def build_sdist(sdist_directory: str, config_settings: Any = None) -> str:
    sdist_directory = os.path.abspath(sdist_directory)
    with _in_copy():
        return _setuptools.build_sdist(sdist_directory, config_settings)


def prepare_metadata_for_build_wheel(metadata_directory: str, config_settings: Any = None) -> str:
    metadata_directory = os.path.abspath(metadata_directory)
    with _in_copy():
        return _setuptools.prepare_metadata_for_build_wheel(metadata_directory, config_settings)


def get_requires_for_build_wheel(config_settings: Any = None) -> list[str]:
    with _in_copy():  # setuptools runs egg_info for it
        return _setuptools.get_requires_for_build_wheel(config_settings)


def get_requires_for_build_sdist(config_settings: Any = None) -> list[str]:
    with _in_copy():
        return _setuptools.get_requires_for_build_sdist(config_settings)
