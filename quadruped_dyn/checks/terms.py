"""Cross-check every symbolic term against the Pinocchio reference on random states.

Error measures per term, over all samples: ``max_abs_err`` = max |ours - reference| over
entries; ``max_rel_err`` = max over samples of that error divided by max |reference| of the
sample (the reference's infinity norm). A term passes when max_rel_err <= tol. A NaN or inf on
either side is an infinite error (``compare``): it fails, and is null in the JSON report.
"""

from __future__ import annotations

import functools
import itertools
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field

import numpy as np
import pinocchio as pin

from quadruped_dyn.checks.sample_counts import check_samples
from quadruped_dyn.dynamics.derivatives import full_derivatives
from quadruped_dyn.dynamics.grf import grf_solve, grf_solves
from quadruped_dyn.dynamics.kinematics import robot_kinematics
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced import reduced_model
from quadruped_dyn.errors import NumericalError
from quadruped_dyn.files.json import json_safe
from quadruped_dyn.math.compare import max_abs_error, relative_error, scale_of, within
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import GRF_MODELS, STANCE_SETS
from quadruped_dyn.model.state import FullState, random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference
from quadruped_dyn.tolerances import COND_ERR_FACTOR, REL_TOL_DERIVATIVES, REL_TOL_TERMS, derivative_tolerance


@dataclass
class TermResult:
    name: str
    max_abs_err: float = 0.0
    max_rel_err: float = 0.0
    tol: float = REL_TOL_TERMS  # the largest of the samples' tolerances
    passed: bool = True
    #: the largest cond(M) at which the tolerance was scaled by M's conditioning (``tolerances.derivative_tolerance``):
    #: there the term's accuracy is limited by the model, not by the code; 0 where it was not
    model_limited_cond: float = 0.0

    def add(self, ours: object, reference: object, tol: float | None = None, cond_m: float = 0.0) -> None:
        """One sample's comparison, within ``tol`` (default: the term's own), scaled at cond(M) ``cond_m``."""
        error = relative_error(ours, reference)
        self.max_abs_err = max(self.max_abs_err, max_abs_error(ours, reference))
        self.max_rel_err = max(self.max_rel_err, error)
        sample_tol = self.tol if tol is None else tol
        if tol is not None and tol > self.tol:
            self.tol, self.model_limited_cond = tol, max(self.model_limited_cond, cond_m)
        self.passed = self.passed and within(error, sample_tol)

    def fail_singular(self, cond_m: float) -> None:
        """The term could not be computed at a sample: M numerically singular there (the model's limit)."""
        self.max_abs_err = self.max_rel_err = float("inf")
        self.model_limited_cond = max(self.model_limited_cond, cond_m)
        self.passed = False


@dataclass
class CheckReport:
    robot: str
    samples: int
    seed: int
    terms: list[TermResult] = field(default_factory=list)
    grf: list[GrfResult] = field(default_factory=list)
    build_seconds: float = 0.0  # time to build the symbolic Functions (0 if this process had built them)

    @property
    def passed(self) -> bool:
        return all(t.passed for t in self.terms) and all(g.passed for g in self.grf)

    def as_dict(self) -> dict[str, object]:
        """Plain JSON types; a non-finite error is None (strict JSON has no inf)."""
        return json_safe(  # type: ignore[return-value]
            {"robot": self.robot, "samples": self.samples, "seed": self.seed, "passed": self.passed,
             "build_seconds": self.build_seconds, "terms": [asdict(t) for t in self.terms],
             "grf": [asdict(g) for g in self.grf]})

    def table(self) -> str:
        lines = [f"{'term':<28}{'max abs err':>13}{'max rel err':>13}{'tol':>9}  result"]
        for t in self.terms:
            verdict = "pass" if t.passed else "FAIL"
            if t.model_limited_cond:
                verdict += f" (accuracy limited by the model: cond(M) up to {t.model_limited_cond:.1e})"
            lines.append(f"{t.name:<28}{t.max_abs_err:>13.2e}{t.max_rel_err:>13.2e}{t.tol:>9.0e}  {verdict}")
        if self.grf:
            lines.append("")
            lines.append(f"{'GRF stance':<14}{'model':<10}{'rank':>5}{'max residual':>14}{'err vs SVD':>12}{'err vs pin':>12}"
                         f"{'max cond':>10}  result")
            for g in self.grf:
                verdict = "pass" if g.passed else "FAIL"
                lines.append(f"{g.stance:<14}{g.model:<10}{g.rank:>5}{g.max_residual:>14.2e}{g.max_err_vs_reference:>12.1e}"
                             f"{g.max_err_vs_pinocchio:>12.1e}{g.max_cond:>10.1e}  {verdict}")
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
    yield "M_full (Walker-Orin)", fd.M_full_walker_orin(q), M
    yield "M_full (CasADi AD)", fd.M_full_ad(q), M
    yield "M_full (CRBA)", fd.M_full_crba(q), M
    yield "C_full", fd.C_full(q, v), ref.nonlinear_effects(q, v) - G
    yield "G_full", fd.G_full_newton_euler(q), G
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


