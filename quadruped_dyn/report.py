"""``quadruped-dyn report``: one self-contained HTML page of everything the toolkit knows about
a robot (``<out>/<robot>/report.html``), with its files beside it (the experiment's plots and
JSON, the generated C).

Each section is gathered by a function here, from the toolkit's public APIs, and rendered by
``report_sections`` from plain data (the same dicts the commands print as JSON). A section
whose gathering raises shows FAIL with the message; the page is written anyway.

Conventions of the numbers shown: trunk frame b (x forward, y left, z up), world z up;
joint order FL, FR, BL, BR x (HAA, HFE, KFE); quaternions (x, y, z, w); a = vdot, i.e. the
trunk's spatial acceleration, as everywhere in the project.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import platform
import subprocess
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from .errors import InputError
from .leg import JOINT_ROLES
from .report_html import Section, figure, page, png_image
from .robot import ROBOT_NAMES, Robot, load_robot, robot_path

#: Random states of the check (the README's numbers use 200).
CHECK_SAMPLES = 200
#: Friction coefficient of the friction-cone column (rubber foot on a hard floor).
FRICTION_MU = 0.6
#: The experiment's sampling interval, s (the ``validate`` default).
EXPERIMENT_DT = 1e-3
#: Libraries whose versions the page records.
LIBRARIES = ("quadruped_dyn", "pin", "casadi", "numpy", "sympy", "matplotlib", "example-robot-data", "click",
             "nbclient", "ipykernel", "markdown-it-py", "pygments")


class Progress:
    """One line per step on stderr: ``[k/N] what ... 12.3 s``; on a terminal, a step with
    a count (``count(n, total)``) shows it as it goes."""

    def __init__(self, total: int, enabled: bool = True) -> None:
        self.total, self.k, self.enabled = total, 0, enabled
        self.line = ""
        self.live = enabled and sys.stderr.isatty()

    def step(self, what: str) -> Callable[[], None]:
        self.k += 1
        start = time.perf_counter()
        self.line = f"[{self.k}/{self.total}] {what} ..."
        if self.enabled:
            print(self.line, end="", file=sys.stderr, flush=True)

        def done() -> None:
            if self.enabled:
                again = f"\r{self.line}\x1b[K" if self.live else ""  # rewrite the line a count has extended
                print(f"{again} {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)

        return done

    def count(self, n: int, total: int) -> None:
        if self.live:
            print(f"\r{self.line} {n}/{total}", end="", file=sys.stderr, flush=True)


def prepare(robot_arg: str, out: str | Path) -> tuple[Path, Path]:
    """Validate the arguments before any work: (URDF path, the robot's output directory).
    InputError for an unknown robot or an output directory that cannot be written."""
    urdf = robot_path(robot_arg)
    name = robot_arg if robot_arg in ROBOT_NAMES else urdf.stem  # as load_robot names it
    target = Path(out) / name
    try:
        target.mkdir(parents=True, exist_ok=True)
        probe = target / f".write-test-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise InputError(f"cannot write to '{target}' ({e.strerror}); expected a writable --out directory") from e
    return urdf, target


# ----------------------------------------------------------------------------- gathering


def load_with_warnings(robot_arg: str) -> tuple[Robot, list[str]]:
    """The robot, and every warning raised while loading it (Python warnings, and the
    ``warnings`` attribute of a Robot if the loader records them)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_robot(robot_arg)
    messages = [str(w.message) for w in caught]
    return robot, messages + [str(w) for w in getattr(robot, "warnings", ())]


def robot_data(robot: Robot, urdf_warnings: list[str]) -> dict[str, Any]:
    from .cli import robot_info

    info = robot_info(robot)
    info["joints"] = [{"name": j.name, "leg": leg.label, "role": role, "lower": j.lower, "upper": j.upper,
                       "standing": float(robot.standing_q[3 * i + k])}
                      for i, leg in enumerate(robot.legs) for k, (j, role) in enumerate(zip(leg.joints, JOINT_ROLES))]
    info["warnings"] = urdf_warnings
    return info


def leg_points(robot: Robot, q_joints: np.ndarray) -> dict[str, np.ndarray]:
    """World points (Pinocchio forward kinematics) of each leg's HAA, HFE, KFE origins and
    foot, trunk level with its origin placed so the lowest foot touches z = 0."""
    import pinocchio as pin

    from .pinocchio_ref import PinocchioReference
    from .state import full_q

    data = robot.model.createData()
    q = PinocchioReference(robot).pin_q(full_q(np.eye(3), np.zeros(3), q_joints))
    pin.framesForwardKinematics(robot.model, data, q)
    chains = {}
    for leg, foot in zip(robot.legs, robot.foot_frame_ids):
        joints = [data.oMi[robot.model.getJointId(j.name)].translation for j in leg.joints]
        chains[leg.label] = np.array([*joints, data.oMf[foot].translation])
    lowest = min(c[-1, 2] for c in chains.values())
    return {label: c - [0.0, 0.0, lowest] for label, c in chains.items()}


def grf_posture(robot: Robot, q_joints: np.ndarray, mu: float) -> tuple[dict[str, Any], list[dict[str, Any]], np.ndarray]:
    """The paper model's solve of every stance set at ``q_joints``, trunk level and still:
    ranks (structural and from an SVD of Pinocchio's contact Jacobians), residual, friction;
    and, for the rank-5 cases drawn on the footprint, the free direction's forces."""
    from .grf import STANCE_SETS, friction_cone, grf_solve
    from .pinocchio_ref import PinocchioReference
    from .state import full_q, rotation

    ref = PinocchioReference(robot)
    q = full_q(np.eye(3), np.zeros(3), q_joints)
    v = a = np.zeros(18)
    feet = ref.foot_positions(q)
    stances, cases = [], []
    for s in STANCE_SETS:
        if not s.feet:
            continue
        P = s.selection("paper")
        r = ref.grf_solve(q, v, a, s.feet, P)
        lam, f, residual, _ = (np.asarray(x, dtype=float).ravel() for x in grf_solve(robot, s).function(q, v, a))
        f_world = f.reshape(4, 3)[list(s.feet)] @ rotation(q).T
        ok, margin = friction_cone(f_world, mu)
        stances.append({"stance": s.name, "kind": s.kind, "rank": s.rank("paper"), "numeric_rank": r.rank,
                        "singular_values": r.singular_values.tolist(), "max_residual": float(np.abs(residual).max()),
                        "min_friction_margin_N": float(margin.min()), "in_cone": bool(ok.all())})
        if s.name in ("FL+FR+BL+BR", "FL+BR", "FR+BL"):
            Jc = ref.contact_jacobian(q, s.feet)
            A = Jc[:, :6].T @ np.kron(np.eye(len(s.feet)), rotation(q)) @ P
            _, _, Vt = np.linalg.svd(A)
            cases.append({"name": s.name, "stance": s.feet, "f_free": (P @ Vt[-1]).reshape(-1, 3)})
    return {"mu": mu, "stances": stances}, cases, feet


def reduced_rows(robot: Robot, q_joints: np.ndarray) -> list[dict[str, Any]]:
    """cond(M_r), asymmetry and M_r against the Pinocchio-built reduced reference, for every
    stance set of 2, 3 or 4 feet, at ``q_joints``, trunk level (roll 0), still."""
    from .evaluate import evaluate
    from .grf import STANCE_SETS
    from .pinocchio_ref import PinocchioReference
    from .reduced import MAX_COND_M_R, REDUCED_KINDS, reduced_model
    from .tolerances import REL_TOL_TERMS

    ref = PinocchioReference(robot)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    rows = []
    for s in STANCE_SETS:
        if len(s.feet) not in REDUCED_KINDS:
            continue
        m = reduced_model(robot, s.name)
        q_r = np.append(q_joints, np.zeros(m.n - 12))
        try:
            (M,) = evaluate(m.M_r, q_r, quat)
            cond = float(np.linalg.cond(M))
            if not cond < MAX_COND_M_R:
                raise InputError(f"cond(M_r) = {cond:.1e}, beyond {MAX_COND_M_R:.0e}: numerically singular")
        except InputError as e:  # a result: e.g. a front or back pair, whose free pitch the roll cannot describe
            rows.append({"stance": s.name, "kind": s.kind, "n": m.n, "cond": float("inf"), "asymmetry": None,
                         "err_vs_pinocchio": None, "tol": REL_TOL_TERMS, "singular": str(e)})
            continue
        P, zero = s.selection("paper"), np.zeros(m.n)
        base = ref.reduced_inverse_dynamics(s.feet, P, q_r, zero, zero, quat)
        M_ref = np.column_stack([ref.reduced_inverse_dynamics(s.feet, P, q_r, zero, e, quat) - base for e in np.eye(m.n)])
        scale = float(np.abs(M_ref).max())
        rows.append({"stance": s.name, "kind": s.kind, "n": m.n, "cond": cond,
                     "asymmetry": float(np.abs(M - M.T).max() / np.abs(M).max()),
                     "err_vs_pinocchio": float(np.abs(M - M_ref).max() / scale), "tol": REL_TOL_TERMS})
    return rows


def experiment(robot: Robot, out: Path) -> tuple[dict[str, dict[str, Any] | None], dict[str, str]]:
    """Both gaits' validation (two cycles each, DOP853 sampled every EXPERIMENT_DT, with the
    physics check): the JSON dicts and the BR HFE figures, written beside the report as
    ``validate`` writes them."""
    from .gait import GAITS
    from .simulate import reduced_dynamics
    from .validation import report as validation_report
    from .validation import run_experiment, static_stability
    from .validation_files import output_paths, plot_br_hfe, plot_physics_check, write_json

    validations: dict[str, dict[str, Any] | None] = {}
    plots: dict[str, str] = {}
    for name, gait in GAITS.items():
        horizon = 2 * gait.period
        exp = run_experiment(robot, gait, reduced_dynamics(robot, "c"), horizon, EXPERIMENT_DT)
        data = validation_report(exp, "dop853", EXPERIMENT_DT, "c", static_stability(exp.plan, exp.ik, horizon))
        paths = output_paths(out, robot.name, name)
        write_json(paths["json"], data)
        plot_br_hfe(paths["plot"], exp)
        plot_physics_check(paths["physics_plot"], exp)
        validations[name] = json.loads(paths["json"].read_text())
        plots[name] = (f"<figure>{png_image(paths['plot'].read_bytes(), f'BR HFE, {name}')}<figcaption>BR HFE: acceleration, "
                       f"velocity, displacement, forward dynamics against IK (the paper's Figs. 7, 6, 5)</figcaption></figure>"
                       f"<figure>{png_image(paths['physics_plot'].read_bytes(), f'physics check, {name}')}<figcaption>"
                       "largest joint-angle difference: reduced model vs rigid contacts</figcaption></figure>")
    return validations, plots


def generated_c(robot: Robot, out: Path) -> dict[str, Any]:
    """Generate the C beside the report, compile (cached) and compare each function with
    Pinocchio at the fixed reference state."""
    from .codegen import PREFIX, codegen_functions, generate, pinocchio_outputs, reference_state, work_sizes
    from .compiled import CompiledFunction, compiled_library
    from .pinocchio_ref import PinocchioReference
    from .symbolic import shapes
    from .tolerances import REL_TOL_TERMS

    directory = out / "c"
    paths = generate(robot, directory)
    work = work_sizes(paths[1].read_text())

    functions: list[dict[str, Any]] = [
        {"name": f.name(), "inputs": shapes(f), "outputs": shapes(f, outputs=True), "instructions": f.n_instructions(),
         "iw": work[f.name()][0], "w": work[f.name()][1]} for f in codegen_functions(robot)]
    start = time.perf_counter()
    library = compiled_library(robot)
    compile_s = time.perf_counter() - start
    ref, s = PinocchioReference(robot), reference_state(robot)
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel()}
    checks = []
    for f in functions:
        name = f["name"][len(PREFIX):]
        fn = CompiledFunction(library, name)
        ours = fn(*[inputs[n] for n in fn.names_in])
        expected = pinocchio_outputs(robot, ref, name, s)
        ours_all = np.concatenate([np.asarray(o, dtype=float).ravel() for o in ours])
        expected_all = np.concatenate([np.asarray(e, dtype=float).ravel() for e in expected])
        # relative to the largest reference output: a residual that should be ~0 has no scale of its own
        err = float(np.abs(ours_all - expected_all).max() / (np.abs(expected_all).max() or 1.0))
        checks.append({"name": f["name"], "max_rel_err": err, "tol": REL_TOL_TERMS})
    return {"directory": str(directory), "files": [{"name": p.name, "bytes": p.stat().st_size} for p in paths],
            "functions": functions, "checks": checks, "compile_s": compile_s,
            "library_bytes": library.path.stat().st_size}


