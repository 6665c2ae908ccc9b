"""The paper's validation experiment, compared and reported (docs/experiment.md, paper Figs. 5-7).

Plan (``gait``) -> IK plan (``ik_target``) -> id_r -> tau(t) -> reduced forward dynamics
(``simulate``) -> compared with the IK plan, per joint:
percentage error of a signal x = max_t |x_sim - x_ref| / max_t |x_ref| x 100 (None where the
target is identically zero, e.g. HAA rates of a straight trot).

Runs of the reduced model (all from the IK state at t = 0, on the stance closure):
* ``paper``: tau_ext = all of id_r (for two feet the roll moment too, as if actuated): the
  paper's check, the inverse/forward pair against itself;
* ``physical`` (gaits with a roll coordinate): the roll unactuated, as on a robot;
* a twin of ``paper`` with every initial coordinate one ulp up, and a ``coarse`` run at
  ``TRUNCATION_RTOL_FACTOR`` x the tolerance (DOP853) or a ``refined`` run at half the step (RK4):
  the instability and the error budget. ``growth_rate_per_s`` is the slope of ln |twin - paper|
  (largest joint angle, running maximum) over the second half of the run; ``roundoff_pct`` =
  % difference twin vs paper (what one ulp of noise grows to: the run's own round-off enters at
  every step and is larger, 2.6x on go2's walk against a long-double run), ``truncation_pct`` = the
  integrator's own error: % difference coarse vs paper / (factor - 1) (DOP853's error is
  proportional to its tolerance, ``simulate.TRUNCATION_RTOL_FACTOR``), refined vs paper (RK4).

Physics check (``rigid_contact``): the same torque laws drive the full-coordinate rigid-contact
dynamics and the reduced model with the roll unactuated: IK torques, IK torques + 1 %, and
IK torques + 1 % with joint PD feedback. Departure = largest joint-angle difference (rad), time
to 1 % = first time it exceeds 1 % of the target's largest |joint angle|.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from quadruped_dyn.codegen.emit import reduced_symbol
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
from quadruped_dyn.codegen.reduced_library import CompiledReducedDynamics
from quadruped_dyn.dynamics.guarded import guarded_call
from quadruped_dyn.dynamics.reduced import reduced_maps
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Gait, Plan, gait_plan, support_margin
from quadruped_dyn.experiment.native_run import NativeRuns
from quadruped_dyn.experiment.rigid_contact import simulate_rigid
from quadruped_dyn.experiment.simulate import (
    IDENTITY_QUAT,
    RTOL,
    TRUNCATION_RTOL_FACTOR,
    IkTorques,
    ReducedDynamics,
    Run,
    TorqueLaw,
    check_times,
    simulate_reduced,
)
from quadruped_dyn.experiment.torque_table import IkTorqueTable
from quadruped_dyn.model.leg import JOINT_ROLES
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.model.state import GRAVITY_W

#: A target signal whose largest |value| is below this fraction of the largest joint's is
#: treated as identically zero (IK round-off, ~1e-16 rad/s, would give absurd percentages).
ZERO_SIGNAL = 1e-9

#: Joint PD gains of the physics check's feedback run, per kg of robot mass: the paper robot
#: (10 kg) gets 30 N m/rad and 1.5 N m s/rad -- stiff enough to hold a leg against its weight,
#: soft enough to leave the models' difference visible.
PD_KP_PER_KG = 3.0  # N m / rad / kg
PD_KD_PER_KG = 0.15  # N m s / rad / kg

#: Static-stability samples along the target (f_z of the paper's GRF model, CoM margin), s.
STABILITY_DT = 5e-3

#: The departure threshold, % of the target's largest |joint angle|.
DEPARTURE_PCT = 1.0

#: A comparison needs at least this many samples: the first (t = 0) agrees with IK by
#: construction (every run starts from the IK state), so a run that stopped on its first step
#: compared one sample and would report 0 % error.
MIN_COMPARED_SAMPLES = 2

SIGNALS = ("q", "qd", "qdd")


@dataclass
class Experiment:
    """Everything one ``validate`` call simulated: target samples and runs on one time grid."""

    plan: Plan
    ik: IkTorques  # the target and id_r's torques along it
    target: dict[str, np.ndarray]  # "t" -> (N,) grid, signal -> (N, n) IK values on it
    runs: dict[str, Run] = field(default_factory=dict)  # reduced model
    rigid: dict[str, Run] = field(default_factory=dict)  # rigid-contact dynamics, 12 joints
    engines: set[str] = field(default_factory=set)  # how the DOP853 runs were integrated: "native", "python"


def joint_names(robot: Robot) -> list[str]:
    """Project joint labels, e.g. FL_HAA (FL, FR, BL, BR x HAA, HFE, KFE)."""
    return [f"{leg.label}_{role}" for leg in robot.legs for role in JOINT_ROLES]


def percent_errors(sim: np.ndarray, target: np.ndarray) -> list[float | None]:
    """Per joint: max_t |sim - target| / max_t |target| x 100 over the rows both have; None for a
    target below ZERO_SIGNAL of the largest joint's, or over fewer than MIN_COMPARED_SAMPLES
    rows (a run that stopped on its first step: no comparison, not 0 %)."""
    m = min(len(sim), len(target))
    if m < MIN_COMPARED_SAMPLES:
        return [None] * target.shape[1]
    scale = np.abs(target[:m]).max(axis=0)
    err = np.abs(sim[:m] - target[:m]).max(axis=0)
    return [float(e / s * 100) if s > ZERO_SIGNAL * scale.max() else None for e, s in zip(err, scale)]


def _worst(values: list[float | None]) -> float | None:
    finite = [v for v in values if v is not None]
    return max(finite) if finite else None


def departure(t: np.ndarray, q_a: np.ndarray, q_b: np.ndarray, scale: float) -> tuple[np.ndarray, float | None]:
    """(largest joint-angle difference per sample (rad), first time it exceeds DEPARTURE_PCT %
    of ``scale``, or None)."""
    m = min(len(q_a), len(q_b))
    d = np.abs(q_a[:m, :12] - q_b[:m, :12]).max(axis=1)
    over = np.flatnonzero(d > DEPARTURE_PCT / 100 * scale)
    return d, (float(t[over[0]]) if over.size else None)


def growth_rate(t: np.ndarray, d: np.ndarray) -> float | None:
    """Slope (1/s) of ln(running max of d) over the second half of t: how fast a difference
    grows along the target. None when d stays zero."""
    if d.size < 4 or not np.any(d > 0):
        return None
    envelope = np.maximum.accumulate(d)
    half = (t >= t[-1] / 2) & (envelope > 0)
    if half.sum() < 2:
        return None
    return float(np.polyfit(t[half], np.log(envelope[half]), 1)[0])


def _series(t: np.ndarray, d: np.ndarray, every: float = 0.1) -> list[list[float]]:
    """[[t, d]] every ``every`` seconds (the JSON's departure-over-time)."""
    idx = np.unique(np.searchsorted(t, np.arange(0.0, t[-1] + 1e-9, every))) if t.size else np.zeros(0, int)
    return [[round(float(t[i]), 6), float(d[i])] for i in idx if i < len(d)]


def static_stability(plan: Plan, ik: IkTorques, horizon: float, dt: float = STABILITY_DT) -> dict[str, Any]:
    """Along the target: smallest f_z (N) of the paper's GRF model on any stance foot, and
    smallest CoM margin (m) inside the support triangle (three or more feet; Pinocchio's CoM),
    sampled every ``dt`` (s). The forces come from the generated ``qd_grf_<stance>`` (the
    paper's model; the trunk is level, so trunk frame = world), which does not check the foot
    layout as ``GrfSolve.solve`` does: a plan's stance feet are never collinear."""
    import pinocchio as pin

    from quadruped_dyn.references.pinocchio import PinocchioReference

    robot = plan.robot
    pin_ref = PinocchioReference(robot)
    library = compiled_library(robot)
    grf: dict[str, CompiledFunction] = {}
    min_fz, min_margin = np.inf, np.inf
    at_fz = at_margin = 0.0
    for t in np.arange(0.0, horizon + 1e-9, dt):
        stance = plan.stance(float(t))
        target, _ = ik(float(t), stance)
        name = StanceSet(stance).name
        v, a = guarded_call(reduced_maps(robot, name), target.q_r, target.qd_r, target.qdd_r, IDENTITY_QUAT)
        q = np.concatenate([plan.trunk(float(t))[0], IDENTITY_QUAT, target.q_r[:12]])
        if name not in grf:
            grf[name] = CompiledFunction(library, reduced_symbol("grf", StanceSet(stance)))
        f_body = grf[name](q, v, a)[1].reshape(4, 3)[list(stance)]
        fz = float(f_body[:, 2].min())
        if fz < min_fz:
            min_fz, at_fz = fz, float(t)
        if len(stance) >= 3:
            com = pin.centerOfMass(robot.model, pin_ref.data, pin_ref.pin_q(q))
            margin = support_margin(com[:2], plan.footholds(float(t), stance))
            if margin < min_margin:
                min_margin, at_margin = margin, float(t)
    return {
        "min_fz_N": min_fz, "min_fz_at_s": at_fz, "weight_N": float(robot.total_mass * -GRAVITY_W[2]),
        "min_com_margin_m": None if min_margin == np.inf else float(min_margin),
        "min_com_margin_at_s": None if min_margin == np.inf else at_margin,
    }


def pd_gains(robot: Robot) -> tuple[float, float]:
    return PD_KP_PER_KG * robot.total_mass, PD_KD_PER_KG * robot.total_mass


ENGINES = ("native", "python")


def run_experiment(robot: Robot, gait: Gait, dynamics: ReducedDynamics, horizon: float, dt: float,
                   integrator: str = "dop853", physics: bool = True,
                   progress: Callable[[float], None] | None = None, engine: str = "native",
                   twin_ulps: int = 1) -> Experiment:
    """Every run ``validate`` reports (see the module docstring); ``progress`` gets the
    simulated seconds of each finished stretch. ``engine``: "native" integrates DOP853 runs of
    the generated C backend one gait phase per C call (``native_run``), "python" through scipy
    (the baseline the native runs are tested against); RK4 runs and the CasADi backend always
    take the Python path. ``twin_ulps``: the twin's initial perturbation, ulps up in every coordinate (1, what
    ``validate`` reports: what one ulp of noise grows to; more, the perturbation stands above the round-off both runs
    accumulate, and the twin's departure measures the dominant mode's growth rate alone)."""
    if engine not in ENGINES:
        raise InputError(f"unknown engine '{engine}'; expected one of {', '.join(ENGINES)}")
    check_times(gait, horizon, dt, integrator)
    plan = gait_plan(robot, gait)
    ik = IkTorqueTable(plan, dynamics)  # the runs' target torques; the compared target stays exact
    native = None
    if engine == "native" and integrator == "dop853" and isinstance(dynamics, CompiledReducedDynamics):
        native = NativeRuns(robot)
    done = [0.0]

    def tick(t: float) -> None:  # per-run progress -> total seconds simulated
        if progress:
            progress(t - done[0] if t > done[0] else t)
            done[0] = t if t < horizon - 1e-9 else 0.0

    def reduced(law: TorqueLaw, **kw: Any) -> Run:
        run = native.reduced(plan, ik, law, horizon, dt, progress=tick, **kw) if native else None
        exp.engines.add("native" if run else "python")
        return run or simulate_reduced(plan, dynamics, law, horizon, dt, integrator, ik=ik, progress=tick, **kw)

    def rigid(law: TorqueLaw) -> Run:
        run = native.rigid(plan, ik, law, horizon, dt, progress=tick) if native else None
        exp.engines.add("native" if run else "python")
        return run or simulate_rigid(plan, ik, law, horizon, dt, integrator, progress=tick)

    paper = TorqueLaw("paper", roll_applied=True)
    exp = Experiment(plan, ik, {})
    exp.runs["paper"] = reduced(paper)
    exp.runs["twin"] = reduced(paper, initial_ulps=twin_ulps)
    if integrator == "rk4":
        exp.runs["refined"] = simulate_reduced(plan, dynamics, paper, horizon, dt / 2, "rk4", ik=ik, progress=tick)
    else:
        exp.runs["coarse"] = reduced(paper, rtol=TRUNCATION_RTOL_FACTOR * RTOL)
    unactuated = TorqueLaw("ik")
    if gait.n_coords == 13:
        exp.runs["physical"] = reduced(unactuated)
    if physics:
        kp, kd = pd_gains(robot)
        laws = [unactuated, TorqueLaw("plus_1pct", scale=1.01), TorqueLaw("pd", scale=1.01, kp=kp, kd=kd)]
        for law in laws:
            if law.name != "ik":
                exp.runs[law.name] = reduced(law)
            exp.rigid[law.name] = rigid(law)
    # the planned grid, also when the 'paper' run stopped early (its own times would shrink the target)
    grid = np.arange(int(np.floor(horizon / dt + 1e-9)) + 1) * dt
    targets = [target for target, _ in ik.exact_many(grid, [plan.stance(float(t)) for t in grid])]
    exp.target = {"t": grid, "q": np.array([r.q_r for r in targets]), "qd": np.array([r.qd_r for r in targets]),
                     "qdd": np.array([r.qdd_r for r in targets])}
    return exp


def _run_summary(run: Run, target: dict[str, np.ndarray], scale: float) -> dict[str, Any]:
    _, departs = departure(run.t, run.q, target["q"], scale)
    return {"stopped_at_s": run.stopped_at, "departs_1pct_at_s": departs,
            "max_closure_m": float(run.closure_m.max()) if run.closure_m.size else None,
            "rhs_evaluations": run.rhs_evaluations,
            **{f"max_pct_err_{s}": _worst(percent_errors(getattr(run, s)[:, :12], target[s][:, :12])) for s in SIGNALS}}


def report(exp: Experiment, integrator: str, dt: float, backend: str, stability: dict[str, Any]) -> dict[str, Any]:
    """The JSON report (the keys of docs/results.md's experiment, plus the runs' details)."""
    plan, target = exp.plan, exp.target
    names = joint_names(plan.robot)
    horizon = float(target["t"][-1])
    scale = float(np.abs(target["q"][:, :12]).max())
    paper, twin = exp.runs["paper"], exp.runs["twin"]
    errors = {s: percent_errors(getattr(paper, s)[:, :12], target[s][:, :12]) for s in SIGNALS}
    d_twin, _ = departure(paper.t, paper.q, twin.q, scale)
    budget = {}
    for s in SIGNALS:
        r = target[s][:, :12]
        m = min(len(twin.t), len(paper.t), len(r))  # runs that stopped early have fewer samples
        budget[s] = {"total_pct": _worst(errors[s]),
                     "roundoff_pct": _worst(percent_errors(getattr(twin, s)[:m, :12] - getattr(paper, s)[:m, :12] + r[:m],
                                                           r[:m])),
                     "truncation_pct": _worst(truncation(exp, s, r))}
    dop853 = {"native": "DOP853 (scipy's coefficients and step control, in C)", "python": "DOP853 (scipy)"}
    name = " / ".join(dop853[e] for e in sorted(exp.engines)) or dop853["python"]
    method = (f"{name}, rtol = atol = {RTOL:g}, sampled every {dt:g} s" if integrator == "dop853"
              else f"classical RK4, fixed step {dt:g} s")
    out: dict[str, Any] = {
        "robot": plan.robot.name, "gait": plan.gait.name, "horizon_s": horizon, "backend": backend,
        "engine": "+".join(sorted(exp.engines)),
        "compared_samples": compared_samples(exp), "compared_until_s": float(target["t"][compared_samples(exp) - 1])
        if compared_samples(exp) else None,
        "integrator": method + "; restarted at every stance switch; state projected onto the stance closure after "
                      "every step",
        "max_pct_err": {n: {s: errors[s][j] for s in SIGNALS} for j, n in enumerate(names)},
        "max_pct_err_overall": {s: _worst(errors[s]) for s in SIGNALS},
        "instability": {"growth_rate_per_s": growth_rate(paper.t[: len(d_twin)], d_twin),
                        "one_ulp_grows_to_rad": float(d_twin[-1]) if d_twin.size else None,
                        "error_budget": budget},
        "static_stability": stability,
        "runs": {name: _run_summary(run, target, scale) for name, run in exp.runs.items()},
    }
    if exp.rigid:
        out["physics_check"] = physics_check(exp, scale)
    return out


def compared_samples(exp: Experiment) -> int:
    """Samples over which the 'paper' run is compared with IK (fewer than MIN_COMPARED_SAMPLES:
    no result)."""
    return min(len(exp.runs["paper"].t), len(exp.target["t"]))


def truncation(exp: Experiment, signal: str, target: np.ndarray) -> list[float | None]:
    """The 'paper' run's truncation error per joint, % (module docstring): from the ``coarse``
    run (DOP853) or the ``refined`` one (RK4)."""
    paper = exp.runs["paper"]
    if "coarse" in exp.runs:
        return [None if x is None else x / (TRUNCATION_RTOL_FACTOR - 1)
                for x in _difference(exp.runs["coarse"], paper, signal, target)]
    return _difference(exp.runs["refined"], paper, signal, target)


def _difference(other: Run, run: Run, signal: str, target: np.ndarray) -> list[float | None]:
    """% difference between another run and the run, on the run's samples (an RK4 run at
    dt / 2 has twice the samples: every second one)."""
    step = max(1, round((len(other.t) - 1) / max(len(run.t) - 1, 1)))
    a = getattr(other, signal)[::step, :12]
    m = min(len(a), len(run.t), len(target))  # runs that stopped early have fewer samples
    return percent_errors(a[:m] - getattr(run, signal)[:m, :12] + target[:m], target[:m])


def physics_check(exp: Experiment, scale: float) -> dict[str, Any]:
    """Rigid-contact dynamics vs IK and vs the reduced model, per torque law."""
    target = exp.target
    reduced_of = {"ik": exp.runs.get("physical", exp.runs["paper"]), "plus_1pct": exp.runs["plus_1pct"],
                  "pd": exp.runs["pd"]}
    kp, kd = pd_gains(exp.plan.robot)
    laws = {"ik": "id_r's joint torques (roll unactuated)", "plus_1pct": "1.01 x id_r's joint torques",
            "pd": f"1.01 x id_r's joint torques + joint PD (kp {kp:g} N m/rad, kd {kd:g} N m s/rad) to the IK plan"}
    out: dict[str, Any] = {"departure_threshold_pct_of_max_joint_angle": DEPARTURE_PCT,
                           "max_joint_angle_rad": scale}
    for name, rigid in exp.rigid.items():
        reduced = reduced_of[name]
        d_rr, t_rr = departure(rigid.t, rigid.q, reduced.q, scale)
        d_ik, t_ik = departure(rigid.t, rigid.q, target["q"], scale)
        d_red, t_red = departure(reduced.t, reduced.q, target["q"], scale)
        out[name] = {
            "torques": laws[name],
            "rigid_vs_reduced": {"max_joint_angle_diff_rad": float(d_rr.max()) if d_rr.size else None,
                                 "time_to_1pct_s": t_rr, "over_time": _series(rigid.t, d_rr)},
            "rigid_vs_ik": {"max_joint_angle_diff_rad": float(d_ik.max()) if d_ik.size else None, "time_to_1pct_s": t_ik},
            "reduced_vs_ik": {"max_joint_angle_diff_rad": float(d_red.max()) if d_red.size else None,
                              "time_to_1pct_s": t_red},
            "rigid_stopped_at_s": rigid.stopped_at, "reduced_stopped_at_s": reduced.stopped_at,
        }
    return out
