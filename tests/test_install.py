"""The package installs (NOT editable) into a fresh virtual environment and works there: the
paper's URDF and the C templates are package data, nothing is read from the checkout."""

from __future__ import annotations

import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

CHECKOUT = Path(__file__).resolve().parent.parent
NOT_SOURCE = shutil.ignore_patterns(".venv", ".git", "build", "*.egg-info", "results", "__pycache__", ".*_cache",
                                    ".hypothesis", "notebooks", "casadi_gen")


def _install(tmp_path: Path, deps: bool) -> Path:
    """A fresh venv with a regular (non-editable) install of a copy of the checkout; its bin/.
    Without ``deps`` the venv sees this environment's packages (not this checkout) through a
    .pth file, so only the package itself is installed."""
    source = tmp_path / "src"
    shutil.copytree(CHECKOUT, source, ignore=NOT_SOURCE)  # pip builds in the tree: keep the checkout clean
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    if not deps:
        purelib = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                                 capture_output=True, text=True, check=True).stdout.strip()
        lines = [f"import site; site.addsitedir({d!r})" for d in site.getsitepackages()]
        Path(purelib, "zz_test_env.pth").write_text("\n".join(lines) + "\n")
    cmd = [sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet", str(source)]
    proc = subprocess.run(cmd + ([] if deps else ["--no-deps"]), capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]
    left = sorted(p.name for p in source.iterdir() if p.name == "build" or p.name.endswith(".egg-info"))
    assert not left, f"pip install . left {left} in the source tree"
    where = subprocess.run([str(python), "-c", "import quadruped_dyn; print(quadruped_dyn.__file__)"],
                           capture_output=True, text=True, check=True, cwd=tmp_path).stdout
    assert where.startswith(str(venv)), f"imported from {where}, not the installed copy"
    return venv / "bin"


def _run(bin_dir: Path, tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run([str(bin_dir / "quadruped-dyn"), *args], capture_output=True, text=True, cwd=tmp_path,
                          check=False)
    assert proc.returncode == 0, (args, proc.stderr[-2000:])
    return proc


def test_installed_package_info(tmp_path):
    bin_dir = _install(tmp_path, deps=False)
    info = _run(bin_dir, tmp_path, "info", "paper").stdout
    assert info.startswith("paper  (" + str(tmp_path / "venv"))
    assert "total mass 10.000 kg" in info


@pytest.mark.slow
def test_installed_package_with_its_dependencies(tmp_path):
    """The whole install, dependencies from the index (pip's cache makes it ~30 s): info, check
    and codegen, whose C equals the committed casadi_gen/."""
    bin_dir = _install(tmp_path, deps=True)
    _run(bin_dir, tmp_path, "info", "paper")
    assert "all terms pass" in _run(bin_dir, tmp_path, "check", "paper", "--samples", "2").stdout
    _run(bin_dir, tmp_path, "codegen", "paper", "--out", str(tmp_path / "gen"))
    for name in ("qd_paper.c", "qd_paper.h", "qd_paper-r-FL_BR.c"):
        assert (tmp_path / "gen" / name).read_text() == (CHECKOUT / "casadi_gen" / name).read_text(), name
