"""The build cache trusts nothing it cannot verify (docs/reliability.md §4): faults are injected
into a temporary QUADRUPED_DYN_CACHE; a corrupted entry is rebuilt, never loaded."""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.cache import HASH_SUFFIX, PARTIAL_MARK, cached_build, verified
from quadruped_dyn.tolerances import REL_TOL_TERMS

#: A library small enough to compile in a fraction of a second; its constant is what an
#: altered library would change.
SOURCE = "double qd_cache_probe(void) { return 2.5; }\n"
EXPECTED = 2.5


def _compile(out: Path) -> None:
    src = out.with_name(out.name + ".c")
    src.write_text(SOURCE)
    subprocess.run(["gcc", "-shared", "-fPIC", "-O2", str(src), "-o", str(out)], check=True)
    src.unlink()


def _probe(path: Path) -> float:
    fn = ctypes.CDLL(str(path)).qd_cache_probe
    fn.restype = ctypes.c_double
    return float(fn())


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    root = tmp_path / "cache"
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(root))
    return root


def _build_counted(log: Path):
    def build(out: Path) -> None:
        with open(log, "a") as f:
            f.write("built\n")
        _compile(out)

    return build


def test_entry_is_built_once_and_verified(cache, tmp_path):
    log = tmp_path / "log"
    first = cached_build("probe", "libprobe.so", _build_counted(log))
    second = cached_build("probe", "libprobe.so", _build_counted(log))
    assert first == second and verified(first)
    assert log.read_text().count("built") == 1
    assert (first.parent / (first.name + HASH_SUFFIX)).read_text().strip()


def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _zero(p: Path) -> None:
    p.write_bytes(b"")


def _garbage(p: Path) -> None:
    p.write_bytes(os.urandom(p.stat().st_size))


def _alter_constant(p: Path) -> None:
    data = p.read_bytes()
    old = ctypes.c_double(EXPECTED)
    assert bytes(old) in data, "the constant is stored in the library"
    p.write_bytes(data.replace(bytes(old), bytes(ctypes.c_double(-1.0))))


def _drop_hash(p: Path) -> None:
    p.with_name(p.name + HASH_SUFFIX).unlink()


@pytest.mark.parametrize("fault", [_truncate, _zero, _garbage, _alter_constant, _drop_hash])
def test_corrupted_entry_is_rebuilt_not_loaded(fault, cache, tmp_path, capfd):
    log = tmp_path / "log"
    lib = cached_build("probe", "libprobe.so", _build_counted(log))
    fault(lib)
    assert not verified(lib)
    rebuilt = cached_build("probe", "libprobe.so", _build_counted(log))
    assert log.read_text().count("built") == 2, "the damaged entry was rebuilt"
    assert verified(rebuilt) and _probe(rebuilt) == EXPECTED
    why = "has no recorded hash" if fault is _drop_hash else "does not match its recorded hash"
    assert f"{why}; rebuilding it" in capfd.readouterr().err


def test_stray_partial_files_are_ignored_and_cleaned(cache, tmp_path):
    entry = cache / "probe"
    entry.mkdir(parents=True)
    stray = entry / f"libprobe.so{PARTIAL_MARK}99999"
    stray.write_bytes(b"half a library")
    (entry / "libprobe.so").write_bytes(b"half a library")  # a killed build that renamed but never hashed
    lib = cached_build("probe", "libprobe.so", _build_counted(tmp_path / "log"))
    assert _probe(lib) == EXPECTED
    assert not stray.exists()
    assert not list(entry.glob(f"*{PARTIAL_MARK}*"))


def _slow_build(out: Path) -> None:
    with open(out.parent.parent / "builds.log", "a") as f:
        f.write(f"{os.getpid()}\n")
    time.sleep(0.5)  # long enough for every process to arrive while the first builds
    _compile(out)


def _build_in_child(root: str, results: multiprocessing.Queue) -> None:
    os.environ["QUADRUPED_DYN_CACHE"] = root
    results.put(str(cached_build("probe", "libprobe.so", _slow_build)))


