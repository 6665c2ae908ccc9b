"""The reduced files' products in pairs (codegen/c/qd_reduced_solve.c, ``qd_pair``: GCC's vector extension) give the
scalar loops' results to the bit: the paper robot's fd_r built both ways (QD_NO_PAIRS), one stance set of two, three
and four feet, at states around the reference state."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from quadruped_dyn.checks.check_program_values import reduced_inputs, reference_state
from quadruped_dyn.codegen.library import C_FLAGS, CompiledFunction, CompiledLibrary, compile_sources
from quadruped_dyn.model.robot import load_robot

CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"
STANCES = ("FL_BR", "FL_FR_BL", "FL_FR_BL_BR")


@pytest.mark.slow
def test_pairs_give_the_scalar_loops_results_to_the_bit(tmp_path):
    sources = [CASADI_GEN / "qd_paper.c", CASADI_GEN / "qd_paper-d.c", *(CASADI_GEN / f"qd_paper-r-{s}.c" for s in STANCES)]
    builds = {}
    for name, extra in (("pairs", ()), ("scalar", ("-DQD_NO_PAIRS",))):
        path = tmp_path / f"libqd_paper_{name}.so"
        compile_sources(sources, (*C_FLAGS, "-Dcasadi_real=double", *extra), path)
        builds[name] = CompiledLibrary(path, sources[0], name)
    x0 = reduced_inputs(reference_state(load_robot("paper")))
    rng = np.random.default_rng(25)
    for stance in STANCES:
        n = 13 if stance.count("_") == 1 else 12
        fs = {name: CompiledFunction(lib, f"fd_r_{stance}") for name, lib in builds.items()}
        for _ in range(5):
            x = {k: v if k == "quat" else v[:n] + (rng.normal(scale=0.02, size=n) if k == "q_r" else 0.0)
                 for k, v in x0.items()}
            pairs, scalar = (f(*[x[k] for k in f.names_in])[0] for f in fs.values())
            assert np.all(np.isfinite(pairs)) and np.array_equal(pairs, scalar), stance
