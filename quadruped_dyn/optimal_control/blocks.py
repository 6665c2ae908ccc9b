"""The NLP's derivatives for IPOPT, assembled from the transcription's blocks (docs/optimal_control.md, "Formulation").

Every nonlinear block of the constraints is one of a few SX Functions f evaluated at z = A w + b
(A constant and sparse, ``transcription.Piece``); the rest of g is linear (the spline's continuity
rows) and the rest of the objective quadratic. So the constraint Jacobian is J_f(z) A block by
block, and the Hessian of the Lagrangian is Q + sum A^T H_f(z) A, H_f the Hessian of
sigma * effort + lam . g of the block. Each distinct f is differentiated once, symbolically (SX);
an MX graph calls those derivatives block by block. CasADi's own derivatives of the whole NLP
(the MX graph expanded to SX) took most of the build; this builds in about a second, and each
evaluation costs what the blocks' SX derivatives cost.
"""

from __future__ import annotations

import casadi as ca

from quadruped_dyn.optimal_control.transcription import W_EFFORT, Transcription


def _derivatives(fun: ca.Function) -> tuple[ca.Function, ca.Function]:
    """(z -> J (m, nz) of g; z, lam, sigma -> H (nz, nz) of sigma * effort + lam . g) of one block Function."""
    z = ca.SX.sym("z", fun.size1_in(0))
    g, effort = fun(z)[:2]
    lam, sigma = ca.SX.sym("lam", g.shape[0]), ca.SX.sym("sigma")
    jac = ca.Function(f"jac_{fun.name()}", [z], [ca.jacobian(g, z)])
    hess = ca.Function(f"hess_{fun.name()}", [z, lam, sigma], [ca.hessian(sigma * effort + ca.dot(lam, g), z)[0]])
    return jac, hess


def derivative_functions(tr: Transcription) -> tuple[ca.Function, ca.Function]:
    """(jac_g: x, p -> g, jac_g_x; hess_lag: x, p, lam_f, lam_g -> triu_hess_gamma_x_x), nlpsol's
    signatures for its "jac_g" and "hess_lag" options."""
    assert tr.linear is not None and tr.quadratic_hessian is not None
    nw, ng = tr.lbw.size, tr.lbg.size
    w, lam_f, lam_g, p = ca.MX.sym("w", nw), ca.MX.sym("lam_f"), ca.MX.sym("lam_g", ng), ca.MX.sym("p", 0)
    derivatives: dict[str, tuple[ca.Function, ca.Function]] = {}
    rows: list[ca.MX] = []
    hessian = lam_f * tr.quadratic_hessian
    for piece in tr.pieces:
        name = piece.fun.name()
        if name not in derivatives:
            derivatives[name] = _derivatives(piece.fun)
        jac, hess = derivatives[name]
        z = ca.mtimes(piece.A, w) + piece.b
        rows.append(ca.mtimes(jac(z), piece.A))
        H = hess(z, lam_g[piece.start : piece.stop], lam_f * W_EFFORT * piece.weight_dt)
        hessian = hessian + ca.mtimes([piece.A.T, H, piece.A])
    A_lin, start = tr.linear
    if start != sum(r.shape[0] for r in rows) or start + A_lin.shape[0] != ng:
        raise AssertionError("the transcription's blocks do not tile g in order")
    g = ca.Function("g", [tr.nlp["x"]], [tr.nlp["g"]])(w)
    jac_g = ca.Function("nlp_jac_g", [w, p], [g, ca.vertcat(*rows, A_lin)], ["x", "p"], ["g", "jac_g_x"])
    hess_lag = ca.Function("nlp_hess_l", [w, p, lam_f, lam_g], [ca.triu(hessian)],
                           ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
    return jac_g, hess_lag
