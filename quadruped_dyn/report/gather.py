"""The report's numbers, gathered from the public APIs (each section's data as plain values)."""

from __future__ import annotations

import importlib.metadata
import json
import math
import os
import platform
import subprocess
import sys
import time
import warnings
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from quadruped_dyn.errors import InputError, NumericalError
from quadruped_dyn.files.safe_write import output_dir
from quadruped_dyn.math.compare import relative_error, scale_of
from quadruped_dyn.model.leg import JOINT_ROLES
from quadruped_dyn.model.robot import Robot, load_robot
from quadruped_dyn.report.html import png_image

if TYPE_CHECKING:
    from quadruped_dyn.codegen.emit import GeneratedFiles


#: Friction coefficient of the friction-cone column (rubber foot on a hard floor).
FRICTION_MU = 0.6

#: The experiment's sampling interval, s (the ``validate`` default).
EXPERIMENT_DT = 1e-3

#: The generated C's folder beside the report's page.
C_FOLDER = "c"

#: Libraries whose versions the page records.
LIBRARIES = ("quadruped_dyn", "pin", "casadi", "numpy", "sympy", "matplotlib", "example-robot-data", "click",
             "nbclient", "ipykernel", "markdown-it-py", "pygments", "mujoco", "idyntree", "drake", "adam-robotics")

