"""The trunk pose from the stance feet (the reduced coordinates' pose reconstruction)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError


def pose_from_feet(
    r_b: np.ndarray, P_w: np.ndarray, roll: float | None = None, pitch_hint: float = 0.0
) -> tuple[np.ndarray, np.ndarray, float]:
    """Trunk pose (R, p) that best puts the body-frame foot points r_b (k, 3) on the world
    footholds P_w (k, 3), and the closure error: max_i |R r_i + p - P_i| (m), how far the
    stance legs are from reaching their footholds.

    Three or four feet: least-squares rigid fit (Kabsch, proper rotation). Two feet: R =
    Rz(psi) Ry(theta) Rx(roll) with R (r_1 - r_2) parallel to P_1 - P_2 (closed form; the
    roll is the trot's coordinate; of the two pitch solutions the one nearer ``pitch_hint``,
    e.g. the previous step's pitch, is taken)."""
    r_b, P_w = np.atleast_2d(np.asarray(r_b, dtype=float)), np.atleast_2d(np.asarray(P_w, dtype=float))
    k = r_b.shape[0]
    if k >= 3:
        rc, Pc = r_b - r_b.mean(axis=0), P_w - P_w.mean(axis=0)
        U, _, Vt = np.linalg.svd(rc.T @ Pc)
        D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
        R = Vt.T @ D @ U.T
    elif k == 2 and roll is not None:
        c, s = np.cos(roll), np.sin(roll)
        u = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]) @ (r_b[0] - r_b[1])
        d = (P_w[0] - P_w[1]) / np.linalg.norm(P_w[0] - P_w[1]) * np.linalg.norm(u)
        rho, beta = np.hypot(u[0], u[2]), np.arctan2(u[0], u[2])
        base = np.arccos(np.clip(d[2] / rho, -1.0, 1.0))
        theta = min((base - beta, -base - beta),
                    key=lambda x: abs(np.arctan2(np.sin(x - pitch_hint), np.cos(x - pitch_hint))))
        w = np.array([u[0] * np.cos(theta) + u[2] * np.sin(theta), u[1]])
        psi = np.arctan2(d[1], d[0]) - np.arctan2(w[1], w[0])
        R = pin.rpy.rpyToMatrix(roll, theta, psi)
    else:
        raise InputError(f"a trunk pose needs 3 or 4 stance feet, or 2 and the roll angle; got {k} feet")
    p = P_w.mean(axis=0) - R @ r_b.mean(axis=0)
    closure = float(np.abs(np.linalg.norm(r_b @ R.T + p - P_w, axis=1)).max())
    return R, p, closure
