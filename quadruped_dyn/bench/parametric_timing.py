"""The parametric library's cost per call against Pinocchio's and the fixed library's, in the same run, and the time a
new robot takes from a fresh cache to its first compiled parametric M_full.

Per call (``c/bench_parametric.c`` beside ``c/bench_pinocchio.cpp``, alternated over rounds as ``timing.run_bench``
does; median ns): p_M_full ~ crba and M_full, p_id_full ~ rnea and id_full, p_nle_full ~ nonLinearEffects and
nle_full. The fixed library is the robot's own (``compiled_library``: minutes for a robot not yet in the cache).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from quadruped_dyn.bench.harnesses import HARNESSES, cmeel_prefix
from quadruped_dyn.bench.placement import TimedProgram, median_over_rounds
from quadruped_dyn.bench.timing import pinocchio_harness
from quadruped_dyn.codegen.library import C_FLAGS, compiled_library, run_tool
from quadruped_dyn.codegen.parametric_library import parametric_library
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import random_state

#: (parametric, fixed, Pinocchio) of each timed term
PAIRS = (("p_M_full", "M_full", "crba"), ("p_id_full", "id_full", "rnea"),
         ("p_nle_full", "nle_full", "nonLinearEffects"))


def parametric_timings(robot: Robot, calls: int = 20000, reps: int = 9, rounds: int = 5,
                       cc: str = "gcc") -> dict[str, dict[str, float]]:
    """Per term (``PAIRS``): ns per call of the parametric, fixed and Pinocchio functions and the ratios."""
    library = parametric_library(robot)
    p = library.parameters(robot)
    fixed = compiled_library(robot, cc=cc)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(0))
    numbers = [repr(float(x)) for x in np.concatenate([s.q, s.v, s.a, s.f.ravel(), p])]
    flags = (*C_FLAGS, "-Dcasadi_real=double")
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("bench_parametric.c", "bench_median.h"):
            shutil.copy(HARNESSES / name, tmp)
        for path in (fixed.path, library.library.path):
            shutil.copy(path, tmp)
            shutil.copy(path.with_name(path.name.removeprefix("lib").replace(".so", ".h")), tmp)
        libs = [Path(tmp) / fixed.path.name, Path(tmp) / library.library.path.name]
        run_tool([cc, *flags, f"-DQD_HEADER=\"{fixed.path.stem.removeprefix('lib')}.h\"",
                  f"-DQD_P_HEADER=\"{library.library.path.stem.removeprefix('lib')}.h\"", "bench_parametric.c",
                  *(p.name for p in libs), "-Wl,--enable-new-dtags", f"-Wl,-rpath,{tmp}", "-lm", "-o", "bench_parametric"],
                 cwd=tmp)
        programs = {"generated": TimedProgram([str(Path(tmp) / "bench_parametric"), str(calls), str(reps), *numbers],
                                              tuple(libs)),
                    "pinocchio": TimedProgram([str(pinocchio_harness()), str(robot.urdf), str(calls), str(reps)],
                                              (cmeel_prefix() / "lib" / "libpinocchio_default.so",))}
        median, _ = median_over_rounds(programs, rounds)
    ours, theirs = median["generated"], median["pinocchio"]
    return {fixed_name: {"parametric_ns": ours[name], "fixed_ns": ours[fixed_name], "pinocchio_ns": theirs[algo],
                         "vs_pinocchio": ours[name] / theirs[algo], "vs_fixed": ours[name] / ours[fixed_name]}
            for name, fixed_name, algo in PAIRS}


_FIRST_CALL = """
import sys, numpy as np
from quadruped_dyn import load_robot
from quadruped_dyn.codegen.parametric_library import parametric_library
robot = load_robot(sys.argv[1])
library = parametric_library(robot)
M = library.function("M_full")(np.concatenate([[0, 0, 0, 0, 0, 0, 1], robot.standing_q]), library.parameters(robot))[0]
assert np.all(np.isfinite(M))
"""


def first_call_seconds(urdf: str) -> float:
    """Wall seconds from a fresh cache (a new process, an empty QUADRUPED_DYN_CACHE) to the first compiled parametric
    M_full of the robot at ``urdf``: load, symbolic build, print, compile, call."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "QUADRUPED_DYN_CACHE": cache}
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", _FIRST_CALL, urdf], env=env, check=True, capture_output=True)
        return time.perf_counter() - start