def symbolic_data(robot: Robot) -> tuple[list[dict[str, Any]] | None, str, list[dict[str, Any]], list[tuple[str, np.ndarray]]]:
    """Formulas of the DH robot checked against Pinocchio at random joint angles; sizes and
    sparsity patterns of every term."""
    from .pinocchio_ref import PinocchioReference
    from .state import full_q
    from .symbolic import DISPLAY_DIGITS, paper_formulas, term_sizes
    from .tolerances import REL_TOL_TERMS

    formulas = None
    note = "Formulas are typeset for the robot built from the paper's DH table (`paper`); this robot has no DH description."
    if robot.name == "paper":  # the paper's URDF by any path or copy (robot.load_robot's identity)
        ref = PinocchioReference(robot)
        rng = np.random.default_rng(0)
        states = [rng.uniform(robot.lower, robot.upper) for _ in range(20)]
        references = [
            lambda q: ref.foot_positions(q)[0],
            lambda q: ref.foot_jacobians(q)[0],
            lambda q: ref.gravity(q)[6:9],
        ]
        formulas = []
        for formula, reference in zip(paper_formulas(robot), references):
            err = 0.0
            for qj in states:
                expected = np.asarray(reference(full_q(np.eye(3), np.zeros(3), qj)))
                got = formula.evaluate(qj[:3]).reshape(expected.shape)
                err = max(err, float(np.abs(got - expected).max() / (np.abs(expected).max() or 1.0)))
            formulas.append({"title": formula.title, "latex": formula.latex, "mathml": formula.mathml,
                             "max_err_vs_pinocchio": err, "tol": REL_TOL_TERMS})
        note = (f"Front-left leg of the DH robot, from the CasADi expressions (SX → SymPy, simplified). Trunk frame "
                f"(x forward, y left, z up), trunk level (R = I); θ1, θ2, θ3 = HAA, HFE, KFE (rad). Coefficients shown "
                f"to {DISPLAY_DIGITS} digits; checked with full precision on 20 random joint states.")
    sizes = term_sizes(robot)
    rows = [{"name": t.name, "instructions": t.instructions, "inputs": t.inputs, "outputs": t.outputs,
             "nonzeros": int(t.pattern.sum())} for t in sizes]
    return formulas, note, rows, [(t.name, t.pattern) for t in sizes]