def test_concurrent_builds_of_one_entry_build_once(cache):
    cache.mkdir()
    ctx = multiprocessing.get_context("spawn")
    results = ctx.Queue()
    procs = [ctx.Process(target=_build_in_child, args=(str(cache), results)) for _ in range(3)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
    assert [p.exitcode for p in procs] == [0, 0, 0]
    paths = {results.get(timeout=5) for _ in procs}
    assert len(paths) == 1
    assert len((cache / "builds.log").read_text().split()) == 1, "one build, the others waited and reused it"
    assert _probe(Path(paths.pop())) == EXPECTED


def test_failing_build_leaves_nothing_trusted(cache):
    def failing(out: Path) -> None:
        out.write_bytes(b"partial")
        raise RuntimeError("compiler died")

    with pytest.raises(RuntimeError, match="compiler died"):
        cached_build("probe", "libprobe.so", failing)
    entry = cache / "probe"
    assert not (entry / "libprobe.so").exists()
    assert not list(entry.glob(f"*{PARTIAL_MARK}*"))


def test_cache_that_is_a_file_is_bad_input(tmp_path, monkeypatch):
    blocker = tmp_path / "cache"
    blocker.write_text("not a directory")
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(blocker))
    with pytest.raises(InputError, match=r"QUADRUPED_DYN_CACHE.*is a file; expected a writable directory"):
        cached_build("probe", "libprobe.so", _compile)
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(blocker / "below"))
    with pytest.raises(InputError, match=r"is a file"):
        cached_build("probe", "libprobe.so", _compile)


def test_unwritable_cache_is_bad_input(monkeypatch):
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", "/proc/quadruped_dyn_cache")  # unwritable even for root
    with pytest.raises(InputError, match=r"QUADRUPED_DYN_CACHE.* is not writable .*expected a writable directory"):
        cached_build("probe", "libprobe.so", _compile)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_cache_is_bad_input(tmp_path, monkeypatch):
    root = tmp_path / "cache"
    root.mkdir()
    root.chmod(0o500)
    monkeypatch.setenv("QUADRUPED_DYN_CACHE", str(root))
    try:
        with pytest.raises(InputError, match=r"expected a writable directory"):
            cached_build("probe", "libprobe.so", _compile)
    finally:
        root.chmod(0o700)


def test_verified_entry_is_reused_without_building(cache):
    lib = cached_build("probe", "libprobe.so", _compile)

    def must_not_build(out: Path) -> None:
        raise AssertionError("a verified entry was rebuilt")

    assert cached_build("probe", "libprobe.so", must_not_build) == lib


def test_generated_library_comes_from_a_verified_entry(paper):
    from quadruped_dyn.codegen.library import compiled_library

    assert verified(compiled_library(paper).path)


@pytest.mark.slow  # rebuilds the paper's whole library (full terms, GRF and 11 reduced models): ~2.5 min
def test_truncated_generated_library_is_rebuilt_without_a_signal(paper, tmp_path):
    """End to end, in a child process (a SIGBUS would kill it): the paper's compiled library,
    truncated in the cache, is detected, rebuilt and gives Pinocchio's M."""
    from quadruped_dyn.codegen.library import compiled_library

    original = compiled_library(paper)  # the user's cache: usually already built
    root = tmp_path / "cache"
    entry = root / original.key
    entry.mkdir(parents=True)
    lib = entry / original.path.name
    lib.write_bytes(original.path.read_bytes()[:4096])
    (entry / (lib.name + HASH_SUFFIX)).write_text((original.path.parent / (lib.name + HASH_SUFFIX)).read_text())
    child = (
        "import numpy as np\n"
        "from quadruped_dyn.codegen.library import CompiledFunction, compiled_library\n"
        "from quadruped_dyn.references.pinocchio import PinocchioReference\n"
        "from quadruped_dyn.model.robot import load_robot\n"
        "from quadruped_dyn.model.state import random_state\n"
        "r = load_robot('paper')\n"
        "s = random_state(r.lower, r.upper, np.random.default_rng(0))\n"
        "(M,) = CompiledFunction(compiled_library(r), 'M_full')(s.q)\n"
        "ref = PinocchioReference(r).mass_matrix(s.q)\n"
        "print(float(np.abs(M - ref).max() / np.abs(ref).max()))\n"
    )
    env = {**os.environ, "QUADRUPED_DYN_CACHE": str(root)}
    proc = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, env=env, timeout=600, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "rebuilding" in proc.stderr and "building paper's generated C (double) once" in proc.stderr
    assert float(proc.stdout.split()[-1]) <= REL_TOL_TERMS


