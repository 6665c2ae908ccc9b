"""The plan's target and id_r's torques as one polynomial interpolant per gait phase.

Within one phase the stance is fixed and the plan is a smooth function of t (quintic and
sextic polynomials of the phase fraction for a swing foot, constants for stance feet, a
trigonometric sway for the trunk), and so are the IK and id_r along it (analytic away from
the legs' singularities). The integrators ask for the target at tens of thousands of times
per run; evaluating the IK and id_r there from Python was most of a ``validate`` run's time.
``IkTorqueTable`` evaluates them exactly at the Chebyshev-Lobatto points of each phase
(``CHEB_DEGREE`` + 1 points, shared by every run of the experiment) and answers every other time
by barycentric interpolation (forward stable on these points), in a few microseconds.

The interpolant is accepted for a phase only after it has been checked at the midpoints between
its nodes (independent of the nodes, where the interpolation error of a Chebyshev interpolant
peaks): every component within ``TABLE_REL_TOL`` of that signal's largest magnitude over the
phase, or -- where the exact evaluation's own round-off is above that -- a difference that no
longer shrinks when the degree doubles (``NOISE_FLOOR_RATIO``) and is within ``TABLE_NOISE_TOL``.
A phase that fails at ``CHEB_MAX_DEGREE`` falls back to the exact evaluation. At the
nodes (t = a phase's start included) the exact values are returned.
"""

from __future__ import annotations

import numpy as np

from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.plan_ik import IkTarget
from quadruped_dyn.experiment.simulate import IkTorques, ReducedDynamics
from quadruped_dyn.tolerances import TABLE_NOISE_TOL, TABLE_REL_TOL

#: Polynomial degree per phase to start with, doubled until the check passes.
CHEB_DEGREE = 64
CHEB_MAX_DEGREE = 256

#: Doubling the degree shrinks a Chebyshev interpolant's error of a smooth signal by orders of
#: magnitude; a midpoint difference that shrinks by less than this factor is the exact
#: evaluation's own round-off (see ``TABLE_NOISE_TOL``).
NOISE_FLOOR_RATIO = 0.5


class _Phase:
    """Values (m + 1, c) at the Chebyshev-Lobatto points of [t0, t1] and their barycentric weights."""

    def __init__(self, t0: float, t1: float, degree: int, values: np.ndarray, nodes: np.ndarray) -> None:
        self.t0, self.t1, self.nodes, self.values = t0, t1, nodes, values
        w = (-1.0) ** np.arange(degree + 1)
        w[0] *= 0.5
        w[-1] *= 0.5
        self.weights = w

    def __call__(self, t: float) -> np.ndarray:
        d = t - self.nodes
        hit = np.flatnonzero(d == 0.0)
        if hit.size:
            return self.values[hit[0]]
        c = self.weights / d
        return (c @ self.values) / c.sum()


def lobatto(t0: float, t1: float, degree: int) -> np.ndarray:
    """Chebyshev-Lobatto points of [t0, t1] in increasing order, the ends exactly t0 and t1."""
    x = -np.cos(np.pi * np.arange(degree + 1) / degree)
    nodes = t0 + (t1 - t0) * (x + 1.0) / 2.0
    nodes[0], nodes[-1] = t0, t1
    return nodes


class IkTorqueTable(IkTorques):
    """``IkTorques`` answered from a per-phase interpolant (see the module docstring); the
    exact evaluation stays available as ``exact``."""

    def __init__(self, plan: Plan, dynamics: ReducedDynamics) -> None:
        super().__init__(plan, dynamics)
        self.n = plan.gait.n_coords
        self._phases: dict[tuple[int, tuple[int, ...]], _Phase | None] = {}
        self.max_rel_error = 0.0  # the largest checked midpoint error, relative to each signal's scale
        self.degrees: list[int] = []

    def exact(self, t: float, stance: tuple[int, ...]) -> tuple[IkTarget, np.ndarray]:
        return super().__call__(t, stance)

    def exact_many(self, ts: np.ndarray, stances: list[tuple[int, ...]]) -> list[tuple[IkTarget, np.ndarray]]:
        return super().many(ts, stances)

    def _stack(self, ts: np.ndarray, stance: tuple[int, ...]) -> np.ndarray:
        """(len(ts), 3 n + n_tau): q_r, qd_r, qdd_r and id_r at each time, exactly."""
        return np.array([np.concatenate([target.q_r, target.qd_r, target.qdd_r, tau])
                         for target, tau in self.exact_many(ts, [stance] * len(ts))])

    def _build(self, k: int, stance: tuple[int, ...]) -> _Phase | None:
        h = self.plan.gait.phase_duration
        t0, t1 = k * h, (k + 1) * h
        degree = CHEB_DEGREE
        previous = np.inf
        while degree <= CHEB_MAX_DEGREE:
            nodes = lobatto(t0, t1, degree)
            values = self._stack(nodes, stance)
            phase = _Phase(t0, t1, degree, values, nodes)
            mids = 0.5 * (nodes[:-1] + nodes[1:])
            exact = self._stack(mids, stance)
            approx = np.array([phase(float(t)) for t in mids])
            scale = np.maximum(np.abs(values).max(axis=0), np.abs(exact).max(axis=0))
            signal_scale = np.concatenate([np.full(self.n, scale[i * self.n : (i + 1) * self.n].max())
                                           for i in range(3)] + [np.full(len(scale) - 3 * self.n, scale[3 * self.n :].max())])
            rel = float((np.abs(approx - exact) / np.where(signal_scale > 0, signal_scale, 1.0)).max())
            at_noise_floor = rel > NOISE_FLOOR_RATIO * previous and rel <= TABLE_NOISE_TOL
            if rel <= TABLE_REL_TOL or at_noise_floor:
                self.max_rel_error = max(self.max_rel_error, rel)
                self.degrees.append(degree)
                return phase
            previous = rel
            degree *= 2
        return None

    def phase(self, k: int, stance: tuple[int, ...]) -> _Phase | None:
        """The interpolant of the plan's phase k (None: it falls back to the exact evaluation)."""
        key = (k, stance)
        if key not in self._phases:
            self._phases[key] = self._build(k, stance)
        return self._phases[key]

    def __call__(self, t: float, stance: tuple[int, ...]) -> tuple[IkTarget, np.ndarray]:
        h = self.plan.gait.phase_duration
        k = int(np.floor(t / h + 1e-12))
        if k > 0 and abs(t - k * h) <= 1e-12 * max(1.0, t) and self.plan.stance(k * h + 0.5 * h) != stance:
            k -= 1  # a step that ends on a switch keeps its phase's stance
        phase = self.phase(k, stance)
        if phase is None:
            return self.exact(t, stance)
        v = phase(t)
        n = self.n
        return IkTarget(v[:n], v[n : 2 * n], v[2 * n : 3 * n], stance), v[3 * n :]
