"""Standalone C code generation (docs/formulation.md §11).

``CODEGEN_FUNCTIONS`` lists what is generated, one line per function. Each becomes a C
function ``qd_<name>(const casadi_real** arg, casadi_real** res, casadi_int* iw,
casadi_real* w, int mem)``: C99, no CasADi runtime, no malloc, no global state (all
temporaries are locals; ``iw``/``w`` are caller-provided work arrays of the sizes the
header states), so it is thread-safe. ``casadi_real`` is ``double`` unless the including
code defines it (``-Dcasadi_real=float`` gives the float build of the same source).

The header opens with the documentation of every function: inputs and outputs with shapes,
units and frames, output sparsity, and work sizes. ``compiled`` builds and loads the code.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import casadi as ca

from quadruped_dyn.codegen.by_leg import LegCall, by_leg_c, foot_c
from quadruped_dyn.codegen.c_alone import PROVIDED
from quadruped_dyn.codegen.c_facts import TEMPLATES, layouts_c, prelude_c, regularity_c, return_codes_c
from quadruped_dyn.codegen.c_file import Entry, FileOptions, c_file, entry_work, file_helpers
from quadruped_dyn.codegen.emit_derivatives import (
    DERIVATIVE_NAMES,
    GRF_DERIVATIVE_NAMES,
    GRF_DERIVATIVE_STANCE_SETS,
    REDUCED_DERIVATIVE_NAMES,
    DfdRPieces,
    derivative_functions,
    derivative_source,
    dfd_r_pieces,
    dfd_r_work_reals,
    reduced_derivative_functions,
)
from quadruped_dyn.codegen.file_names import (
    REDUCED_STANCE_SETS,
    REDUCED_TEMPLATES,
    GeneratedFiles,
    casadi_name,
    check_no_collision,
    file_layout,
)
from quadruped_dyn.codegen.forms.leg_pieces import foot_pieces, id_full_pieces, mass_matrix_pieces
from quadruped_dyn.codegen.forms.stance_maps import stance_maps
from quadruped_dyn.codegen.joint_trig import trig_as_inputs
from quadruped_dyn.codegen.precision_math import template_c
from quadruped_dyn.codegen.print_settings import EVALUATION, PREFIX, SINCOS, UNGUARDED, static_c
from quadruped_dyn.codegen.printer import SIGNATURE
from quadruped_dyn.codegen.work_memory import memory_doc
from quadruped_dyn.dynamics.grf import grf_balance, grf_solve
from quadruped_dyn.dynamics.kinematics import feet_full
from quadruped_dyn.dynamics.newton_euler import full_dynamics
from quadruped_dyn.dynamics.reduced_projection import reduced_projection
from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import comment_text
from quadruped_dyn.files.safe_write import output_path, output_set, write_text
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import STANCE_SETS, StanceSet, stance_set
from quadruped_dyn.model.state import JOINT_ANGLES, NQ_FULL
from quadruped_dyn.tolerances import (
    FLOAT_ERR_PER_REGULARITY,
    FLOAT_MAX_BOUND,
    FLOAT_REGULARITY_MIN,
    PITCH_ERR_PER_COS3,
    REL_TOL_TERMS,
    TRUNK_PITCH_DEG_MARGIN,
)


def _grf_paper(stance: StanceSet) -> Callable[[Robot], ca.Function]:
    return lambda robot: grf_solve(robot, stance, "paper").function


#: name -> builder; adding a generated function is one line here.
CODEGEN_FUNCTIONS: dict[str, Callable[[Robot], ca.Function]] = {
    "M_full": lambda r: full_dynamics(r).M_full_crba,  # = Walker-Orin M (tested), fewer operations
    "C_full": lambda r: full_dynamics(r).C_full,
    "G_full": lambda r: full_dynamics(r).G_full_crb,  # = Newton-Euler G (tested), fewer operations
    "nle_full": lambda r: full_dynamics(r).nle_full,
    "id_full": lambda r: full_dynamics(r).id_full,
    "feet_full": feet_full,  # the feet's positions, Jacobian and Jdot v (a whole-body controller's contact rows)
    **{f"grf_{s.name.replace('+', '_')}": _grf_paper(s) for s in STANCE_SETS},
}
#: Each algorithm's Python name in C too (Python's ``M_full_walker_orin`` and ``M_full_crba`` are two algorithms; the C
#: ``qd_M_full`` is CRBA): alias -> the generated function it is, whose graph and C it shares: its entry point calls it.
ALIASES = {"M_full_crba": "M_full", "G_full_crb": "G_full"}
CODEGEN_FUNCTIONS.update({alias: CODEGEN_FUNCTIONS[name] for alias, name in ALIASES.items()})

#: Reduced-model functions generated for every stance set in REDUCED_STANCE_SETS, as
#: qd_<name>_<feet> (feet joined by '_'), each in the file qd_<robot>-r-<feet>.c.
REDUCED_NAMES = ("M_r", "CG_r", "G_r", "id_r", "fd_r")


#: How many derivative functions ``generate`` writes: the full ones and the GRF ones in qd_<robot>-d.c, the
#: reduced ones in each reduced file (codegen/emit_derivatives.py).
N_DERIVATIVE_FUNCTIONS = (len(DERIVATIVE_NAMES) + len(GRF_DERIVATIVE_NAMES) * len(GRF_DERIVATIVE_STANCE_SETS)
                          + len(REDUCED_DERIVATIVE_NAMES) * len(REDUCED_STANCE_SETS))


def reduced_symbol(name: str, stance: StanceSet) -> str:
    """C name (without prefix) of reduced function ``name`` of a stance set, e.g. 'fd_r_FL_BR'."""
    return f"{name}_{stance.name.replace('+', '_')}"


def reduced_functions(robot: Robot, stance: StanceSet) -> list[ca.Function]:
    """The generated reduced functions of one stance set (``reduced_projection``'s forms),
    named with the C prefix, then its derivatives (``emit_derivatives.reduced_derivative_functions``).
    Their graphs give the C functions' signatures (and are tested against the references); the C bodies are the
    hand-written templates of ``c/qd_reduced_solve.c`` over the generated pieces (``_reduced_helpers_c``) and the
    library's qd_M_full, qd_G_full, qd_id_full. ``fd_r`` is a signature only (qdd_r = tau_ext), and dfd_r's body
    is ``c/qd_reduced_derivatives.c``."""
    n = 13 if len(stance.feet) == 2 else 12
    q_r, qd_r, qdd_r = ca.SX.sym("q_r", n), ca.SX.sym("qd_r", n), ca.SX.sym("qdd_r", n)
    quat, tau_ext = ca.SX.sym("quat", 4), ca.SX.sym("tau_ext", n)
    p = reduced_projection(robot, stance, q_r, quat)
    opts = {"cse": True}

    def function(name: str, inputs: dict[str, ca.SX], outputs: dict[str, ca.SX]) -> ca.Function:
        return ca.Function(PREFIX + reduced_symbol(name, stance), list(inputs.values()), list(outputs.values()),
                           list(inputs), list(outputs), opts)

    return [
        function("M_r", {"q_r": q_r, "quat": quat}, {"M_r": ca.densify(p.mass_matrix())}),
        function("CG_r", {"q_r": q_r, "qd_r": qd_r, "quat": quat}, {"CG_r": ca.densify(p.coriolis_gravity(qd_r))}),
        function("G_r", {"q_r": q_r, "quat": quat}, {"G_r": ca.densify(p.gravity())}),
        function("id_r", {"q_r": q_r, "qd_r": qd_r, "qdd_r": qdd_r, "quat": quat},
                 {"tau_r": ca.densify(p.inverse_dynamics(qd_r, qdd_r))}),
        function("fd_r", {"q_r": q_r, "qd_r": qd_r, "tau_ext": tau_ext, "quat": quat}, {"qdd_r": tau_ext}),
        *reduced_derivative_functions(robot, stance),
    ]


#: What each input and output name means: shape is printed from the Function itself.
SIGNAL_DOCS = {
    "q": "p [m, world frame], quaternion (x, y, z, w) of R (trunk -> world, need not be unit), "
    "12 joint angles [rad] in order FL, FR, BL, BR x (HAA, HFE, KFE)",
    "v": "v_b [m/s], omega_b [rad/s] (trunk frame), 12 joint rates [rad/s]",
    "a": "vdot: d/dt of v; trunk part is the SPATIAL acceleration vdot_b = a_b - omega_b x v_b "
    "[m/s^2], alpha_b [rad/s^2]; 12 joint accelerations [rad/s^2]",
    "f": "ground force on each foot FL, FR, BL, BR, trunk frame [N]",
    "M": "joint-space inertia matrix (6 trunk + 12 joints), column-major nonzeros [kg, kg m, kg m^2]",
    "C": "velocity terms C(q, v) (g = 0, a = 0): trunk force [N], moment [N m], joint torques [N m]",
    "G": "gravity terms G(q): trunk force [N], moment [N m] (trunk frame), joint torques [N m]",
    "nle": "C(q, v) + G(q), as Pinocchio's nonLinearEffects",
    "w_res": "base wrench residual: force [N], moment about the trunk origin [N m], trunk frame; "
    "zero when the foot forces produce the motion",
    "tau": "joint torques [N m]",
    "r_feet": "foot positions FL, FR, BL, BR relative to the trunk origin, trunk frame [m]",
    "J_feet": "feet's velocity Jacobian: R^T d/dt p_foot = J_feet v, rows of a foot [I, -[r]x, its leg's J] [m/rad]",
    "Jdv_feet": "R^T d2/dt2 p_foot - J_feet a = Jdot v + omega_b x (J_feet v): the feet's bias acceleration [m/s^2]",
    "lambda": "the GRF model's unknowns (minimum-norm solution), see quadruped_dyn/dynamics/grf.py",
    "residual": "part of the required trunk wrench the GRF model cannot balance: force [N], moment [N m]",
    "q_r": "reduced coordinates: 12 joint angles [rad] (FL, FR, BL, BR x HAA, HFE, KFE); for two stance feet a "
    "13th, the trunk roll phi [rad] (R = Rz(psi) Ry(theta) Rx(phi)), which these functions take from quat",
    "qd_r": "d/dt q_r [rad/s]; the 13th is the roll rate phid",
    "qdd_r": "d2/dt2 q_r [rad/s^2]; the 13th is the roll acceleration",
    "quat": "trunk orientation (x, y, z, w) of R (trunk -> world; need not be unit); must agree with the "
    "stance: it sets gravity in the trunk frame and, with two feet, the roll-rate row",
    "tau_ext": "joint torques [N m] (project order); for two feet a 13th entry, a moment about the "
    "foot-to-foot line [N m] applied as if the roll were actuated (0 on the robot)",
    "M_r": "reduced inertia matrix (n x n, column-major) = d tau_r / d qdd_r; not symmetric",
    "CG_r": "C_r(q_r, qd_r) + G_r(q_r): tau_r at qdd_r = 0 [N m]",
    "G_r": "tau_r at qd_r = 0, qdd_r = 0 [N m]",
    "tau_r": "12 joint torques [N m] with the paper's GRF model of the stance set; for two feet a 13th entry: "
    "the trunk moment about the foot-to-foot line (from foot 2 to foot 1) that the feet cannot produce [N m], "
    "0 for a motion the robot can make (the roll is unactuated)",
    # derivatives (qd_<robot>-d.c, docs/derivatives.md): d/dq along pinocchio.integrate, 18 columns
    "tau_full": "generalized force (18): trunk wrench (force [N], moment [N m], trunk frame), 12 joint torques [N m]",
    "dtau_dq": "d rnea / dq (18x18): columns along the tangent dq = (dv_b, dw_b, dq_joints), body-frame increment",
    "dtau_dv": "d rnea / dv (18x18)",
    "dtau_da": "d rnea / da = M (18x18)",
    "da_dq": "d a / dq (18x18, dense), a = M^-1 (tau_full - C - G); tangent columns as dtau_dq",
    "da_dv": "d a / dv (18x18, dense)",
    "da_dtau": "d a / d tau_full = M^-1 (18x18, dense)",
    "dq_r": "direction of q_r (n); its 13th entry (the roll) has no effect: the roll is read from quat",
    "dqd_r": "direction of qd_r (n)",
    "dtheta": "direction of the trunk orientation: body-frame rotation increment, quat -> quat (x) exp(dtheta / 2) [rad]",
    "dtau_r": "directional derivative of tau_r along (dq_r, dqd_r, dtheta) at fixed qdd_r (n)",
    "dqdd_dq": "d qdd_r / d q_r (n x n, dense) at fixed quat; its 13th column (the roll) is 0",
    "dqdd_dqd": "d qdd_r / d qd_r (n x n, dense)",
    "dqdd_dtau": "d qdd_r / d tau_ext = M_r^-1 (n x n, dense)",
    "dqdd_dtheta": "d qdd_r / d theta (n x 3, dense), theta as dtheta (total derivative along the stance: "
    "dqdd_dq + dqdd_dtheta W, W = d omega_b / d qd_r)",
    "w": "a trunk wrench (force [N], moment about the trunk origin [N m], trunk frame) for the GRF solve",
    "dq": "direction of q in the tangent (18): (dv_b, dw_b, dq_joints) as dtau_dq's columns",
    "lambda_w": "the GRF model's unknowns balancing the wrench w: P(q) w (minimum norm, as lambda)",
    "dlambda_w": "directional derivative of P(q) w along dq at fixed w (only the stance legs' joints enter)",
    "dlambda_dq": "d lambda / dq (m x 18, dense), tangent columns as dtau_dq",
    "dlambda_dv": "d lambda / dv (m x 18, dense)",
    "dlambda_da": "d lambda / da (m x 18, dense)",
}


def codegen_function(robot: Robot, name: str) -> ca.Function:
    """The generated Function ``name`` (a key of ``CODEGEN_FUNCTIONS``), renamed with the C prefix (same graph, no
    wrapper call, common subexpressions shared)."""
    f = CODEGEN_FUNCTIONS[name](robot)
    args = f.sx_in()
    return ca.Function(PREFIX + name, args, f.call(args), f.name_in(), f.name_out(), {"cse": True})


def codegen_functions(robot: Robot) -> list[ca.Function]:
    """The generated Functions, renamed with the C prefix (``codegen_function`` of each)."""
    return [codegen_function(robot, name) for name in CODEGEN_FUNCTIONS]


def library_functions(robot: Robot) -> list[ca.Function]:
    """Every generated Function, in the header's order: the full-coordinate terms and GRF solves, the
    reduced model of each stance set, the derivatives."""
    return [*codegen_functions(robot), *(f for s in REDUCED_STANCE_SETS for f in reduced_functions(robot, s)),
            *derivative_functions(robot)]


def _shape(sp: ca.Sparsity) -> str:
    shape = f"{sp.size1()}x{sp.size2()}" if sp.size2() > 1 else f"{sp.size1()}"
    return shape if sp.is_dense() else f"{shape}, {sp.nnz()} nonzeros"


def reduced_parts(name: str) -> tuple[str, StanceSet] | None:
    """('fd_r', stance) for 'fd_r_FL_BR'; None for a full-coordinate or GRF function."""
    for kind in REDUCED_NAMES + REDUCED_DERIVATIVE_NAMES:
        if name.startswith(kind + "_"):
            return kind, stance_set(name[len(kind) + 1 :].replace("_", "+"))
    return None


def _note(name: str) -> str:
    if name in ALIASES:
        return f"  [= {PREFIX}{ALIASES[name]}, by its algorithm's name]"
    if name.startswith("grf_"):
        stance = stance_set(name[4:].replace("_", "+"))
        return f"  [{stance.kind}, rank {stance.rank('paper')}]"
    reduced = reduced_parts(name)
    if name == "dfd_full":
        return "  [returns QD_NONFINITE / QD_SINGULAR / QD_NO_WORK]"
    if name.startswith("dgrf_") and not name.startswith("dgrf_dir_"):
        return "  [returns QD_NONFINITE / QD_NO_WORK]"
    if name in ("did_full", "dfd_full_parts") or name.startswith("dgrf_dir_"):
        return "  [returns QD_NONFINITE]"
    if not reduced:
        return ""
    # only the solves (fd_r, dfd_r) factor M_r: M_r, CG_r, G_r and id_r never return QD_SINGULAR
    singular = " / QD_SINGULAR" if reduced[0] in ("fd_r", "dfd_r") else ""
    no_work = " / QD_NO_WORK" if reduced[0] == "dfd_r" else ""
    return f"  [{reduced[1].kind}, returns QD_NONFINITE{singular} / QD_DEGENERATE{no_work}]"


#: The functions whose entry points read a null input pointer as zeros (CasADi's convention, kept by the generated
#: graphs and the GRF solves); the templates' entry points (reduced functions, dfd_full, dgrf, dfd_r) read every input.
NULL_INPUT_AS_ZEROS = ("M_full", "C_full", "G_full", "nle_full", "id_full", *ALIASES, "grf_<feet>", "did_full",
                       "dfd_full_parts", "dgrf_dir_<feet>")


def header_doc(robot: Robot, functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> str:
    """Documentation block: conventions, every signal once, every function's shapes and work sizes."""
    lines = [
        f"/* quadruped_dyn: generated dynamics of the robot '{robot.name}' ({robot.urdf.name}).",
        " * Generated by `quadruped-dyn codegen`; do not edit.",
        " * Feet (the contact points of the GRF solves and the reduced model): "
        + ", ".join(f"{leg.label} '{comment_text(leg.foot_frame)}'" for leg in robot.legs) + ".",
        " *",
        *_calling_doc(), *_grf_doc(), *_reduced_doc(), *_derivatives_doc(), *_functions_doc(functions, work),
        " */",
    ]
    return "\n".join(lines) + "\n"


def _calling_doc() -> list[str]:
    """How every generated function is called: arguments, work memory, null inputs, sparse outputs."""
    return [
        " * Call qd_NAME(arg, res, iw, w, 0): arg[i] points to input i, res[i] to output i (a null",
        " * res[i] skips it), iw and w are caller-provided work arrays of qd_NAME_SZ_IW and",
        " * qd_NAME_SZ_W entries. No malloc, no global state: thread-safe with per-thread work.",
        " * A null arg[i] reads as zeros (CasADi's convention) only in",
        f" * {', '.join(NULL_INPUT_AS_ZEROS)};",
        " * every other function dereferences each input: pass them all. No output may overlap an",
        " * input or another output (e.g. id_full's tau written over its input f gives wrong values).",
        " * Vectors are contiguous; a sparse output holds its nonzeros column by column in the",
        " * pattern qd_NAME_sparsity_out(i) returns (CasADi's compressed-column format: nrow, ncol,",
        " * colind[ncol + 1], row[nnz]); a dense input or output's pattern is the short form",
        " * {nrow, ncol, 1} (nrow x ncol entries, column-major), with no colind or row after it.",
        " * casadi_real is double unless defined before this header (e.g. -Dcasadi_real=float).",
        " * qd_NAME_batch(n, arg, res, status, w): n states, state-major (state s's input i at",
        " * arg[i] + s * nnz_i, outputs alike), one qd_NAME call each with work w of qd_NAME_SZ_W reals;",
        " * status[s] (if status is not NULL) gets state s's return code, a bad state does not stop the",
        " * others; returns the number of non-zero codes. Outputs equal one call's, bit for bit.",
        " *",
    ]


def _grf_doc() -> list[str]:
    """What the qd_grf_<feet> functions solve and where they do not detect a degenerate stance."""
    return [
        " * qd_grf_<feet>: the paper's GRF model for those stance feet (trunk-frame assumptions,",
        " * quadruped_dyn/dynamics/grf.py), minimum-norm solution. Where the model's rank is 5 (four feet,",
        " * two feet) `residual` carries the trunk wrench the feet cannot balance. At coincident or",
        " * collinear stance feet the system loses further rank and the outputs are meaningless;",
        " * this code does not detect that (quadruped_dyn's GrfSolve.solve does).",
        " *",
    ]


def _reduced_doc() -> list[str]:
    """The reduced model's functions, their return codes and the thresholds behind them."""
    return [
        " * Reduced model (paper section 5; quadruped_dyn/dynamics/reduced_projection.py), one set of functions per",
        " * stance set of 2, 3 or 4 feet, named qd_<fn>_<feet>: n = 12 coordinates (the joint angles) for",
        " * 3 or 4 stance feet, n = 13 for 2 (the 13th is the trunk roll phi, unactuated on the robot). The",
        " * trunk's motion follows from the stance feet staying on the ground; quat gives its orientation.",
        " *   M_r(q_r, quat)                  reduced inertia matrix, n x n column-major, not symmetric;",
        " *   CG_r(q_r, qd_r, quat)           C_r + G_r in one Newton-Euler pass;",
        " *   G_r(q_r, quat)                  gravity part;",
        " *   id_r(q_r, qd_r, qdd_r, quat)    tau_r = M_r qdd_r + C_r + G_r (paper's GRF model);",
        " *   fd_r(q_r, qd_r, tau_ext, quat)  qdd_r = M_r^-1 (tau_ext - C_r - G_r) (paper eq. (5)), on the stack",
        " *                                   (no work memory needed): with a swing leg, M_r is not formed: each",
        " *                                   swing leg is folded into the trunk's inertia (M's leg block, positive",
        " *                                   definite: no pivoting) and the rest solved with partial pivoting;",
        " *                                   four feet: M_r, then partial pivoting.",
        " * Each reduced file generates only the stance's pieces (regularity, S_b, T_b, the full v and a) and",
        " * calls qd_M_full, qd_G_full and qd_id_full of qd_<robot>.c: M_r = S M_full T, CG_r = S rnea(q, v, k),",
        " * G_r = S G_full, id_r = S rnea(q, v, T qdd_r + k) (link the reduced files with qd_<robot>.c).",
        " * Return codes: 0 ok; QD_NONFINITE (1) an output is NaN/inf: the trunk pitched +-90 deg (two feet:",
        " * the roll row has tan(pitch)), a zero quaternion (M_r with three or four feet does not depend on quat and",
        " * returns 0 for any) or a non-finite input the function reads. Every reduced function reads every entry",
        " * of its inputs except q_r's 13th with two feet (the roll: taken from quat) and quat in M_r with three or",
        " * four feet: a NaN there is not read and not reported. QD_SINGULAR (2, fd_r, dfd_r) M_r",
        " * singular to working precision (a pivot below QD_SINGULAR_RTOL times the largest entry of the matrix it",
        " * eliminates, M_r's, or a swing leg's block and the folded rest's), and in the float build also where the",
        " * result's error bound",
        f" * FLT_EPSILON x cond_1 of that matrix exceeds {FLOAT_MAX_BOUND:g} (so a float fd_r returned as 0 is",
        " * within 1 %);",
        " * (QD_SINGULAR_RTOL: reduced_templates.h, a multiple of casadi_real's epsilon; QD_REGULARITY_MIN:",
        " * each qd_<robot>-r-<feet>.c, quadruped_dyn.tolerances.REGULARITY_MIN; neither is in this header.)",
        " * QD_DEGENERATE (3) the stance is degenerate, checked first by",
        " * every reduced function: its regularity (quadruped_dyn/dynamics/stance_regularity.py, in [0, 1]) is",
        " * at most QD_REGULARITY_MIN (coincident or collinear stance feet, or two feet whose line is",
        " * perpendicular to the roll axis: the front or back pair at zero pitch or roll), where the model",
        " * is undefined and would return ~1e15, or two feet with the trunk pitched within"
        f" {TRUNK_PITCH_DEG_MARGIN:.1f} deg of +-90 deg,",
        f" * where the error {PITCH_ERR_PER_COS3:g} eps / cos(pitch)^3 exceeds {REL_TOL_TERMS:g}; in the float build"
        " also, with two feet, where the maps' error",
        f" * bound {FLOAT_ERR_PER_REGULARITY:g} x FLT_EPSILON / regularity exceeds {FLOAT_MAX_BOUND:g} (regularity below"
        f" {FLOAT_REGULARITY_MIN:.1e}:",
        " * the front or back pair near a level trunk). The outputs are not written on QD_SINGULAR or QD_DEGENERATE.",
        " * A stance leg stretched straight is not singular here: the reduced",
        " * model never inverts a leg's Jacobian (measured on the paper robot: cond(M_r) 1e3 -> 3e4).",
        " * Each function's codes are in its [returns ...] note below; one without that note returns 0",
        " * always (M_full, C_full, G_full, nle_full, id_full, grf_<feet>): test its outputs for NaN/inf.",
        " *",
    ]


def _derivatives_doc() -> list[str]:
    """The derivative functions: the increment d/dq is along, each function's outputs, work memory."""
    return [
        " * Derivatives (qd_<robot>-d.c; quadruped_dyn/dynamics/derivatives.py, docs/derivatives.md). d/dq is",
        " * along pinocchio.integrate(q, dq): dq (18) = (dv_b, dw_b, dq_joints), a body-frame (local) increment",
        " * of the trunk pose (p -> p + R dv_b, R -> R Exp([dw_b]x)), as Pinocchio's analytical derivatives;",
        " * no column is a derivative w.r.t. a quaternion entry, and the first three (position) are zero.",
        " *   did_full(q, v, a)               d rnea/dq, d rnea/dv, d rnea/da = M (rnea: no foot forces); sparse:",
        " *                                   d rnea/dq's position columns hold no entry,",
        " *                                   a leg's joint columns only the trunk's and that leg's rows;",
        " *   dfd_full_parts(q, v)            M (dense) and C + G;",
        " *   dfd_full(q, v, tau_full)        d a/dq, d a/dv, d a/dtau = M^-1 of a = M^-1 (tau_full - C - G):",
        " *                                   M^-1 by M's tree structure (legs' 3 x 3 blocks, then the trunk's",
        " *                                   Schur complement), -M^-1 d rnea/dx at a; temporaries in w. Returns",
        " *                                   QD_SINGULAR (2) if M is not positive definite to working precision.",
        " *   dgrf_dir_<feet>(q, w, dq)       the GRF solve for a trunk wrench w, P(q) w, and its derivative along dq;",
        " *   dgrf_<feet>(q, v, a)            d lambda/dq, d lambda/dv, d lambda/da of the GRF solve (1-4 feet):",
        " *                                   lambda = P(q) w_req is linear in w_req (rnea's trunk rows), so",
        " *                                   d lambda = P d w_req (did_full's trunk rows) + d(P w)/dq dq.",
        " * In each reduced file (the trunk orientation is the input quat: d/dq_r at fixed quat, the roll's",
        " * column 0; d/dtheta along quat -> quat (x) exp(dtheta/2), a body-frame increment):",
        " *   dfd_r_<feet>(q_r, qd_r, tau_ext, quat)  d qdd_r/dq_r, d qdd_r/dqd_r, d qdd_r/dtau_ext = M_r^-1,",
        " *                                   d qdd_r/dtheta: -M_r^-1 d id_r/dx by fd_r's LU, d id_r/dx by the chain",
        " *                                   rule over did_full and id_full (id_r = S rnea(q, v, a)); needs caller",
        " *                                   work memory w (its _work entry, _SZ_W); return codes as fd_r.",
        " * Work memory: a function whose _SZ_W is not 0 (dfd_full, dgrf_<feet>, dfd_r_<feet>) returns QD_NO_WORK",
        " * (4) for a null w and writes no output; the others never read iw or w (a null one is allowed).",
        " *",
    ]


def _functions_doc(functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> list[str]:
    """Every signal once, then every function's shapes, work sizes and caller memory."""
    signals = sorted({f.name_in(i) for f in functions for i in range(f.n_in())}
                     | {f.name_out(i) for f in functions for i in range(f.n_out())}, key=list(SIGNAL_DOCS).index)
    lines = [
        " * Signals:",
        # the names' column as wide as the longest name and a space (a fixed 9 ran dlambda_w into its text)
        *[f" *   {name:<{max(9, max(map(len, signals)) + 1)}}{SIGNAL_DOCS[name]}" for name in signals],
        " *",
        " * Functions (work sizes iw, w):",
    ]
    for f in functions:
        ins = ", ".join(f"{f.name_in(i)}[{_shape(f.sparsity_in(i))}]" for i in range(f.n_in()))
        outs = ", ".join(f"{f.name_out(i)}[{_shape(f.sparsity_out(i))}]" for i in range(f.n_out()))
        iw, w = work[f.name()]
        lines.append(f" *   {f.name()}({ins}) -> ({outs});  iw {iw}, w {w}{_note(f.name()[len(PREFIX):])}")
    return lines + memory_doc(functions, work)  # caller memory per function (docs/embedded.md)


_REDUCED_TEMPLATE_FILES = (SINCOS, "qd_dense.c", "qd_reduced_solve.c", "qd_reduced_derivatives.c")


def reduced_templates_h() -> str:
    """The text of ``REDUCED_TEMPLATES``: c/qd_sincos.c, c/qd_dense.c, c/qd_reduced_solve.c and
    c/qd_reduced_derivatives.c after the return codes, ``c/qd_prelude.h`` and the pieces' layouts (``c_facts``); they
    call the including file's precision wrappers (``precision_math``)."""
    body = prelude_c() + layouts_c() + "\n".join(template_c(t) for t in _REDUCED_TEMPLATE_FILES)
    return ("/* quadruped_dyn: the hand-written templates of the reduced model, included by every qd_<robot>-r-<feet>.c\n"
            " * after its generated pieces (quadruped_dyn/codegen/emit.py). Not a header to include elsewhere: its\n"
            " * functions are static and call the including file's qd_stance_maps, qd_M_full, qd_id_full, ... */\n"
            + body)


def float_err_per_regularity(stance: StanceSet) -> float:
    """The float build's error per FLT_EPSILON / regularity that stance set's reduced functions assume: with two feet
    the maps' rounding grows so (tolerances.FLOAT_ERR_PER_REGULARITY); 0 with three or four, where it does not."""
    return FLOAT_ERR_PER_REGULARITY if len(stance.feet) == 2 else 0.0


def _reduced_helpers_c(stance: StanceSet, dfd_r: DfdRPieces) -> str:
    """QD_REGULARITY_MIN, QD_FLOAT_MAX_BOUND, QD_FLOAT_ERR_PER_REGULARITY, ``qd_stance_maps`` ((r, quat) ->
    (regularity, W, Y[, y_e, s_e, D]): ``codegen.forms.stance_maps``, from which with the library's qd_foot_trig the
    templates' qd_parts forms S_b, T_b, v and a) and dfd_r's ``qd_dfd_r_lift`` (``emit_derivatives.dfd_r_pieces``),
    the generated pieces the templates call."""
    return (regularity_c(float_err_per_regularity(stance))
            + static_c("qd_stance_maps", stance_maps(stance), all_io=True) + "\n"
            + f"#define QD_DFD_R_TAPE {dfd_r.tape} /* reals of the lift's tape: emit_derivatives.split_at_seeds */\n"
            + f"#define QD_DID_FULL_L {dfd_r.did_legs} /* reals of did_full's legs' outputs: codegen.by_leg.legs_reals */\n"
            + static_c("qd_dfd_r_lift", dfd_r.lift, all_io=True) + "\n" + _lift_derivative_c(dfd_r))


def _lift_derivative_c(dfd_r: DfdRPieces) -> str:
    """The lift's derivative dfd_r calls: qd_dfd_r_lift_columns (every direction at once, QD_DFD_R_LIFT_COLUMNS
    columns), and at -Os, the embedded builds' size budget, qd_dfd_r_lift_dir (one direction per call;
    docs/derivatives.md)."""
    one = static_c("qd_dfd_r_lift_dir", dfd_r.lift_dir, all_io=True)
    return ("#if !defined(__OPTIMIZE_SIZE__) /* the lift's columns at once; at -Os one direction per call */\n"
            f"#define QD_DFD_R_LIFT_COLUMNS {dfd_r.lift_columns.size2_out(0)} /* emit_derivatives.lift_seeds */\n"
            + static_c("qd_dfd_r_lift_columns", dfd_r.lift_columns, all_io=True)
            + "#else\n" + one + "#endif\n")


def _reduced_source(stem: str, functions: list[ca.Function], helpers_c: str, dfd_r: DfdRPieces,
                    precision: str) -> tuple[str, str, dict[str, tuple[int, int]]]:
    """A reduced file: ``helpers_c`` (``_reduced_helpers_c``) and the include of ``REDUCED_TEMPLATES``, and the entry
    points calling them: every function returns QD_DEGENERATE at a degenerate stance and
    QD_NONFINITE for a non-finite output; M_r, CG_r, G_r and id_r by ``qd_reduced_term`` over the generated
    qd_stance_maps and the library's qd_foot_trig, qd_M_full, qd_G_full, qd_id_full (no unrolled graph of their own:
    ~160 kB per stance set); fd_r by ``qd_fd_r_solve`` (the parts once for M_r and C_r + G_r, checked
    once, then the LU); dfd_r by ``c/qd_reduced_derivatives.c`` over ``dfd_r``'s pieces, its caller work memory
    declared. Returns (C source, header, work sizes)."""
    stance = reduced_parts(functions[0].name()[len(PREFIX):])[1]  # type: ignore[index]
    legs = sum(1 << i for i in stance.feet)  # S_b's rows and T_b's columns of the other legs' joints are zero
    n_r = functions[0].size1_out(0)
    evals = "".join(f"static int qd_{kind}_eval{SIGNATURE} {{\n  return qd_reduced_term({n_r}, {legs}, {which}, arg, res, iw, "
                    "w, mem);\n}\n" for which, kind in enumerate(("M_r", "CG_r", "G_r", "id_r")))
    entries = []
    for f in functions:
        if f.sz_arg() != f.n_in():
            raise AssertionError(f"{f.name()} needs work memory; qd_fd_r_solve assumes it does not")
        sz_w = 0
        if f.name().startswith(PREFIX + "fd_r_"):
            body = f"  return qd_fd_r_solve({f.nnz_out(0)}, {legs}, arg, res, iw, w, mem);\n"
        elif f.name().startswith(PREFIX + "dfd_r_"):  # caller work memory; its size checked at compile time
            n, sz_w = f.size1_out(0), dfd_r_work_reals(f.size1_out(0), dfd_r.tape, dfd_r.did_legs)
            body = (f"  typedef char w_agrees[QD_DFD_R_W({n}) == {sz_w} ? 1 : -1];\n"
                    "  (void)sizeof(w_agrees);\n"
                    f"  return qd_dfd_r_solve({n}, {dfd_r.legs}, {int(dfd_r.lift_reads_quat)}, arg, res, iw, w, mem);\n")
        else:
            nnz = ", ".join(str(f.nnz_out(i)) for i in range(f.n_out()))
            evaluation = f"qd_{reduced_parts(f.name()[len(PREFIX):])[0]}_eval"  # type: ignore[index]
            body = f"  return qd_finite({evaluation}(arg, res, iw, w, mem), res, 1, (const casadi_int[]){{{nnz}}});\n"
        entries.append(Entry(f, None, body, sz_w))
    preamble = helpers_c + f'\n#include "{REDUCED_TEMPLATES}"\n' + evals + "\n"
    options = FileOptions(precision, preamble=preamble, precision_math=True, included=reduced_templates_h())
    return (*c_file(stem, entries, options), entry_work(entries))


#: The full terms whose C evaluates the joint rows first (``_joint_rows_first``); the GRF solves call id_full's.
JOINT_ROWS_FIRST = ("M_full", "G_full", "nle_full", "id_full")
#: Of those, the ones qd_<robot>.c also exports as qd_<name>_trig (arg: theirs, then sin and cos of q's joint angles)
#: for the reduced files, which take the sines and cosines once per call (c/qd_reduced_solve.c); with
#: qd_M_full_dense_trig (``_M_full_dense``), and qd_id_full_trig and qd_M_blocks_legs_trig leg by leg
#: (``_reduced_calls_by_leg``).
TRIG_GIVEN = ("G_full",)
#: qd_id_full_trig's arg (q, v, a, sin, cos) and qd_M_blocks_legs_trig's (q, sin, cos) as their pieces read them
#: (``codegen.forms.leg_pieces``): the reduced files' calls, leg by leg (``_reduced_calls_by_leg``).
ID_FULL_CALL = LegCall(head_args=(0, 1, 2), leg_inputs=(("arg", 1, 3), ("arg", 2, 3), ("head", 0), ("joint", 0, 7),
                                                        ("joint", 1, 6), ("joint", 2, 6)),
                       sin_arg=3, tail_args=(0, 1, 2))
M_BLOCKS_CALL = LegCall(head_args=(), leg_inputs=(("joint", 0, 7),), sin_arg=1, tail_args=())


def _joint_rows_first(robot: Robot, functions: list[ca.Function], host_helpers: frozenset[str]) -> tuple[str, dict[str, str]]:
    """Evaluate M_full, G_full, nle_full and id_full joint rows first (M_full: its joint columns). CasADi's C
    evaluates a graph output by output, each depth first: the trunk rows come first and gather all four legs,
    so the legs' recursions interleave and their temporaries are live together (spilled: x86-64 has 16
    registers). With the joint rows first each leg's recursion runs to its end before the next starts and
    the trunk rows then add up the legs' wrenches. Each entry point calls a static qd_<name>_eval of its own
    signature: the same graph with its outputs in that order (``static_c``) and mapped back (no evaluation in the
    signature's order); for a function in ``UNGUARDED`` the graph reads its inputs untested and
    qd_<name>_eval gives a NULL input qd_zeros. The same operations on the same values (docs/benchmark.md). For the
    reduced files the graphs are also exported with the joints' sines and cosines as inputs (no NULL input):
    qd_<name>_trig for ``TRIG_GIVEN``, qd_M_full_dense_trig (``_M_full_dense``); qd_id_full_trig and
    qd_M_blocks_legs_trig leg by leg (``_reduced_calls_by_leg``). Returns (the C, entry point name -> its body)."""
    helpers, bodies = [], {}
    for f in functions:
        name = f.name()[len(PREFIX):]
        if name not in JOINT_ROWS_FIRST:
            continue
        args = f.sx_in()
        outs = f.call(args)
        if name == "id_full":  # (w_res, tau): the torques first
            ordered, res = [outs[1], outs[0]], "{res[1], res[0]}"
        else:  # one output, compressed-column nonzeros: rows 6..17 of a vector, columns 6..17 of M
            nz = outs[0].nz[:]  # column vector of the nonzeros
            k = 6 if f.size2_out(0) == 1 else int(f.sparsity_out(0).colind()[6])
            ordered, res = [nz[k:], nz[:k]], f"{{res[0] ? res[0] + {k} : 0, res[0]}}"
        if f.n_out() != (2 if name == "id_full" else 1) or f.sz_arg() != f.n_in():
            raise AssertionError(f"{f.name()}: not the signature _joint_rows_first reorders")
        if f.name_in(0) != "q" or f.nnz_in(0) != NQ_FULL or max(f.nnz_in(i) for i in range(f.n_in())) > NQ_FULL:
            raise AssertionError(f"{f.name()}: not (q (19), ...) with inputs no longer than qd_zeros")
        body = trig_as_inputs(ca.Function(f"{name}_joint_rows_first", args, ordered, {"cse": True}), 0, JOINT_ANGLES)
        static = static_c(f"qd_{name}_joint_rows_first", body, host_helpers, inputs_given=name in UNGUARDED)
        if name in UNGUARDED:  # a NULL input reads as zeros, as CasADi's tests gave it
            a_init = [f"arg[{i}] ? arg[{i}] : qd_zeros" for i in range(f.n_in())]
        else:
            a_init = [f"arg[{i}]" for i in range(f.n_in())]
        n = len(JOINT_ANGLES)
        if name in TRIG_GIVEN:
            static += (f"/* {name} with the joints' sines and cosines given: arg = ({', '.join(f.name_in())}, sin, cos) */\n"
                       f"int qd_{name}_trig{SIGNATURE} {{\n  casadi_real* r[2] = {res};\n"
                       f"  return qd_{name}_joint_rows_first(arg, r, iw, w, mem);\n}}\n")
        helpers.append(static + f"static int qd_{name}_eval{SIGNATURE} {{\n"
                       f"  casadi_real c[{n}], s[{n}]; /* the joints' cosines and sines, once (qd_sincos) */\n"
                       f"  qd_sincos({n}, (arg[0] ? arg[0] : qd_zeros) + {JOINT_ANGLES.start}, c, s);\n"
                       f"  const casadi_real* a[{f.n_in() + 2}] = {{{', '.join([*a_init, 's', 'c'])}}};\n"
                       f"  casadi_real* r[2] = {res};\n"
                       f"  return qd_{name}_joint_rows_first(a, r, iw, w, mem);\n}}\n")
        bodies[f.name()] = f"  return qd_{name}_eval(arg, res, iw, w, mem);\n"
    helpers.append(_M_full_dense(functions, host_helpers))
    helpers.append(_reduced_calls_by_leg(robot, host_helpers))
    helpers.insert(0, template_c(SINCOS)
                   + f"static const casadi_real qd_zeros[{NQ_FULL}]; /* a NULL input (CasADi's convention: zeros) */\n")
    return "\n".join(helpers), bodies


def _M_full_dense(functions: list[ca.Function], host_helpers: frozenset[str]) -> str:
    """qd_M_full_dense_trig (q, sin, cos) -> M (18 x 18, dense column-major): M_full's graph with its zeros written
    and the joints' sines and cosines given, joint columns first (as ``_joint_rows_first``), for the reduced files,
    which take the sines and cosines once for all their calls and read M dense (c/qd_reduced_solve.c)."""
    m = next(f for f in functions if f.name() == PREFIX + "M_full")
    args = m.sx_in()
    nz = ca.densify(m.call(args)[0]).nz[:]  # column-major, 18 x 18
    k = 18 * 6  # the joint columns first
    dense = trig_as_inputs(ca.Function("M_full_dense", args, [nz[k:], nz[:k]], {"cse": True}), 0, JOINT_ANGLES)
    return (static_c("qd_M_full_dense_joint_rows_first", dense, host_helpers, all_io=True)
            + "/* M_full (18 x 18, dense column-major, zeros written) with the joints' sines and cosines given: arg = "
            "(q, sin, cos) */\n"
            f"int qd_M_full_dense_trig{SIGNATURE} {{\n"
            f"  casadi_real* r[2] = {{res[0] + {k}, res[0]}};\n"
            "  return qd_M_full_dense_joint_rows_first(arg, r, iw, w, mem);\n}\n")


def _reduced_calls_by_leg(robot: Robot, host_helpers: frozenset[str]) -> str:
    """qd_id_full_trig (q, v, a, sin, cos) -> (w_res, tau) (no foot forces) and qd_M_blocks_legs_trig (q, sin, cos) ->
    M's nonzero blocks (``by_leg.mass_blocks``: fd_r's), the joints' sines and cosines given, each as one leg function
    per leg template called once per leg (``codegen.forms.leg_pieces``, ``codegen.by_leg``), whose code stays in the instruction
    cache: for the reduced files' fd_r, C_r + G_r, id_r and dfd_r (c/qd_reduced_solve.c), which call them among ~45 kB
    of other code per call (docs/benchmark.md, "Design choices"). M_r calls ``_M_full_dense``'s
    qd_M_full_dense_trig, one function of fewer instructions, which fits the cache beside M_r's other ~20 kB."""
    return ("/* id_full without foot forces, the joints' sines and cosines given, leg by leg: arg = (q, v, a, sin, cos) */\n"
            + by_leg_c("qd_id_full_trig", id_full_pieces(robot), ID_FULL_CALL, host_helpers) + "\n"
            "/* M_full's nonzero blocks (M_bb, then per leg M_bl and M_ll, column-major: codegen/forms/leg_pieces.py, "
            "mass_blocks) with the joints' sines and cosines given, leg by leg: arg = (q, sin, cos) */\n"
            + by_leg_c("qd_M_blocks_legs_trig", mass_matrix_pieces(robot), M_BLOCKS_CALL, host_helpers) + "\n"
            "/* a leg's foot kinematics (codegen/forms/leg_pieces.py, FOOT_PARTS), the joints' sines and cosines given: "
            "y = (r, J, J qd_l, Jdot qd_l), trunk frame */\n"
            + foot_c("qd_foot_trig", foot_pieces(robot), host_helpers))


def _grf_through_id_full(robot: Robot, functions: list[ca.Function],
                         host_helpers: frozenset[str]) -> tuple[str, dict[str, str]]:
    """Route every qd_grf_<feet> of qd_<robot>.c through ``c/qd_grf_solve.c``: id_full's evaluation (one
    Newton-Euler pass) and a generated static qd_grf_balance_<feet> (``grf.grf_balance``), instead of
    the unrolled graph, which repeats the recursion in each of the 15 (~0.4 MB per robot). Returns (the C, entry
    point name -> its body)."""
    id_full = next(f for f in functions if f.name() == PREFIX + "id_full")
    if id_full.name_in() != ["q", "v", "a", "f"] or id_full.name_out() != ["w_res", "tau"] or id_full.sz_arg() != 4:
        raise AssertionError("qd_grf_solve calls id_full as (q, v, a, f) -> (w_res, tau) with no work memory")
    q, w_req = ca.SX.sym("q", NQ_FULL), ca.SX.sym("w_req", 6)
    helpers = [f"#define QD_ID_FULL_EVAL {PROVIDED['QD_ID_FULL_EVAL']} /* _joint_rows_first */\n"
               + template_c("qd_grf_solve.c")]
    bodies = {}
    for f in functions:
        if not f.name().startswith(PREFIX + "grf_"):
            continue
        suffix = f.name()[len(PREFIX + "grf_"):]
        b = grf_balance(robot, stance_set(suffix.replace("_", "+")), "paper", q[7:], w_req)
        balance = ca.Function(f"grf_balance_{suffix}", [q, w_req], [b.lam, b.f, b.residual, b.tau], {"cse": True})
        if [balance.sparsity_out(i) for i in range(3)] != [f.sparsity_out(i) for i in range(3)]:
            raise AssertionError(f"{f.name()}: the balance's outputs are not the GRF function's")
        helpers.append(static_c(f"qd_grf_balance_{suffix}", balance, host_helpers))
        bodies[f.name()] = ("  casadi_real w_req[6], tau_0[12], tau_f[12];\n"
                            "  const casadi_real* b_arg[2] = {arg[0], w_req};\n"
                            "  casadi_real* b_res[4] = {res[0], res[1], res[2], tau_f};\n"
                            "  int flag = qd_grf_begin(arg, w_req, tau_0, iw, w, mem);\n"
                            f"  if (!flag) flag = qd_grf_balance_{suffix}(b_arg, b_res, iw, w, mem);\n"
                            "  return flag ? flag : qd_grf_end(res, tau_0, tau_f);\n")
    return "\n".join(helpers), bodies


def _full_source(robot: Robot, stem: str, functions: list[ca.Function],
                 precision: str) -> tuple[str, str, dict[str, tuple[int, int]]]:
    """qd_<robot>.c: the full terms joint rows first (``_joint_rows_first``), the GRF solves through id_full
    (``_grf_through_id_full``), the other functions CasADi's graphs. Returns (C source, header, work sizes)."""
    host_helpers = file_helpers(functions)
    joint_rows, bodies = _joint_rows_first(robot, functions, host_helpers)
    grf, grf_bodies = _grf_through_id_full(robot, functions, host_helpers)
    bodies.update(grf_bodies)
    bodies.update({PREFIX + alias: f"  return {PREFIX}{name}(arg, res, iw, w, mem);\n" for alias, name in ALIASES.items()})
    entries = [Entry(f, None, bodies[f.name()]) if f.name() in bodies else Entry(f, EVALUATION) for f in functions]
    c_text, h_text = c_file(stem, entries, FileOptions(precision, preamble=joint_rows + "\n" + grf + "\n",
                                                       precision_math=True))
    return c_text, h_text, entry_work(entries)


def generate(robot: Robot, out_dir: Path, precision: str = "double",
             extra_files: Callable[[list[ca.Function], dict[str, tuple[int, int]]], dict[str, str]] | None = None,
             ) -> GeneratedFiles:
    """Write into ``out_dir``: qd_<robot>.c (full-coordinate terms and GRF solves), qd_<robot>.h
    (one header for all), the files ``extra_files(functions, work sizes)`` returns (e.g. the
    reference values of ``checks.check_program_values``), check_qd.c, the Cortex-M start-up files and check_threads.c
    (docs/embedded.md), the Makefile, qd_<robot>-r-<feet>.c (the reduced model of each stance set
    of 2-4 feet) and qd_<robot>-d.c (derivatives); returns them by role (``GeneratedFiles``)."""
    if precision not in ("double", "float"):
        raise InputError(f"precision '{precision}' is not supported; expected 'double' or 'float'")
    out_dir = Path(out_dir)
    layout = file_layout(robot.name, out_dir)
    check_no_collision(layout, robot.name, out_dir)  # before the work: another robot's files are never written over
    out_dir.mkdir(parents=True, exist_ok=True)
    full = codegen_functions(robot)
    c_full, casadi_header, work = _full_source(robot, casadi_name(layout.source), full, precision)
    sources = {layout.source: c_full}
    functions = list(full)
    for stance, path in zip(REDUCED_STANCE_SETS, layout.reduced, strict=True):
        reduced = reduced_functions(robot, stance)
        dfd_r = dfd_r_pieces(robot, stance)
        sources[path], h_text, reduced_work = _reduced_source(casadi_name(path), reduced,
                                                              _reduced_helpers_c(stance, dfd_r), dfd_r, precision)
        casadi_header += h_text
        work.update(reduced_work)
        functions += reduced
    derivatives = derivative_functions(robot)  # qd_<robot>-d.c: derivatives of the full dynamics
    (derivative_path,) = layout.derivatives
    sources[derivative_path], h_text, derivative_work = derivative_source(robot, casadi_name(derivative_path),
                                                                          derivatives, precision)
    casadi_header += h_text
    work.update(derivative_work)
    functions += derivatives
    did = next(f for f in functions if f.name() == PREFIX + "did_full")
    if any(work[PREFIX + g] != (0, 0) for g in ("M_full", "G_full", "id_full", "nle_full", "did_full")) or (
            did.sz_arg() != 3 or (did.name_in(), did.name_out()) != (["q", "v", "a"], ["dtau_dq", "dtau_dv", "dtau_da"])):
        raise AssertionError("qd_dfd_r_solve calls id_full and did_full (q, v, a) -> (dtau_dq, dtau_dv, dtau_da), "
                             "the reduced terms M_full, G_full and id_full, qd_dfd_full_parts M_full and nle_full, "
                             "with no work memory of their own")
    extra = extra_files(functions, work) if extra_files else {}
    layout = file_layout(robot.name, out_dir, tuple(extra))
    texts = {
        **sources,
        layout.header: header_doc(robot, functions, work) + return_codes_c() + casadi_header,
        **{layout.extra[f]: text for f, text in extra.items()},
        layout.check_program: (TEMPLATES / "check_qd.c").read_text(),
        **{path: (TEMPLATES / path.name).read_text() for path in layout.embedded},  # docs/embedded.md
        layout.makefile: (TEMPLATES / "Makefile").read_text(),  # robot-independent: ROBOT defaults to the header's
        layout.reduced_templates: reduced_templates_h(),
    }
    with output_set():  # the package appears whole: an interrupt never leaves new sources beside old ones
        for path in layout.all():
            write_text(output_path(out_dir, path.name), texts[path])  # under out_dir, never through a link
    return layout


