"""The block-assembled derivatives IPOPT gets equal CasADi's own derivatives of the whole NLP."""

from __future__ import annotations

import casadi as ca
import numpy as np

from quadruped_dyn.experiment.gait import TROT
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.optimal_control.blocks import derivative_functions
from quadruped_dyn.optimal_control.transcription import Options, transcribe

#: Two summation orders of the same products: round-off relative to the largest entry.
REL_TOL = 1e-12


def test_block_derivatives_match_casadi_whole_graph(paper: Robot) -> None:
    tr = transcribe(paper, TROT, Options(nodes_per_phase=3, interior_points=(0.5,)))
    jac_g, hess_lag = derivative_functions(tr)
    w = tr.nlp["x"]
    rng = np.random.default_rng(1)
    x = tr.w0 + 0.01 * rng.normal(size=tr.w0.size)  # off the plan: every term nonzero
    lam, sigma = rng.normal(size=tr.lbg.size), 0.7
    g, J = jac_g(x, [])
    J_ref = ca.Function("J", [w], [ca.jacobian(tr.nlp["g"], w)])(x)
    lagrangian = sigma * tr.nlp["f"] + ca.dot(ca.MX(lam), tr.nlp["g"])
    H_ref = np.triu(np.asarray(ca.DM(ca.Function("H", [w], [ca.hessian(lagrangian, w)[0]])(x))))
    J, J_ref, H = np.asarray(ca.DM(J)), np.asarray(ca.DM(J_ref)), np.asarray(ca.DM(hess_lag(x, [], sigma, lam)))
    for got, ref in ((J, J_ref), (H, H_ref)):
        assert np.all(np.isfinite(got)) and np.abs(ref).max() > 0
        assert np.abs(got - ref).max() <= REL_TOL * np.abs(ref).max()
    assert np.abs(np.asarray(g).ravel() - np.asarray(ca.Function("g", [w], [tr.nlp["g"]])(x)).ravel()).max() == 0.0
