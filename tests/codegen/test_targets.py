"""The generated C on embedded targets (docs/embedded.md): cross-built -std=c99 -Wall -Wextra
-Werror clean for Cortex-M7 (double), Cortex-M4F (float) and aarch64 (both), and its check
program run under QEMU against the same Pinocchio-built reference values as on x86-64; and
thread safety (every function from several threads at once, bit for bit the serial results).

Without the cross toolchains or QEMU these tests are skipped with a message (./run installs them
as root). The default suite runs the aarch64 double check of casadi_gen and the thread test;
the other targets, the float builds and the example-robot-data robot are slow tests."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from quadruped_dyn.checks.check_program_values import generate_checked
from quadruped_dyn.codegen.emit import CODEGEN_FUNCTIONS, N_DERIVATIVE_FUNCTIONS, REDUCED_NAMES, REDUCED_STANCE_SETS
from quadruped_dyn.codegen.file_names import robot_stem
from quadruped_dyn.codegen.library import compiled_library
from quadruped_dyn.codegen.targets import TARGETS, Target, make, run_check, skip_reason
from quadruped_dyn.model.robot import load_robot
from tests.codegen.test_emit import MAX_DOUBLE_SKIPPED, MAX_FLOAT_SKIPPED

CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"
N_FUNCTIONS = len(CODEGEN_FUNCTIONS) + len(REDUCED_NAMES) * len(REDUCED_STANCE_SETS) + N_DERIVATIVE_FUNCTIONS


def _require(target: Target) -> None:
    reason = skip_reason(target)
    if reason:
        pytest.skip(reason)


def _assert_check_passed(proc: subprocess.CompletedProcess[str], precision: str, what: str) -> None:
    """Every function checked: all pass, at most MAX_DOUBLE_SKIPPED / MAX_FLOAT_SKIPPED skipped."""
    out = proc.stdout
    assert proc.returncode == 0, f"{what}: exit {proc.returncode}\n{out[-3000:]}\n{proc.stderr[-2000:]}"
    summary = re.search(r"\n(\d+) passed, (\d+) failed(?:, (\d+) skipped)?\n", "\n" + out)
    assert summary, f"{what}: no summary line\n{out[-2000:]}"
    passed, failed, skipped = (int(g or 0) for g in summary.groups())
    assert failed == 0 and passed + skipped == N_FUNCTIONS, f"{what}: {summary.group(0).strip()}"
    assert skipped <= (MAX_FLOAT_SKIPPED if precision == "float" else MAX_DOUBLE_SKIPPED), f"{what}: {summary.group(0).strip()}"
    assert "FAIL" not in out and "returned" not in out


def _check_target(source: Path, build: Path, target: Target, precisions: tuple[str, ...]) -> None:
    programs = [p for p, prec in zip(target.programs, target.precisions) if prec in precisions]
    make(source, [str(build.resolve() / p) for p in programs], build)
    for program, precision in zip(programs, precisions):
        _assert_check_passed(run_check(target, build / program), precision, f"{target.name} {precision} ({source.name})")


def test_aarch64_double_check_of_casadi_gen(tmp_path):
    """Default suite: casadi_gen cross-built for aarch64 (double, -Os) and checked under qemu-aarch64."""
    _require(TARGETS["aarch64"])
    _check_target(CASADI_GEN, tmp_path / "build", TARGETS["aarch64"], ("double",))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cortex-m7", "cortex-m4f", "aarch64"])
def test_casadi_gen_checks_on_target(tmp_path, name):
    """`make check-<target>`: the paper robot's committed C on each target, every precision it builds."""
    target = TARGETS[name]
    _require(target)
    _check_target(CASADI_GEN, tmp_path / "build", target, target.precisions)


@pytest.fixture(scope="module")
def b1_generated(tmp_path_factory, erd):
    """The example-robot-data B1, given by path, generated with its reference values."""
    urdf = Path(str(erd)) / "b1_description" / "urdf" / "b1.urdf"
    if not urdf.is_file():
        pytest.skip(f"{urdf} not found (example-robot-data)")
    out = tmp_path_factory.mktemp("b1_gen")
    generate_checked(load_robot(str(urdf)), out)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cortex-m7", "cortex-m4f", "aarch64"])
def test_example_robot_data_b1_checks_on_target(tmp_path, b1_generated, name):
    target = TARGETS[name]
    _require(target)
    _check_target(b1_generated, tmp_path / "build", target, target.precisions)


def test_cross_builds_are_warning_free_and_board_memory_fits():
    """The Makefile's cross flags: C99, -Wall -Wextra -Werror, the FPU of each core; a check
    program's image fits the MPS2 boards' 4 MB code and 4 MB data RAM (cortex_m.ld)."""
    makefile = (CASADI_GEN / "Makefile").read_text()
    assert "WARN = -std=c99 -pedantic -Wall -Wextra -Werror" in makefile
    assert "-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard" in makefile
    assert "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard" in makefile
    linker = (CASADI_GEN / "cortex_m.ld").read_text()
    assert "ORIGIN = 0x00000000, LENGTH = 4M" in linker and "ORIGIN = 0x20000000, LENGTH = 4M" in linker


def _thread_program(robot_dir: Path, library: Path, out: Path, flags: list[str]) -> Path:
    name = robot_stem("paper")
    cmd = ["gcc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", *flags, "-pthread", "-Dcasadi_real=double",
           f'-DQD_HEADER="{name}.h"', f'-DQD_REFERENCE="{name}-reference.h"', f"-I{robot_dir}",
           str(robot_dir / "check_threads.c"), str(library), f"-Wl,-rpath,{library.parent}", "-lm", "-o", str(out)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


def test_every_function_is_thread_safe_bit_for_bit(tmp_path, paper):
    """check_threads.c: 4 threads x 20 rounds of every generated function at once, each thread with
    its own work memory, against the serial results bit for bit (the cached -O3 library of the
    same code)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not installed")
    program = _thread_program(CASADI_GEN, compiled_library(paper).path, tmp_path / "threads", ["-O2"])
    proc = subprocess.run([str(program)], capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert re.search(rf"^{N_FUNCTIONS} functions, 4 threads x 20 rounds: {N_FUNCTIONS * 80} calls, 0 differ", proc.stdout)


def _tsan_available(tmp_path: Path) -> bool:
    probe = tmp_path / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    proc = subprocess.run(["gcc", "-fsanitize=thread", str(probe), "-o", str(tmp_path / "probe")], capture_output=True,
                          check=False)
    return proc.returncode == 0 and subprocess.run([str(tmp_path / "probe")], check=False).returncode == 0


@pytest.mark.slow
def test_thread_program_is_threadsanitizer_clean(tmp_path):
    """`make check-threads-tsan`: library and program built with -fsanitize=thread, no report."""
    if shutil.which("gcc") is None or not _tsan_available(tmp_path):
        pytest.skip("gcc -fsanitize=thread (libtsan) not available")
    work = tmp_path / "casadi_gen"
    shutil.copytree(CASADI_GEN, work, ignore=shutil.ignore_patterns("build"))
    proc = subprocess.run(["make", "-C", str(work), "-j2", "check-threads-tsan"], capture_output=True, text=True,
                          timeout=3600, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    assert "WARNING: ThreadSanitizer" not in proc.stdout + proc.stderr
    assert " 0 differ from the serial results" in proc.stdout
