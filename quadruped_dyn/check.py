"""Cross-check every symbolic term against the Pinocchio reference on random states.

Error measures per term, over all samples: ``max_abs_err`` = max |ours - reference| over
entries; ``max_rel_err`` = max over samples of that error divided by max |reference| of the
sample (the reference's infinity norm). A term passes when max_rel_err <= tol.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field

import numpy as np

from .kinematics import robot_kinematics
from .newton_euler import full_dynamics
from .pinocchio_ref import PinocchioReference
from .robot import Robot
from .state import FullState, random_state, rotation
from .tolerances import REL_TOL_TERMS


@dataclass
class TermResult:
    name: str
    max_abs_err: float = 0.0
    max_rel_err: float = 0.0
    tol: float = REL_TOL_TERMS
    passed: bool = True

    def add(self, ours: object, reference: object) -> None:
        ours_arr = np.asarray(ours, dtype=float).squeeze()
        ref_arr = np.asarray(reference, dtype=float).squeeze()
        if ours_arr.shape != ref_arr.shape:
            raise AssertionError(f"{self.name}: shape {ours_arr.shape} vs reference {ref_arr.shape}")
        err = float(np.abs(ours_arr - ref_arr).max())
        scale = float(np.abs(ref_arr).max()) or 1.0
        self.max_abs_err = max(self.max_abs_err, err)
        self.max_rel_err = max(self.max_rel_err, err / scale)
        self.passed = bool(self.max_rel_err <= self.tol)


@dataclass
class CheckReport:
    robot: str
    samples: int
    seed: int
    terms: list[TermResult] = field(default_factory=list)
    build_seconds: float = 0.0  # time to build the symbolic Functions

    @property
    def passed(self) -> bool:
        return all(t.passed for t in self.terms)

    def as_dict(self) -> dict[str, object]:
        return {"robot": self.robot, "samples": self.samples, "seed": self.seed, "passed": self.passed,
                "build_seconds": self.build_seconds, "terms": [asdict(t) for t in self.terms]}

    def table(self) -> str:
        lines = [f"{'term':<28}{'max abs err':>13}{'max rel err':>13}{'tol':>9}  result"]
        for t in self.terms:
            verdict = "pass" if t.passed else "FAIL"
            lines.append(f"{t.name:<28}{t.max_abs_err:>13.2e}{t.max_rel_err:>13.2e}{t.tol:>9.0e}  {verdict}")
        verdict = "all terms pass" if self.passed else "SOME TERMS FAIL"
        lines.append(f"{self.robot}: {len(self.terms)} terms on {self.samples} random states (seed {self.seed}), "
                     f"symbolic build {self.build_seconds:.2f} s: {verdict}")
        return "\n".join(lines)


def _comparisons(robot: Robot, ref: PinocchioReference, s: FullState) -> Iterator[tuple[str, object, object]]:
    """(term name, ours, Pinocchio's) for one state."""
    fd = full_dynamics(robot)
    kin = robot_kinematics(robot)
    q, v, a = s.q, s.v, s.a
    qj, vj = q[7:], v[6:]
    M = ref.mass_matrix(q)
    G = ref.gravity(q)
    yield "M_full (Walker-Orin)", fd.M_full(q), M
    yield "M_full (CasADi AD)", fd.M_full_ad(q), M
    yield "C_full", fd.C_full(q, v), ref.nonlinear_effects(q, v) - G
    yield "G_full", fd.G_full(q), G
    yield "coriolis_matrix", fd.coriolis(q, v), ref.coriolis_matrix(q, v)
    R = rotation(q)
    forces_w = np.concatenate([R @ fi for fi in s.f])
    expected = ref.rnea(q, v, a) - ref.contact_jacobian(q, (0, 1, 2, 3)).T @ forces_w
    w_res, tau = fd.id_full(q, v, a, s.f.ravel())
    yield "id_full tau", tau, expected[6:]
    yield "id_full base residual", w_res, expected[:6]
    yield "foot positions", [k.foot_position(qj[3 * i : 3 * i + 3]) for i, k in enumerate(kin)], ref.foot_positions(q)
    yield "foot Jacobians", [k.foot_jacobian(qj[3 * i : 3 * i + 3]) for i, k in enumerate(kin)], ref.foot_jacobians(q)
    yield (
        "foot Jdot qdot",
        [k.foot_bias_acceleration(qj[3 * i : 3 * i + 3], vj[3 * i : 3 * i + 3]) for i, k in enumerate(kin)],
        ref.foot_bias_accelerations(q, v),
    )


def run_check(robot: Robot, samples: int = 20, seed: int = 0,
              progress: Callable[[int], None] | None = None) -> CheckReport:
    ref = PinocchioReference(robot)
    rng = np.random.default_rng(seed)
    report = CheckReport(robot.name, samples, seed, build_seconds=full_dynamics(robot).build_seconds)
    terms: dict[str, TermResult] = {}
    for n in range(samples):
        s = random_state(robot.lower, robot.upper, rng)
        for name, ours, theirs in _comparisons(robot, ref, s):
            term = terms.setdefault(name, TermResult(name))
            term.add([np.asarray(x, dtype=float) for x in ours] if isinstance(ours, list) else ours, theirs)
        if progress:
            progress(n + 1)
    report.terms = list(terms.values())
    return report
