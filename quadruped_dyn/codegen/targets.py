"""Embedded targets of the generated C (docs/embedded.md): cross toolchains, the generated
Makefile's targets for them, and running the check program under QEMU.

The Makefile (``c/Makefile``) holds the flags; this module only names the targets, says which
tools each needs, and runs ``make``. Cortex-M7 builds ``double`` for its double-precision FPU
(QEMU board mps2-an500), Cortex-M4F builds ``float`` for its single-precision FPU (mps2-an386),
aarch64 builds both (Linux user mode, ``qemu-aarch64``).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from quadruped_dyn.errors import BuildError

#: Debian packages that provide the tools (``./run`` installs them when it can).
DEBIAN_PACKAGES = ("gcc-arm-none-eabi", "libnewlib-arm-none-eabi", "qemu-system-arm",
                   "gcc-aarch64-linux-gnu", "libc6-dev-arm64-cross", "qemu-user")


@dataclass(frozen=True)
class Target:
    name: str  # the Makefile target: `make NAME`, `make check-NAME`
    precisions: tuple[str, ...]  # casadi_real of its builds
    compiler: str
    emulator: str
    board: str  # QEMU machine ('' for user mode)
    #: the check programs, relative to the build directory, one per precision
    programs: tuple[str, ...]

    def library(self, precision: str, stem: str) -> str:
        """The static library of one precision, relative to the build directory."""
        return f"{self.name}/lib{stem}{'_float' if precision == 'float' else ''}.a"


TARGETS: dict[str, Target] = {
    t.name: t
    for t in (
        Target("cortex-m7", ("double",), "arm-none-eabi-gcc", "qemu-system-arm", "mps2-an500",
               ("cortex-m7/check_qd.elf",)),
        Target("cortex-m4f", ("float",), "arm-none-eabi-gcc", "qemu-system-arm", "mps2-an386",
               ("cortex-m4f/check_qd_float.elf",)),
        Target("aarch64", ("double", "float"), "aarch64-linux-gnu-gcc", "qemu-aarch64", "",
               ("aarch64/check_qd", "aarch64/check_qd_float")),
    )
}


def missing_tools(target: Target, run: bool = True) -> list[str]:
    """The tools ``target`` needs (to build; and to run, when ``run``) that are not on PATH."""
    tools = [target.compiler, "make"] + ([target.emulator] if run else [])
    missing = [t for t in tools if shutil.which(t) is None]
    if target.name == "aarch64" and run and not Path("/usr/aarch64-linux-gnu/lib").is_dir():
        missing.append("/usr/aarch64-linux-gnu (libc6-arm64-cross)")
    return missing


def skip_reason(target: Target, run: bool = True) -> str | None:
    """Why ``target`` cannot be built (or run) here, or None."""
    missing = missing_tools(target, run)
    if not missing:
        return None
    return (f"{target.name}: {', '.join(missing)} not installed (Debian: apt-get install "
            f"{' '.join(DEBIAN_PACKAGES)}; ./run installs them as root)")


def make(source_dir: Path, goals: list[str], build_dir: Path, cflags: str = "-Os", jobs: int = 2,
         timeout: float = 3600, stem: str | None = None) -> subprocess.CompletedProcess[str]:
    """``make -C source_dir GOALS B=build_dir CROSS_CFLAGS=cflags`` (and ``ROBOT=`` the robot of the files ``stem``
    starts, if given); BuildError on failure with its output."""
    robot = [f"ROBOT={stem.removeprefix('qd_')}"] if stem else []
    cmd = ["make", "-C", str(source_dir), f"-j{jobs}", f"B={Path(build_dir).resolve()}", f"CROSS_CFLAGS={cflags}", *robot,
           *goals]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env={**os.environ, "LC_ALL": "C"})
    except subprocess.TimeoutExpired as e:
        raise BuildError(f"{' '.join(cmd)} timed out after {timeout:.0f} s") from e
    if proc.returncode != 0:
        raise BuildError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc


def run_command(target: Target, program: Path) -> list[str]:
    """The command that runs a check program of ``target`` under QEMU."""
    if target.board:
        return [target.emulator, "-M", target.board, "-nographic", "-semihosting-config", "enable=on,target=native",
                "-kernel", str(program)]
    return [target.emulator, "-L", "/usr/aarch64-linux-gnu", str(program)]


def run_check(target: Target, program: Path, timeout: float = 900) -> subprocess.CompletedProcess[str]:
    """Run one check program under QEMU (its exit status is the check's)."""
    return subprocess.run(run_command(target, program), capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)