def versions() -> dict[str, Any]:
    libraries = {}
    for name in LIBRARIES:
        try:
            libraries[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            libraries[name] = "not installed"
    cpu = next((line.split(":", 1)[1].strip() for line in _read("/proc/cpuinfo").splitlines()
                if line.startswith("model name")), platform.processor() or "unknown")
    machine = {"python": sys.version.split()[0], "platform": platform.platform(), "cpu": cpu,
               "cores": os.cpu_count(), "compiler": _first_line(["gcc", "--version"]),
               "date (UTC)": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M")}
    return {"machine": machine, "libraries": libraries}


def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def _first_line(cmd: list[str]) -> str:
    try:
        return subprocess.run(cmd, capture_output=True, text=True, check=False).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "not found"


def notebooks(robot: Robot) -> tuple[list[dict[str, Any]] | None, str]:
    from .report_notebooks import error_count, execute, notebook_paths, render

    if robot.name != "paper":
        return None, "The notebooks are written for the paper's robot: see the report of `paper`."
    paths = notebook_paths()
    if not paths:
        return None, "The notebooks are part of a source checkout, not of an installed package."
    rendered = []
    for path in paths:
        nb, seconds = execute(path)
        rendered.append({"name": path.name, "seconds": seconds, "errors": error_count(nb), "html": render(nb)})
    return rendered, ""


# ----------------------------------------------------------------------------- the report


@dataclass(frozen=True)
class ReportResult:
    path: Path
    sections: list[Section]

    @property
    def passed(self) -> bool:
        return all(s.verdict != "FAIL" for s in self.sections)

    def summary(self) -> str:
        width = max(len(s.title) for s in self.sections)
        lines = [f"{'section':<{width}}  {'result':<13}  headline"]
        lines += [f"{s.title:<{width}}  {s.verdict:<13}  {s.headline}" for s in self.sections]
        lines.append(f"wrote {self.path}")
        return "\n".join(lines)


def _failed(key: str, title: str, e: Exception) -> Section:
    message = f"{type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else ''}"
    return Section(key, title, "FAIL", message[:160], f'<p class="warn">Could not build this section: {message}</p>')


def build_report(robot_arg: str = "paper", out: str | Path = "results", fast: bool = False,
                 samples: int = CHECK_SAMPLES, with_notebooks: bool = True, show_progress: bool = True) -> ReportResult:
    """Write ``<out>/<robot>/report.html`` (see the module docstring); ``fast`` skips the
    benchmark. Arguments are validated (InputError) before any work."""
    import matplotlib

    matplotlib.use("Agg")  # figures go into the page, never to a window
    from . import report_sections as rs
    from .report_figures import footprint_figure, sparsity_figure, stick_figure

    _, target = prepare(robot_arg, out)
    progress = Progress(9, show_progress)
    sections: list[Section] = []

    def attempt(key: str, title: str, build: Callable[[], Section]) -> None:
        try:
            sections.append(build())
        except Exception as e:  # one section failing must not lose the others: it is reported on the page
            sections.append(_failed(key, title, e))

    done = progress.step(f"loading {robot_arg}")
    robot, urdf_warnings = load_with_warnings(robot_arg)
    from .gait import gait_posture

    def robot_section() -> Section:
        chains = leg_points(robot, robot.standing_q)
        fig = figure(stick_figure(chains, f"{robot.name} at its standing posture"), "stick figure of the robot",
                     "legs and feet at robot.standing_q, trunk level, lowest foot on the ground")
        return rs.robot_section(robot_data(robot, urdf_warnings), fig)

    attempt("robot", "The robot", robot_section)
    done()

    done = progress.step(f"every term against Pinocchio ({samples} random states)")
    check: dict[str, Any] | None = None
    try:
        from .check import run_check

        check = run_check(robot, samples, 0, progress=lambda n: progress.count(n, samples)).as_dict()
        sections.append(rs.terms_section(check))
    except Exception as e:
        sections.append(_failed("terms", "Every term against Pinocchio", e))
    done()

    done = progress.step("GRF systems")

    def grf_section() -> Section:
        posture, cases, feet = grf_posture(robot, gait_posture(robot), FRICTION_MU)
        fig = figure(footprint_figure(feet, cases), "free and unbalanced directions on the footprint",
                     "rank-5 systems of the paper's model at the gait posture: free and unbalanced directions")
        return rs.grf_section(check, posture, fig)

    attempt("grf", "Ground-reaction-force systems", grf_section)
    done()

    done = progress.step("reduced model of every stance set")
    attempt("reduced", "Reduced model per stance set",
            lambda: rs.reduced_section(reduced_rows(robot, gait_posture(robot)), "the gait posture"))
    done()

    done = progress.step("the paper's experiment: trot and static walk")
    def experiment_section() -> Section:
        from .validation import joint_names  # the labels the validation JSON is keyed by

        validations, plots = experiment(robot, target)
        return rs.experiment_section(validations, joint_names(robot), plots)

    attempt("experiment", "The paper's experiment: trot and static walk", experiment_section)
    done()

    done = progress.step("generated C" + ("" if fast else " and the benchmark"))

    def c_section() -> Section:
        gen = generated_c(robot, target)
        if fast:
            return rs.generated_c_section(gen, None, "skipped with --fast")
        from .bench import run_bench

        return rs.generated_c_section(gen, run_bench(robot).as_dict())

    attempt("c", "Generated C", c_section)
    done()

    done = progress.step("symbolic terms")

    def symbolic_section() -> Section:
        formulas, note, sizes, patterns = symbolic_data(robot)
        fig = figure(sparsity_figure(patterns), "sparsity of every term",
                     "structural nonzeros: matrix outputs as they are, vector outputs as their Jacobian w.r.t. all inputs")
        return rs.symbolic_section(formulas, note, sizes, fig)

    attempt("symbolic", "Symbolic terms", symbolic_section)
    done()

    done = progress.step("notebooks")
    if with_notebooks:
        attempt("notebooks", "Notebooks, executed", lambda: rs.notebooks_section(*notebooks(robot)))
    else:
        sections.append(rs.notebooks_section(None, "not executed for this page"))
    done()

    done = progress.step("versions, writing the page")
    sections.append(rs.versions_section(versions()))
    path = target / "report.html"
    subtitle = (f"{robot.urdf} — built {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC by quadruped-dyn report"
                + (" --fast" if fast else ""))
    path.write_text(page(f"quadruped_dyn report: {robot.name}", subtitle, sections))
    done()
    return ReportResult(path, sections)
