"""A full or read-only cache is one line naming the cache (files/cache.py); an interrupted optimize says only that."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace

import pytest
from click.testing import CliRunner

from quadruped_dyn.cli import main
from quadruped_dyn.codegen import library
from quadruped_dyn.errors import InputError
from quadruped_dyn.files import cache

FULL = r"the cache \(QUADRUPED_DYN_CACHE\) at '{}' is full \(.* MB free on its filesystem\); expected at least 64 MB"


def _mount(target: Path, options: str) -> bool:
    """A tmpfs at ``target`` (root only, where mounts are allowed): True if mounted."""
    target.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        return False
    return subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(target)], capture_output=True).returncode == 0


@pytest.fixture
def full_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A cache on a 64 kB filesystem: a real tmpfs where it can be mounted, else its free space reported as 64 kB."""
    root = tmp_path / "small"
    mounted = _mount(root, "size=64k")
    if not mounted:
        real = os.statvfs
        monkeypatch.setattr(cache.os, "statvfs", lambda p: SimpleNamespace(f_bavail=16, f_frsize=4096)
                            if str(p).startswith(str(root)) else real(p))
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(root / "cache"))
    yield root / "cache"
    if mounted:
        subprocess.run(["umount", str(root)], check=True)


def _big_source(tmp_path: Path) -> Path:
    source = tmp_path / "big.c"  # an object of ~1.6 MB: more than the filesystem holds
    source.write_text("double table[200000] = {1.0};\ndouble get(int i) { return table[i]; }\n")
    return source


def test_a_full_cache_is_named_as_full_api(full_cache, tmp_path):
    with pytest.raises(InputError, match=FULL.format(full_cache)):
        library.cached_object(_big_source(tmp_path), ("-O0",))
    assert not list(full_cache.rglob("*.partial-*")), "nothing of the failed build is kept"


def test_a_full_disk_at_the_write_is_named_as_full(tmp_path, monkeypatch):
    """ENOSPC raised by the write itself, whatever the free space says."""
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(tmp_path / "cache"))

    def write(path: Path) -> None:
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    with pytest.raises(InputError, match=FULL.format(tmp_path / "cache")):
        cache.cached_build("entry", "artefact.bin", write)


def test_a_full_cache_is_one_error_line_cli(full_cache, tmp_path, monkeypatch):
    """validate compiles the robot's C into the cache: the generation is replaced by one large source."""
    source = _big_source(tmp_path)
    monkeypatch.setattr(library, "generate", lambda *args: SimpleNamespace(c_sources=[source], library_sources=[]))
    result = CliRunner().invoke(main, ["validate", "paper", "--out", str(tmp_path / "out"), "--horizon", "0.1"])
    assert result.exit_code == 2, result.output
    errors = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in result.output
    assert __import__("re").search(FULL.format(full_cache), errors[0]), errors
    assert result.stderr.splitlines() == errors, "the full cache is found before any progress note is printed"


@pytest.fixture
def read_only_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A cache directory that cannot be written: a read-only tmpfs as root, else a directory without write permission."""
    root = tmp_path / "ro"
    mounted = _mount(root, "size=64k,ro")
    if not mounted:
        root.chmod(0o555)
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(root / "cache"))
    yield root / "cache"
    if mounted:
        subprocess.run(["umount", str(root)], check=True)
    else:
        root.chmod(0o755)


@pytest.mark.parametrize("command", [["control", "paper", "--cycles", "1"], ["report", "paper"],
                                     ["bench", "--robot", "paper"]], ids=["control", "report", "bench"])
def test_a_read_only_cache_is_exit_2_and_one_line(read_only_cache, tmp_path, command):
    result = CliRunner().invoke(main, [*command, *(["--out", str(tmp_path / "out")] if command[0] != "bench" else [])])
    assert result.exit_code == 2, result.output
    assert result.stderr.count("\n") == 1, result.stderr
    assert f"the cache directory '{read_only_cache}' (QUADRUPED_DYN_CACHE) is not writable" in result.stderr


def test_a_read_only_cache_api(read_only_cache):
    with pytest.raises(InputError, match="is not writable"):
        cache.writable_cache()


def _interrupted(args: list[str], marker: str, delay: float) -> tuple[int, str, float]:
    """Run the CLI, send SIGINT ``delay`` s after ``marker`` appears on its stderr: (exit code, stderr, seconds to stop)."""
    process = subprocess.Popen([sys.executable, "-m", "quadruped_dyn.cli", *args], stderr=subprocess.PIPE, text=True,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    lines, sent = [], 0.0
    for line in process.stderr:  # type: ignore[union-attr]
        lines.append(line)
        if marker in line and not sent:
            time.sleep(delay)
            sent = time.perf_counter()
            process.send_signal(signal.SIGINT)
    process.wait(timeout=60)
    return process.returncode, "".join(lines), time.perf_counter() - sent


def test_an_interrupted_optimize_prints_no_casadi_warning(tmp_path):
    code, stderr, _ = _interrupted(["optimize", "paper", "--out", str(tmp_path)], "solving", 1.0)
    assert code == 130, stderr
    assert stderr.splitlines()[-1] == "error: interrupted"
    assert "CasADi" not in stderr and "WARNING" not in stderr, stderr
    assert not list(tmp_path.iterdir()), "nothing written"