def test_objects_are_compiled_once_per_source_and_flags(cache, tmp_path):
    """``compile_sources`` takes an object from the cache only for the same bytes and flags: the
    second library of the same source compiles nothing, a changed constant or flag compiles again,
    and each library answers with its own source's value."""
    from quadruped_dyn.codegen.library import C_FLAGS, compile_sources

    source = tmp_path / "probe.c"
    source.write_text(SOURCE)
    assert compile_sources([source], C_FLAGS, tmp_path / "a.so") == 1
    assert compile_sources([source], C_FLAGS, tmp_path / "b.so") == 0
    assert _probe(tmp_path / "b.so") == EXPECTED
    source.write_text(SOURCE.replace("2.5", "3.5"))
    assert compile_sources([source], C_FLAGS, tmp_path / "c.so") == 1
    assert _probe(tmp_path / "c.so") == 3.5
    assert compile_sources([source], (*C_FLAGS, "-DQD_OTHER"), tmp_path / "d.so") == 1


def test_an_edited_included_file_is_compiled_again(cache, tmp_path):
    """The object's key holds the bytes of the file beside the source that it includes (as the reduced files
    include reduced_templates.h): editing only that file gives a new object, never the stale one."""
    from quadruped_dyn.codegen.library import C_FLAGS, compile_sources

    source, header = tmp_path / "probe.c", tmp_path / "value.h"
    source.write_text('#include "value.h"\ndouble qd_cache_probe(void) { return VALUE; }\n')
    header.write_text("#define VALUE 2.5\n")
    assert compile_sources([source], C_FLAGS, tmp_path / "a.so") == 1
    assert _probe(tmp_path / "a.so") == 2.5
    header.write_text("#define VALUE 3.5\n")
    assert compile_sources([source], C_FLAGS, tmp_path / "b.so") == 1
    assert _probe(tmp_path / "b.so") == 3.5


@pytest.mark.parametrize("include", ['#include "missing.h"', "#include QD_HEADER", '#include "sub/value.h"'])
def test_an_include_the_key_cannot_hold_is_refused(cache, tmp_path, include):
    from quadruped_dyn.codegen.library import C_FLAGS, compile_sources
    from quadruped_dyn.errors import BuildError

    source = tmp_path / "probe.c"
    source.write_text(include + "\n" + SOURCE)
    with pytest.raises(BuildError, match="includes .*only <system> headers and self-contained files beside them"):
        compile_sources([source], C_FLAGS, tmp_path / "a.so")


def test_a_library_build_says_so_once(paper, cache, monkeypatch, capfd):
    """Building a robot's generated C takes minutes: the build says so on stderr, and only a build
    (found by a fresh-clone review: `control` sat at its first progress tick for ~3 min, silent)."""
    from quadruped_dyn.codegen import library

    monkeypatch.setattr(library, "generate", lambda robot, out, precision: SimpleNamespace(c_sources=[], library_sources=[]))
    monkeypatch.setattr(library, "compile_sources", lambda sources, flags, out, cc: _compile(out))
    library.compiled_library(paper)
    assert f"building paper's generated C (double) once into the cache {cache}" in capfd.readouterr().err
    library.compiled_library(paper)
    assert "building" not in capfd.readouterr().err