def load_with_warnings(robot_arg: str, foot_frames: object = None) -> tuple[Robot, list[str]]:
    """The robot (``foot_frames`` as ``load_robot``'s), and every warning raised while loading it (Python warnings,
    and the ``warnings`` attribute of a Robot if the loader records them)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_robot(robot_arg, foot_frames=foot_frames)
    messages = [str(w.message) for w in caught]
    return robot, messages + [str(w) for w in getattr(robot, "warnings", ())]

def robot_data(robot: Robot, urdf_warnings: list[str]) -> dict[str, Any]:
    from quadruped_dyn.model.robot_summary import robot_info

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

    from quadruped_dyn.model.state import full_q
    from quadruped_dyn.references.pinocchio import PinocchioReference

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
    from quadruped_dyn.dynamics.grf import friction_cone, grf_solve
    from quadruped_dyn.model.stance import STANCE_SETS
    from quadruped_dyn.model.state import full_q, rotation
    from quadruped_dyn.references.pinocchio import PinocchioReference

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

def reduced_rows(robot: Robot, q_joints: np.ndarray, progress: Any = None) -> list[dict[str, Any]]:
    """cond(M_r), asymmetry and M_r against the Pinocchio-built reduced reference, for every
    stance set of 2, 3 or 4 feet, at ``q_joints``, trunk level (roll 0), still; ``progress(k, n)``
    after the k-th of n stance sets (each a symbolic model built: seconds)."""
    from quadruped_dyn.dynamics.guarded import guarded_call
    from quadruped_dyn.dynamics.reduced import MAX_COND_M_R, REDUCED_KINDS, reduced_model
    from quadruped_dyn.model.stance import STANCE_SETS
    from quadruped_dyn.references.pinocchio import PinocchioReference
    from quadruped_dyn.tolerances import REL_TOL_TERMS

    ref = PinocchioReference(robot)
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    rows: list[dict[str, Any]] = []
    stances = [s for s in STANCE_SETS if len(s.feet) in REDUCED_KINDS]
    for s in stances:
        if progress is not None:
            progress(len(rows), len(stances))
        m = reduced_model(robot, s.name)
        q_r = np.append(q_joints, np.zeros(m.n - 12))
        try:
            (M,) = guarded_call(m.M_r, q_r, quat)
            cond = float(np.linalg.cond(M))
            if not cond < MAX_COND_M_R:
                raise NumericalError(f"cond(M_r) = {cond:.1e}, beyond {MAX_COND_M_R:.0e}: numerically singular")
        except (InputError, NumericalError) as e:  # a result: e.g. a front or back pair (its free pitch is not the roll)
            rows.append({"stance": s.name, "kind": s.kind, "n": m.n, "cond": float("inf"), "asymmetry": None,
                         "err_vs_pinocchio": None, "tol": REL_TOL_TERMS, "singular": str(e)})
            continue
        M_ref = ref.reduced_mass_matrix(s.feet, s.selection("paper"), q_r, quat)
        rows.append({"stance": s.name, "kind": s.kind, "n": m.n, "cond": cond,
                     "asymmetry": relative_error(M, M.T, scale_of(M)),
                     "err_vs_pinocchio": relative_error(M, M_ref), "tol": REL_TOL_TERMS})
    return rows

def experiment(robot: Robot, out: Path, progress: Any = None) -> tuple[dict[str, dict[str, Any] | None], dict[str, str]]:
    """Both gaits' validation (two cycles each, DOP853 sampled every EXPERIMENT_DT, with the
    physics check): the JSON dicts and the BR HFE figures, written beside the report as
    ``validate`` writes them. ``progress``: a ``quadruped_dyn.progress.Steps`` whose current
    step gets a bar of the simulated seconds and runs."""
    from quadruped_dyn.experiment.gait import GAITS
    from quadruped_dyn.experiment.paper_experiment import report as validation_report
    from quadruped_dyn.experiment.paper_experiment import run_experiment, static_stability
    from quadruped_dyn.experiment.simulate import reduced_dynamics
    from quadruped_dyn.experiment.validation_files import output_paths, plot_br_hfe, plot_physics_check
    from quadruped_dyn.files.json import write_json

    validations: dict[str, dict[str, Any] | None] = {}
    plots: dict[str, str] = {}
    runs = {name: 3 + (gait.n_coords == 13) + 5 for name, gait in GAITS.items()}  # as run_experiment does them
    bar = progress.bar(sum(n * 2 * GAITS[g].period for g, n in runs.items()), "s simulated",
                       runs=None) if progress is not None else None
    for name, gait in GAITS.items():
        horizon = 2 * gait.period
        exp = run_experiment(robot, gait, reduced_dynamics(robot, "c"), horizon, EXPERIMENT_DT,
                             progress=bar.advance if bar is not None else None)
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

def generate_c_directory(robot: Robot, directory: Path) -> tuple[GeneratedFiles, dict[str, Any]]:
    """``codegen``'s files and the reference header in ``directory`` (``generate_checked``'s): (the
    files written, {"functions": every generated Function, "work": their work sizes}). The same
    bytes for the same robot and machine, so the builds keyed by them (the footprint's) are shared
    with the warm process, and the benchmark times these files (``run_bench(checked_c=...)``)."""
    import casadi as ca

    from quadruped_dyn.checks.check_program_values import reference_header, reference_header_name
    from quadruped_dyn.codegen.emit import generate

    generated: dict[str, Any] = {}

    def reference_file(functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> dict[str, str]:
        generated.update(functions=functions, work=work, expected={})  # every generated Function, as generate() builds them
        return {reference_header_name(robot): reference_header(robot, functions, work, generated["expected"])}

    return generate(robot, directory, extra_files=reference_file), generated


def generated_c(robot: Robot, out: Path, progress: Any = None) -> tuple[dict[str, Any], GeneratedFiles]:
    """Generate the C beside the report (every function: the full-coordinate terms, the GRF
    solves and the reduced model of every stance set), compile (cached) and compare each
    function with Pinocchio at the fixed reference state, as the generated ``check_qd`` does;
    ``progress(k, n)`` after the k-th of n functions checked. (The section's data, the files.)"""
    from quadruped_dyn.checks.check_program_values import reference_state
    from quadruped_dyn.codegen.emit import PREFIX
    from quadruped_dyn.codegen.library import compiled_library
    from quadruped_dyn.dynamics.formulas import shapes

    directory = out / C_FOLDER  # created by output_dir (never a link out of --out) when generated
    files, generated = generate_c_directory(robot, output_dir(out, C_FOLDER))
    paths = files.all()
    work = generated["work"]
    functions: list[dict[str, Any]] = [
        {"name": f.name(), "inputs": shapes(f), "outputs": shapes(f, outputs=True), "instructions": f.n_instructions(),
         "iw": work[f.name()][0], "w": work[f.name()][1]} for f in generated["functions"]]
    start = time.perf_counter()
    library = compiled_library(robot)
    compile_s = time.perf_counter() - start
    s = reference_state(robot)
    checks = []
    for f in generated["functions"]:
        checks.append(c_function_check(robot, library, f, s, generated["expected"].get(f.name()[len(PREFIX):])))
        if progress is not None:
            progress(len(checks), len(generated["functions"]))
    return {"directory": str(directory), "files": [{"name": p.name, "bytes": p.stat().st_size} for p in paths],
            "functions": functions, "checks": checks, "compile_s": compile_s,
            "library_bytes": library.path.stat().st_size}, files

#: A case whose scaled tolerance exceeds this could only fail on NaN: reported skipped (check_qd.c's QD_MAX_TOL).
C_CHECK_MAX_TOL = 1e-2

def c_function_check(robot: Robot, library: Any, f: Any, s: Any, expected: list[np.ndarray] | None = None) -> dict[str, Any]:
    """One compiled function at the reference state ``s`` against Pinocchio: the relative error
    (to the largest reference output), its tolerance scaled by the state's conditioning
    (``check_program_values.tolerance_scale``), and pass / FAIL / skipped with the reason, as check_qd.
    ``expected``: Pinocchio's outputs at ``s`` if already computed (``reference_header``'s)."""
    from quadruped_dyn.checks.check_program_values import (
        pinocchio_outputs,
        reduced_inputs,
        reference_tau_full,
        tolerance_floor,
        tolerance_scale,
        wrench_inputs,
    )
    from quadruped_dyn.codegen.emit import PREFIX
    from quadruped_dyn.codegen.library import CompiledFunction
    from quadruped_dyn.math.compare import relative_error, within
    from quadruped_dyn.references.pinocchio import PinocchioReference
    from quadruped_dyn.tolerances import REL_TOL_TERMS

    name = f.name()[len(PREFIX):]
    ref = PinocchioReference(robot)
    # the inputs and the tolerance of check_qd's case (check_program_values.reference_header): the derivatives
    # take tau_full, w and dq too, and a finite-difference reference has its own accuracy (tol_floor)
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel(), "tau_full": reference_tau_full(s), **reduced_inputs(s),
              **wrench_inputs(s)}
    tol = max(REL_TOL_TERMS, tolerance_floor(name)) * tolerance_scale(ref, name, s)
    row: dict[str, Any] = {"name": f.name(), "max_rel_err": None, "tol": tol, "status": "FAIL", "note": ""}
    try:
        ours = CompiledFunction(library, name)(*[inputs[f.name_in(i)][: f.nnz_in(i)] for i in range(f.n_in())])
    except Exception as e:  # a return code (QD_NONFINITE, QD_SINGULAR): a skip only where < 2 digits are left
        skipped = "singular" in str(e) and tol > C_CHECK_MAX_TOL
        row.update(status="skipped" if skipped else "FAIL", note=str(e))
        return row
    if expected is None:
        expected = pinocchio_outputs(robot, ref, name, s)
    ours_all = np.concatenate([np.asarray(o, dtype=float).ravel() for o in ours])
    expected_all = np.concatenate([np.asarray(e, dtype=float).ravel() for e in expected])
    # relative to the largest reference output: a residual that should be ~0 has no scale of its own
    err = relative_error(ours_all, expected_all)
    row["max_rel_err"] = err
    if math.isfinite(err) and tol > C_CHECK_MAX_TOL:
        row.update(status="skipped", note=f"cond x eps = {tol:.1e} leaves < 2 digits")
    else:
        row["status"] = "pass" if within(err, tol) else "FAIL"
    return row

def symbolic_data(robot: Robot) -> tuple[list[dict[str, Any]] | None, str, list[dict[str, Any]], list[tuple[str, np.ndarray]]]:
    """Formulas of the DH robot checked against Pinocchio at random joint angles; sizes and
    sparsity patterns of every term."""
    from quadruped_dyn.dynamics.formulas import DISPLAY_DIGITS, paper_formulas, term_sizes
    from quadruped_dyn.model.state import full_q
    from quadruped_dyn.references.pinocchio import PinocchioReference
    from quadruped_dyn.tolerances import REL_TOL_TERMS

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
                err = max(err, relative_error(got, expected))
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

def notebook_list(robot: Robot) -> tuple[list[Path], str]:
    """The notebooks the report executes for ``robot``, or none and why."""
    from quadruped_dyn.report.notebooks import notebook_paths

    if robot.name != "paper":
        return [], "The notebooks are written for the paper's robot: see the report of `paper`."
    paths = notebook_paths()
    return paths, "" if paths else "The notebooks are part of a source checkout, not of an installed package."


def executed_notebook(path: Path) -> dict[str, Any]:
    """One notebook executed top to bottom and rendered: name, seconds, errors (cells that raised), html."""
    from quadruped_dyn.report.notebooks import error_count, execute, render

    nb, seconds = execute(path)
    return {"name": path.name, "seconds": seconds, "errors": error_count(nb), "html": render(nb)}


def optimal_trot(robot: Robot, out: Path) -> tuple[dict[str, Any], str]:
    """The trot optimised on the reduced model (``optimize``'s defaults) and replayed open loop in the
    rigid-contact dynamics for two cycles: the JSON dict and the plot, written beside the report."""
    from quadruped_dyn.experiment.gait import TROT
    from quadruped_dyn.optimal_control.replay import replay_rigid
    from quadruped_dyn.optimal_control.solve import solve
    from quadruped_dyn.optimal_control.trajectory_files import output_paths, report, write_outputs
    from quadruped_dyn.optimal_control.transcription import transcribe

    sol = solve(transcribe(robot, TROT))
    replay = replay_rigid(sol, 2.0) if sol.converged else None
    data = report(sol, replay)
    paths = output_paths(out, robot.name, "trot")
    write_outputs(paths, sol, replay, data)
    plot = (f"<figure>{png_image(paths['plot'].read_bytes(), 'optimised trot')}<figcaption>the optimised trot against "
            "today's plan: joint angles, trunk, torques, and the open-loop rigid-contact replay</figcaption></figure>")
    return json.loads(paths["json"].read_text()), plot
#: Random states of the cross-library comparison (``check --against``'s default).
CROSS_LIBRARY_SAMPLES = 20

def cross_library(robot: Robot) -> dict[str, Any]:
    """The other libraries as references, as ``check --against all`` runs them, for each of them
    that is installed (the ``xlib`` extra, which ``./run`` installs): ``cross_library`` rows,
    ``model_changes``, ``cross_library_passed``; ``cross_library_note`` says what was not run."""
    import importlib.util

    from quadruped_dyn.checks.cross_library import INSTALL_HINT, LIBRARIES, run_cross_library
    from quadruped_dyn.checks.terms import json_safe

    installed = [n for n, (_, package) in LIBRARIES.items() if importlib.util.find_spec(package) is not None]
    missing = [n for n in LIBRARIES if n not in installed]
    note = f"not installed: {', '.join(missing)} ({INSTALL_HINT})" if missing else ""
    if not installed:
        return {"cross_library_note": note}
    data = json_safe(run_cross_library(robot, installed, CROSS_LIBRARY_SAMPLES, 0).as_dict())
    assert isinstance(data, dict)
    return {**data, "cross_library_samples": CROSS_LIBRARY_SAMPLES, "cross_library_note": note}


def embedded_footprint(robot: Robot, directory: Path, measure: bool = True) -> dict[str, Any]:
    """Caller memory, code size and stack on Cortex-M of the generated C in ``directory``
    (``checks.embedded``), one cross build per target at -Os (``footprint.SIZE_BUILDS``; -O2
    too: ``codegen --json``); the builds take minutes once, then are cached. Without ``measure``
    only the caller memory (no cross build: ``report --footprint`` asks for them)."""
    from quadruped_dyn.checks.embedded import embedded_summary
    from quadruped_dyn.codegen.footprint import SIZE_BUILDS

    summary = embedded_summary(robot, directory, footprint=measure, builds=SIZE_BUILDS)
    if not measure:
        summary["footprint"] = {"skipped": FOOTPRINT_NOT_MEASURED}
    return summary


#: What the page says when the report ran without ``--footprint``.
FOOTPRINT_NOT_MEASURED = ("not measured in this run: pass --footprint (two Cortex-M cross builds, minutes on a "
                          "cold cache), or run codegen --json; the tests check it")


def closed_loop(robot: Robot, out: Path, cycles: int = 10) -> dict[str, Any]:
    """The closed loop in MuJoCo (``quadruped-dyn control``), walk and trot, every controller:
    per gait the JSON as ``control --json`` prints it, the plots (PNG bytes) and the animation
    (GIF bytes, or why there is none); the files are written to ``out`` too."""
    from quadruped_dyn.control.closed_loop import prepare, run_all
    from quadruped_dyn.control.run import LoopOptions
    from quadruped_dyn.control.study_files import best_controller, rendering_available, write_all

    rendering, why = rendering_available()
    gaits: dict[str, Any] = {}
    for gait in ("walk", "trot"):
        study = run_all(prepare(robot, gait, loop=LoopOptions(cycles=cycles)), keep_qpos=rendering)
        data, paths = write_all(out, study, animation=rendering)
        gif = paths["animation"]
        gaits[gait] = {"data": data, "plot_png": paths["plot"].read_bytes(), "grf_png": paths["grf_plot"].read_bytes(),
                       "gif": gif.read_bytes() if gif.exists() else None, "animated": best_controller(study.results),
                       "animation_note": "" if gif.exists() else f"no animation: offscreen rendering unavailable ({why})"}
    return {"cycles": cycles, "gaits": gaits}