@dataclass
class GrfResult:
    stance: str
    model: str
    rank: int  # structural rank of the model's A
    max_residual: float = 0.0  # N / N m: the largest wrench the model could not balance
    max_err_vs_reference: float = 0.0  # relative, vs the SVD reference (lambda, residual, tau)
    max_err_vs_pinocchio: float = 0.0  # rnea - Jc^T f vs (residual, tau), relative to max(|rnea|, |Jc^T f|)
    max_cond: float = 0.0  # largest cond(A) over the samples (nonzero singular values)
    rank_mismatches: int = 0  # samples where the numeric rank differed from the structural one
    passed: bool = True


def _grf_sample(robot: Robot, ref: PinocchioReference, s: FullState, result: GrfResult) -> None:
    g = grf_solve(robot, result.stance, result.model)
    lam, f, residual, tau = (np.asarray(x, dtype=float).ravel() for x in g.function(s.q, s.v, s.a))
    r = ref.grf_solve(s.q, s.v, s.a, g.stance.feet, g.stance.selection(result.model))
    nonzero = r.singular_values[: r.rank]
    cond = float(nonzero[0] / nonzero[-1]) if nonzero.size else 1.0
    err_ref = max(relative_error(lam, r.lam), relative_error(residual, r.residual, scale_of(r.w_req)),
                  relative_error(tau, r.tau))
    R = rotation(s.q)
    rnea = ref.rnea(s.q, s.v, s.a)
    contact = ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ fi for fi in f.reshape(4, 3)])
    pin_full = rnea - contact
    # relative to the magnitude of the two terms whose difference is compared
    pin_scale = max(scale_of(rnea), scale_of(contact))
    err_pin = max(relative_error(pin_full[:6], residual, pin_scale), relative_error(pin_full[6:], tau, pin_scale))
    allowed = max(REL_TOL_TERMS, COND_ERR_FACTOR * cond * float(np.finfo(float).eps))
    result.max_residual = max(result.max_residual, max_abs_error(residual, np.zeros_like(residual)))
    result.max_err_vs_reference = max(result.max_err_vs_reference, err_ref)
    result.max_err_vs_pinocchio = max(result.max_err_vs_pinocchio, err_pin)
    result.max_cond = max(result.max_cond, cond)
    result.rank_mismatches += int(r.rank != g.rank)
    result.passed = result.passed and within(err_ref, allowed) and within(err_pin, REL_TOL_TERMS) and r.rank == g.rank


#: Reduced models checked: standing, a static-walk triple, both trot pairs.
REDUCED_STANCES = ("FL+FR+BL+BR", "FR+BL+BR", "FL+BR", "FR+BL")


def _reduced_comparisons(
    robot: Robot, ref: PinocchioReference, qj: np.ndarray, rng: np.random.Generator
) -> Iterator[tuple[str, object, object]]:
    """id_r, M_r, C_r, G_r of each reduced model against the Pinocchio-built reduced reference,
    at a trunk orientation within 0.5 rad of upright (the roll row has tan(pitch))."""
    quat = pin.Quaternion(pin.rpy.rpyToMatrix(*rng.uniform(-0.5, 0.5, 3))).coeffs()
    for stance in REDUCED_STANCES:
        m = reduced_model(robot, stance)
        feet, P = m.stance.feet, m.stance.selection("paper")
        q_r = np.concatenate([qj, [pin.rpy.matrixToRpy(pin.Quaternion(quat).toRotationMatrix())[0]]])[: m.n]
        qd, qdd, zero = rng.normal(size=m.n), rng.normal(size=m.n), np.zeros(m.n)

        def reference(qd_: np.ndarray, qdd_: np.ndarray, feet=feet, P=P, q_r=q_r) -> np.ndarray:
            return ref.reduced_inverse_dynamics(feet, P, q_r, qd_, qdd_, quat)

        G = reference(zero, zero)  # id_r is affine in qdd: the gravity-free difference gives C_r
        yield f"id_r {stance}", m.id_r(q_r, qd, qdd, quat), reference(qd, qdd)
        yield f"M_r {stance}", m.M_r(q_r, quat), ref.reduced_mass_matrix(feet, P, q_r, quat)
        yield f"C_r {stance}", m.C_r(q_r, qd, quat), reference(qd, zero) - G
        yield f"G_r {stance}", m.G_r(q_r, quat), G


