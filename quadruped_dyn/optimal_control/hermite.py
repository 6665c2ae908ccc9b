"""Piecewise quintic Hermite trajectories: the transcription's representation of the motion.

Between two nodes t_k, t_k + h the motion is the quintic that takes the value, rate and
acceleration (y, y', y'') at both ends: any node values define a C^2 trajectory, so the
transcription needs no continuity constraints, and the torques of the reduced inverse dynamics
along it are continuous within a phase. With s = (t - t_k) / h in [0, 1]:
  y(s) = H0 y_0 + h H1 y'_0 + h^2 H2 y''_0 + H3 y_1 + h H4 y'_1 + h^2 H5 y''_1.
"""

from __future__ import annotations

import numpy as np

#: Rows: H0..H5 as polynomials in s, coefficients of s^0..s^5.
BASIS = np.array([
    [1, 0, 0, -10, 15, -6],
    [0, 1, 0, -6, 8, -3],
    [0, 0, 0.5, -1.5, 1.5, -0.5],
    [0, 0, 0, 10, -15, 6],
    [0, 0, 0, -4, 7, -3],
    [0, 0, 0, 0.5, -1, 0.5],
])


def weights(s: float, h: float) -> np.ndarray:
    """(3, 6): the weights of (y_0, y'_0, y''_0, y_1, y'_1, y''_1) in y, y', y'' at fraction s
    of an interval of length h."""
    powers = np.array([[s**j for j in range(6)],
                       [j * s ** (j - 1) if j >= 1 else 0.0 for j in range(6)],
                       [j * (j - 1) * s ** (j - 2) if j >= 2 else 0.0 for j in range(6)]])
    W = powers @ BASIS.T  # (3, 6): d^m/ds^m of each basis function
    scale = np.array([1.0, h, h**2, 1.0, h, h**2])
    return W * scale / np.array([[1.0], [h], [h**2]])


def interpolate(y0: tuple, y1: tuple, s: float, h: float) -> tuple:
    """(y, y', y'') at fraction s from end values y0 = (y, y', y'') and y1 (arrays or CasADi
    expressions of one shape)."""
    W = weights(s, h)
    ends = (*y0, *y1)
    return tuple(sum(float(W[m, j]) * ends[j] for j in range(6)) for m in range(3))
