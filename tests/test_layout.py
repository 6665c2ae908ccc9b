"""The package's layout: every module imports on its own, and ``import quadruped_dyn`` stays light.

The layer contract itself (each subpackage imports only from the layers below it) is import-linter's,
configured in pyproject.toml and run by ``./run test``; it runs here too, so that a plain ``pytest``
catches a broken layer.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import subprocess
import sys
from pathlib import Path

import pytest

import quadruped_dyn

OPTIONAL = {"quadruped_dyn.references.mujoco": "mujoco", "quadruped_dyn.references.idyntree": "idyntree",
            **{f"quadruped_dyn.control.{m}": "mujoco" for m in ("plant", "plan", "controllers", "run", "measures",
                                                               "study_files", "closed_loop", "perturbations",
                                                               "thresholds")},
            "quadruped_dyn.control.wbc": "proxsuite", "quadruped_dyn.control.mpc": "proxsuite"}
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


def test_the_command_line_starts_light() -> None:
    """``quadruped-dyn --help`` and every command's option parsing load none of scipy, matplotlib, CasADi or Pinocchio
    (2 s before the commands imported them at the top: each command imports its work when it runs)."""
    code = ("import sys; from quadruped_dyn.cli.commands import main; from click.testing import CliRunner; "
            "assert all(CliRunner().invoke(main, [c, '--help']).exit_code == 0 for c in main.commands); "
            "assert CliRunner().invoke(main, ['--help']).exit_code == 0; "
            "print(sorted({'scipy', 'matplotlib', 'casadi', 'pinocchio'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out


def test_layer_contract() -> None:
    lint = Path(sys.executable).with_name("lint-imports")
    if not lint.exists():
        pytest.skip("import-linter is not installed (pip install '.[test]')")
    proc = subprocess.run([str(lint), "--no-cache", "--no-logo"], capture_output=True, text=True,
                          cwd=Path(__file__).resolve().parents[1])
    assert proc.returncode == 0, proc.stdout[-3000:]


SUBPACKAGES = sorted(m.name for m in pkgutil.iter_modules(quadruped_dyn.__path__, "quadruped_dyn.") if m.ispkg)


@pytest.mark.parametrize("name", SUBPACKAGES)
def test_subpackage_exports_resolve(name: str) -> None:
    """Every name in a subpackage's ``__all__`` is what its module defines (exports are lazy)."""
    package = importlib.import_module(name)
    assert package.__all__, f"{name} exports nothing"
    for export in package.__all__:
        module = next((m for m in OPTIONAL if m.startswith(name + ".") and export in _names_of(m)), None)
        if module is not None and importlib.util.find_spec(OPTIONAL[module]) is None:
            continue  # an optional library's adapter
        assert getattr(package, export) is not None, (name, export)


def _names_of(module: str) -> set[str]:
    """Top-level names a module's source defines (without importing it)."""
    import ast

    path = Path(quadruped_dyn.__file__).parent.joinpath(*module.split(".")[1:]).with_suffix(".py")
    tree = ast.parse(path.read_text())
    names = {n.name for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)}
    return names | {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}


def test_top_level_exports_the_api_errors() -> None:
    """Both errors the API raises (docs/reliability.md) are importable from the package itself."""
    from quadruped_dyn import InputError, NumericalError
    from quadruped_dyn.errors import InputError as input_error
    from quadruped_dyn.errors import NumericalError as numerical_error

    assert (InputError, NumericalError) == (input_error, numerical_error)
    assert {"InputError", "NumericalError"} <= set(quadruped_dyn.__all__)


def test_typed_names_are_the_lazy_names() -> None:
    """The top-level package lists its names twice: as imports for a type checker and in
    ``_MODULES`` for loading on first use. The two lists name the same things, or a name is untyped or missing."""
    import ast

    tree = ast.parse(Path(quadruped_dyn.__file__).read_text())
    typed = {(node.module.removeprefix("quadruped_dyn."), alias.name)
             for block in tree.body if isinstance(block, ast.If) and ast.unparse(block.test) == "TYPE_CHECKING"
             for node in block.body if isinstance(node, ast.ImportFrom) and node.module for alias in node.names}
    lazy = {(module, name) for module, names in quadruped_dyn._MODULES.items() for name in names}
    assert typed and typed == lazy, (typed ^ lazy)


def test_no_two_modules_share_a_file_name() -> None:
    """A module's file name says its concept once in the package (``__init__`` and ``__main__`` aside)."""
    modules = [m for m in MODULES if importlib.util.find_spec(m).submodule_search_locations is None]  # not packages
    stems = [m.rsplit(".", 1)[-1] for m in modules]
    shared = sorted({s for s in stems if stems.count(s) > 1})
    assert len(modules) > 100 and not shared, shared