def _derivative_comparisons(robot: Robot, ref: PinocchioReference, s: FullState,
                            rng: np.random.Generator) -> Iterator[tuple[str, object, object]]:
    """did_full and dfd_full (dynamics/derivatives.py; d/dq along pinocchio.integrate) against
    Pinocchio's analytical derivatives, computeRNEADerivatives and computeABADerivatives."""
    d, pd = full_derivatives(robot), PinocchioDerivatives(ref)
    for k, (ours, theirs) in enumerate(zip(d.did_full(s.q, s.v, s.a), pd.rnea_derivatives(s.q, s.v, s.a))):
        yield f"did_full {('dtau_dq', 'dtau_dv', 'dtau_da')[k]}", ours, theirs
    tau = rng.normal(scale=10.0, size=18)
    for name, ours, theirs in zip(DFD_FULL_TERMS, d.dfd_full(s.q, s.v, tau), pd.aba_derivatives(s.q, s.v, tau)):
        yield name, ours, theirs


DFD_FULL_TERMS = ("dfd_full da_dq", "dfd_full da_dv", "dfd_full da_dtau")


#: Symbolic models the check builds before its first sample (``run_check``'s ``building`` counts them).
N_MODELS = 4 + len(REDUCED_STANCES)


def run_check(robot: Robot, samples: int = 20, seed: int = 0, progress: Callable[[int], None] | None = None,
              building: Callable[[int], None] | None = None) -> CheckReport:
    """Every term against Pinocchio on ``samples`` random states; ``progress(n)`` after the n-th
    state, ``building(k)`` after the k-th of the N_MODELS symbolic models is built (minutes on a
    cold process: built once per robot and process). InputError unless ``check_samples`` accepts ``samples``."""
    check_samples(samples)
    ref = PinocchioReference(robot)
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    builds: list[Callable[[], object]] = [lambda: full_dynamics(robot), lambda: robot_kinematics(robot),
                                          lambda: grf_solves(robot), lambda: full_derivatives(robot)]
    builds += [functools.partial(reduced_model, robot, stance) for stance in REDUCED_STANCES]
    for k, build in enumerate(builds):
        build()
        if building:
            building(k + 1)
    report = CheckReport(robot.name, samples, seed, build_seconds=time.perf_counter() - start)
    terms: dict[str, TermResult] = {}
    report.grf = [GrfResult(st.name, m, st.rank(m)) for st in STANCE_SETS for m in GRF_MODELS]
    for n in range(samples):
        s = random_state(robot.lower, robot.upper, rng)
        comparisons = itertools.chain(_comparisons(robot, ref, s), _reduced_comparisons(robot, ref, s.q[7:], rng),
                                      _derivative_comparisons(robot, ref, s, rng))
        cond_m = float(np.linalg.cond(ref.mass_matrix(s.q)))
        try:
            for name, ours, theirs in comparisons:
                derivative = name.startswith(("did_full", "dfd_full"))
                term = terms.setdefault(name, TermResult(name, tol=REL_TOL_DERIVATIVES if derivative else REL_TOL_TERMS))
                term.add([np.asarray(x, dtype=float) for x in ours] if isinstance(ours, list) else ours, theirs,
                         derivative_tolerance(name, cond_m) if derivative else None, cond_m)
        except NumericalError:  # dfd_full where M is numerically singular: the model's limit, reported as such
            for name in DFD_FULL_TERMS:
                terms.setdefault(name, TermResult(name, tol=REL_TOL_DERIVATIVES)).fail_singular(cond_m)
        for result in report.grf:
            _grf_sample(robot, ref, s, result)
        if progress:
            progress(n + 1)
    report.terms = list(terms.values())
    return report
