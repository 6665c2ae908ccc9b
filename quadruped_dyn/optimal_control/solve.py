"""Solve a transcribed gait cycle with IPOPT (shipped with the casadi wheel), warm-started from the plan.

``solve`` returns a ``Solution`` whatever IPOPT says; ``Solution.converged`` is True only for
IPOPT's "Solve_Succeeded" with the constraint violation (recomputed here from the NLP's own
bounds, not taken from IPOPT) at most MAX_CONSTRAINT_VIOLATION. Callers must check it
(the CLI exits 1 with IPOPT's status otherwise).
"""

from __future__ import annotations

import contextlib
import io
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from quadruped_dyn.interrupts import interrupts_deferred
from quadruped_dyn.optimal_control.blocks import derivative_functions
from quadruped_dyn.optimal_control.transcription import Transcription

#: The issue's acceptance: constraint violation (max over g and the bounds, in the NLP's units:
#: N m, N, m, m/s, m/s^2, rad) at most this.
MAX_CONSTRAINT_VIOLATION = 1e-8

#: IPOPT's options: tight tolerances so the violation lands below MAX_CONSTRAINT_VIOLATION.
IPOPT_OPTIONS = {"tol": 1e-8, "constr_viol_tol": 1e-9, "acceptable_iter": 0, "max_iter": 500,
                 "print_level": 0, "sb": "yes", "mu_strategy": "adaptive", "linear_solver": "mumps"}

HESSIANS = ("exact", "limited-memory")


@dataclass
class Solution:
    transcription: Transcription
    w: np.ndarray
    status: str  # IPOPT's return_status
    success: bool
    iterations: int
    objective: float
    constraint_violation: float
    solve_seconds: float
    build_seconds: float
    hessian: str
    g: np.ndarray  # the constraint values at w
    transcribe_seconds: float = 0.0
    solve_cpu_seconds: float = 0.0  # CPU time of this process during the solve (wall time inflates under load)

    @property
    def converged(self) -> bool:
        return self.status == "Solve_Succeeded" and self.constraint_violation <= MAX_CONSTRAINT_VIOLATION


def constraint_violation(tr: Transcription, w: np.ndarray, g: np.ndarray) -> float:
    """max over the constraints and the variable bounds of the distance to the feasible interval."""
    gv = np.maximum(tr.lbg - g, 0) + np.maximum(g - tr.ubg, 0)
    wv = np.maximum(tr.lbw - w, 0) + np.maximum(w - tr.ubw, 0)
    return float(max(gv.max(initial=0.0), wv.max(initial=0.0)))


@contextmanager
def casadi_interrupt_warning_dropped() -> Iterator[None]:
    """CasADi reports the KeyboardInterrupt that stops IPOPT with its own WARNING line on sys.stderr; the command
    reports the interrupt itself ("interrupted"), so that line is dropped and every other line passed on after the block."""
    captured = io.StringIO()
    try:
        with contextlib.redirect_stderr(captured):
            yield
    finally:
        kept = [line for line in captured.getvalue().splitlines(keepends=True) if "KeyboardInterruptException" not in line]
        if kept:
            sys.stderr.write("".join(kept))


def solve(tr: Transcription, hessian: str = "exact", expand: bool = False, w0: np.ndarray | None = None,
          verbose: bool = False) -> Solution:
    """IPOPT from the plan (``tr.w0``) or ``w0``."""
    opts = dict(IPOPT_OPTIONS)
    if hessian == "limited-memory":
        opts["hessian_approximation"] = "limited-memory"
    if verbose:
        opts["print_level"] = 5
    start = time.perf_counter()
    jac_g, hess_lag = derivative_functions(tr)
    nlp_opts: dict[str, Any] = {"ipopt": opts, "expand": expand, "print_time": False, "jac_g": jac_g}
    if hessian == "exact":
        nlp_opts["hess_lag"] = hess_lag
    solver = ca.nlpsol("gait_cycle", "ipopt", tr.nlp, nlp_opts)
    build = time.perf_counter() - start
    start, cpu = time.perf_counter(), time.process_time()
    # CasADi would swallow the handler's exception ('did not converge') and report it on sys.stderr
    with casadi_interrupt_warning_dropped(), interrupts_deferred(stop=True):
        sol = solver(x0=tr.w0 if w0 is None else w0, lbx=tr.lbw, ubx=tr.ubw, lbg=tr.lbg, ubg=tr.ubg)
    seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
    stats = solver.stats()
    w = np.asarray(sol["x"]).ravel()
    g = np.asarray(sol["g"]).ravel()
    return Solution(tr, w, str(stats["return_status"]), bool(stats["success"]), int(stats["iter_count"]),
                    float(sol["f"]), constraint_violation(tr, w, g), seconds, build, hessian, g, tr.build_seconds, cpu)
