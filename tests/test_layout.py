"""The package's layout: every module imports on its own, and ``import quadruped_dyn`` stays light.

The layer contract itself (each subpackage imports only from the layers below it) is import-linter's,
configured in pyproject.toml and run by ``./run test``; it runs here too, so that a plain ``pytest``
catches a broken layer.
"""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import quadruped_dyn

OPTIONAL = {"quadruped_dyn.references.mujoco": "mujoco", "quadruped_dyn.references.idyntree": "idyntree"}
MODULES = sorted(m.name for m in pkgutil.walk_packages(quadruped_dyn.__path__, "quadruped_dyn.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_every_module_imports(name: str) -> None:
    if name in OPTIONAL:
        pytest.importorskip(OPTIONAL[name])
    assert importlib.import_module(name).__doc__, f"{name} has no docstring saying what it holds"


def test_top_level_import_is_light() -> None:
    """``import quadruped_dyn`` loads neither scipy nor matplotlib (the CLI and the API start fast)."""
    code = "import sys, quadruped_dyn; print(sorted({'scipy', 'matplotlib'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out


def test_layer_contract() -> None:
    lint = Path(sys.executable).with_name("lint-imports")
    if not lint.exists():
        pytest.skip("import-linter is not installed (pip install '.[test]')")
    proc = subprocess.run([str(lint), "--no-cache", "--no-logo"], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[1])
    assert proc.returncode == 0, proc.stdout[-3000:]
