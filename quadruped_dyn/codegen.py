"""Standalone C code generation (SPEC section 7).

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

import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin

from .errors import InputError
from .grf import STANCE_SETS, StanceSet, grf_solve, stance_set
from .leg import skew as skew_np
from .newton_euler import full_dynamics
from .pinocchio_ref import PinocchioReference
from .pinocchio_ref import roll_rate_row as roll_rate_row_np
from .reduced_projection import reduced_projection
from .robot import Robot
from .state import NV_FULL, FullState, full_q, rotation
from .tolerances import FLOAT_REL_TOL, GRF_COND_ASSUMED, MAP_COND_ASSUMED, REL_TOL_TERMS

PREFIX = "qd_"

def _grf_paper(stance: StanceSet) -> Callable[[Robot], ca.Function]:
    return lambda robot: grf_solve(robot, stance, "paper").function


#: name -> builder; adding a generated function is one line here.
CODEGEN_FUNCTIONS: dict[str, Callable[[Robot], ca.Function]] = {
    "M_full": lambda r: full_dynamics(r).M_full_crba,  # = Walker-Orin M (tested), fewer operations
    "C_full": lambda r: full_dynamics(r).C_full,
    "G_full": lambda r: full_dynamics(r).G_full,
    "nle_full": lambda r: full_dynamics(r).nle_full,
    "id_full": lambda r: full_dynamics(r).id_full,
    **{f"grf_{s.name.replace('+', '_')}": _grf_paper(s) for s in STANCE_SETS},
}

#: Stance sets with a reduced model (SPEC section 5): four feet, the four triples, the six pairs.
REDUCED_STANCE_SETS: tuple[StanceSet, ...] = tuple(st for st in STANCE_SETS if len(st.feet) >= 2)

#: Reduced-model functions generated for every stance set in REDUCED_STANCE_SETS, as
#: qd_<name>_<feet> (feet joined by '_'), each in the file qd_<robot>_r_<feet>.c.
REDUCED_NAMES = ("M_r", "CG_r", "G_r", "id_r", "fd_r")


def reduced_symbol(name: str, stance: StanceSet) -> str:
    """C name (without prefix) of reduced function ``name`` of a stance set, e.g. 'fd_r_FL_BR'."""
    return f"{name}_{stance.name.replace('+', '_')}"


def reduced_functions(robot: Robot, stance: StanceSet) -> list[ca.Function]:
    """The generated reduced functions of one stance set (``reduced_projection``'s forms),
    named with the C prefix. ``fd_r`` is a signature only (qdd_r = tau_ext): its generated body
    is replaced by the hand-written solve of ``c/qd_reduced_solve.c``."""
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
    "lambda": "the GRF model's unknowns (minimum-norm solution), see quadruped_dyn/grf.py",
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
}


def codegen_functions(robot: Robot) -> list[ca.Function]:
    """The generated Functions, renamed with the C prefix (same graphs, no wrapper call)."""
    out = []
    for name, build in CODEGEN_FUNCTIONS.items():
        f = build(robot)
        args = f.sx_in()
        out.append(ca.Function(PREFIX + name, args, f.call(args), f.name_in(), f.name_out(), {"cse": True}))
    return out


def _shape(sp: ca.Sparsity) -> str:
    shape = f"{sp.size1()}x{sp.size2()}" if sp.size2() > 1 else f"{sp.size1()}"
    return shape if sp.is_dense() else f"{shape}, {sp.nnz()} nonzeros"


def _reduced_parts(name: str) -> tuple[str, StanceSet] | None:
    """('fd_r', stance) for 'fd_r_FL_BR'; None for a full-coordinate or GRF function."""
    for kind in REDUCED_NAMES:
        if name.startswith(kind + "_"):
            return kind, stance_set(name[len(kind) + 1 :].replace("_", "+"))
    return None


def _note(name: str) -> str:
    if name.startswith("grf_"):
        stance = stance_set(name[4:].replace("_", "+"))
        return f"  [{stance.kind}, rank {stance.rank('paper')}]"
    reduced = _reduced_parts(name)
    return f"  [{reduced[1].kind}, returns QD_NONFINITE / QD_SINGULAR]" if reduced else ""


def header_doc(robot: Robot, functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> str:
    """Documentation block: conventions, every signal once, every function's shapes and work sizes."""
    signals = sorted({f.name_in(i) for f in functions for i in range(f.n_in())}
                     | {f.name_out(i) for f in functions for i in range(f.n_out())}, key=list(SIGNAL_DOCS).index)
    lines = [
        f"/* quadruped_dyn: generated dynamics of the robot '{robot.name}' ({robot.urdf.name}).",
        " * Generated by `quadruped-dyn codegen`; do not edit.",
        " *",
        " * Call qd_NAME(arg, res, iw, w, 0): arg[i] points to input i, res[i] to output i (a null",
        " * res[i] skips it), iw and w are caller-provided work arrays of qd_NAME_SZ_IW and",
        " * qd_NAME_SZ_W entries. No malloc, no global state: thread-safe with per-thread work.",
        " * Vectors are contiguous; a sparse output holds its nonzeros column by column in the",
        " * pattern qd_NAME_sparsity_out(i) returns (CasADi's compressed-column format).",
        " * casadi_real is double unless defined before this header (e.g. -Dcasadi_real=float).",
        " *",
        " * qd_grf_<feet>: the paper's GRF model for those stance feet (trunk-frame assumptions,",
        " * quadruped_dyn/grf.py), minimum-norm solution. Where the model's rank is 5 (four feet,",
        " * two feet) `residual` carries the trunk wrench the feet cannot balance. At coincident or",
        " * collinear stance feet the system loses further rank and the outputs are meaningless;",
        " * this code does not detect that (quadruped_dyn's GrfSolve.solve does).",
        " *",
        " * Reduced model (paper section 5; quadruped_dyn/reduced_projection.py), one set of functions per",
        " * stance set of 2, 3 or 4 feet, named qd_<fn>_<feet>: n = 12 coordinates (the joint angles) for",
        " * 3 or 4 stance feet, n = 13 for 2 (the 13th is the trunk roll phi, unactuated on the robot). The",
        " * trunk's motion follows from the stance feet staying on the ground; quat gives its orientation.",
        " *   M_r(q_r, quat)                  reduced inertia matrix, n x n column-major, not symmetric;",
        " *   CG_r(q_r, qd_r, quat)           C_r + G_r in one Newton-Euler pass;",
        " *   G_r(q_r, quat)                  gravity part;",
        " *   id_r(q_r, qd_r, qdd_r, quat)    tau_r = M_r qdd_r + C_r + G_r (paper's GRF model);",
        " *   fd_r(q_r, qd_r, tau_ext, quat)  qdd_r = M_r^-1 (tau_ext - C_r - G_r) (paper eq. (5)), by LU",
        " *                                   with partial pivoting on the stack (no work memory needed).",
        " * Return codes: 0 ok; QD_NONFINITE (1) an output is NaN/inf: coincident or collinear stance feet,",
        " * the trunk pitched +-90 deg (two feet: the roll row has tan(pitch)), a zero quaternion or a",
        " * non-finite input; QD_SINGULAR (2, fd_r only) M_r singular to working precision (an LU pivot",
        " * below QD_SINGULAR_RTOL max|M_r|, e.g. two feet, the trunk pitched within ~1e-12 rad of 90 deg);",
        " * qdd_r is not written then. A stance leg stretched straight is not singular here: the reduced",
        " * model never inverts a leg's Jacobian (measured on the paper robot: cond(M_r) 1e3 -> 3e4).",
        " *",
        " * Signals:",
        *[f" *   {name:<9}{SIGNAL_DOCS[name]}" for name in signals],
        " *",
        " * Functions (work sizes iw, w):",
    ]
    for f in functions:
        ins = ", ".join(f"{f.name_in(i)}[{_shape(f.sparsity_in(i))}]" for i in range(f.n_in()))
        outs = ", ".join(f"{f.name_out(i)}[{_shape(f.sparsity_out(i))}]" for i in range(f.n_out()))
        iw, w = work[f.name()]
        lines.append(f" *   {f.name()}({ins}) -> ({outs});  iw {iw}, w {w}{_note(f.name()[len(PREFIX):])}")
    lines.append(" */")
    return "\n".join(lines) + "\n"


def work_sizes(casadi_header: str) -> dict[str, tuple[int, int]]:
    sizes = dict(re.findall(r"#define (\w+_SZ_(?:IW|W)) (\d+)", casadi_header))
    names = {k.rsplit("_SZ_", 1)[0] for k in sizes}
    return {n: (int(sizes[f"{n}_SZ_IW"]), int(sizes[f"{n}_SZ_W"])) for n in names}


_UNUSED = "(void)arg; (void)res; (void)iw; (void)w; (void)mem;"


def _silence_unused_parameters(c_source: str) -> str:
    """CasADi's evaluation functions ignore some of their five parameters and its
    release hooks ignore ``mem``: cast them to void so -Wextra -Werror passes."""
    c_source = re.sub(r"(static int casadi_f\d+\([^)]*\) \{\n)", lambda m: m.group(1) + f"  {_UNUSED}\n", c_source)
    return re.sub(r"(void \w+_release\(int mem\) \{\n)", lambda m: m.group(1) + "  (void)mem;\n", c_source)


TEMPLATES = Path(__file__).resolve().parent / "c"


def stem(robot: Robot) -> str:
    return f"qd_{re.sub(r'[^A-Za-z0-9_]', '_', robot.name)}"


def _casadi_c(file_stem: str, functions: list[ca.Function], precision: str) -> tuple[str, str]:
    """(C source, CasADi's header) of ``functions`` generated into ``file_stem``.c."""
    cg = ca.CodeGenerator(f"{file_stem}.c", {"with_header": True, "casadi_real": precision})
    for f in functions:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        return _silence_unused_parameters((Path(tmp) / f"{file_stem}.c").read_text()), (Path(tmp) / f"{file_stem}.h").read_text()


def _entry_point(name: str) -> str:
    return (rf"(CASADI_SYMBOL_EXPORT int {name}\(const casadi_real\*\* arg, casadi_real\*\* res, casadi_int\* iw, "
            rf"casadi_real\* w, int mem\)\{{\n)  return (casadi_f\d+)\(arg, res, iw, w, mem\);\n")


def _checked_reduced_c(c_text: str, casadi_header: str, functions: list[ca.Function]) -> str:
    """Insert ``c/qd_reduced_solve.c`` and route the entry points through it: every function
    returns QD_NONFINITE for a non-finite output; fd_r evaluates M_r and CG_r (CasADi's own
    evaluation functions, checked once in the solve) and solves M_r qdd_r = tau_ext - CG_r."""
    first = c_text.index(f"\n/* {functions[0].name()}:")
    c_text = c_text[:first] + "\n" + (TEMPLATES / "qd_reduced_solve.c").read_text() + c_text[first:]
    work = work_sizes(casadi_header)
    raw = {}  # entry point -> CasADi's static evaluation function
    for f in functions:
        found = re.search(_entry_point(f.name()), c_text)
        if not found:
            raise AssertionError(f"entry point of {f.name()} not found in CasADi's output")
        raw[f.name()] = found.group(2)
    for f in functions:
        if f.sz_arg() != f.n_in() or work[f.name()] != (0, 0):
            raise AssertionError(f"{f.name()} needs work memory; qd_fd_r_solve assumes it does not")
        if f.name().startswith(PREFIX + "fd_r_"):
            m_r, cg_r = (raw[g.name()] for g in functions if g.name().startswith((PREFIX + "M_r_", PREFIX + "CG_r_")))
            body = rf"\1  (void)\2;\n  return qd_fd_r_solve({f.nnz_out(0)}, {m_r}, {cg_r}, arg, res, iw, w, mem);\n"
        else:
            nnz = ", ".join(str(f.nnz_out(i)) for i in range(f.n_out()))
            body = rf"\1  return qd_finite(\2(arg, res, iw, w, mem), res, {f.n_out()}, (const casadi_int[]){{{nnz}}});\n"
        c_text, count = re.subn(_entry_point(f.name()), body, c_text)
        if count != 1:
            raise AssertionError(f"entry point of {f.name()} not found in CasADi's output")
    return c_text


def generate(robot: Robot, out_dir: Path, precision: str = "double", reference: bool = True) -> list[Path]:
    """Write into ``out_dir``: qd_<robot>.c (full-coordinate terms and GRF solves), qd_<robot>.h
    (one header for all), qd_<robot>_reference.h (Pinocchio's values for check_qd.c; skipped
    with ``reference=False``), check_qd.c, the Makefile, and qd_<robot>_r_<feet>.c (the reduced
    model of each stance set of 2-4 feet). Returns the paths in that order."""
    if precision not in ("double", "float"):
        raise InputError(f"precision '{precision}' is not supported; expected 'double' or 'float'")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    name = stem(robot)
    full = codegen_functions(robot)
    c_full, casadi_header = _casadi_c(name, full, precision)
    sources = {f"{name}.c": c_full}
    functions = list(full)
    for stance in REDUCED_STANCE_SETS:
        reduced = reduced_functions(robot, stance)
        file_stem = f"{name}_r_{stance.name.replace('+', '_')}"
        c_text, h_text = _casadi_c(file_stem, reduced, precision)
        sources[f"{file_stem}.c"] = _checked_reduced_c(c_text, h_text, reduced)
        casadi_header += h_text
        functions += reduced
    work = work_sizes(casadi_header)
    files = {
        f"{name}.c": c_full,
        f"{name}.h": header_doc(robot, functions, work) + casadi_header,
        **({f"{name}_reference.h": reference_header(robot, functions, work)} if reference else {}),
        "check_qd.c": (TEMPLATES / "check_qd.c").read_text(),
        "Makefile": (TEMPLATES / "Makefile").read_text().replace("ROBOT ?= paper", f"ROBOT ?= {name[3:]}"),
        **sources,
    }
    paths = []
    for file_name, text in files.items():
        (out_dir / file_name).write_text(text)
        paths.append(out_dir / file_name)
    return paths


# ----------------------------------------------------------------------------- reference values


REFERENCE_DIGITS = 12  # significant digits of the reference header: 5e-13 relative, far below the 1e-10 check


def _rounded(x: np.ndarray) -> np.ndarray:
    return np.array([float(f"{v:.{REFERENCE_DIGITS}g}") for v in np.ravel(x)]).reshape(np.shape(x))


def reference_state(robot: Robot) -> FullState:
    """A fixed, well-conditioned state near standing (seeded; the same on every machine),
    rounded to the digits the reference header prints so Pinocchio sees exactly its inputs."""
    rng = np.random.default_rng(2025)
    joints = np.clip(robot.standing_q + rng.normal(scale=0.05, size=12), robot.lower, robot.upper)
    R = pin.rpy.rpyToMatrix(*rng.normal(scale=0.1, size=3))
    return FullState(_rounded(full_q(R, rng.normal(scale=0.5, size=3), joints)), _rounded(rng.normal(scale=0.5, size=18)),
                     _rounded(rng.normal(size=18)), _rounded(rng.normal(scale=20.0, size=(4, 3))))


def reduced_inputs(s: FullState) -> dict[str, np.ndarray]:
    """Inputs of the reduced functions (13 entries; 12-coordinate functions take the first 12)
    derived from a full state: its joints and trunk roll, joint rates and accelerations (+ one
    body component for the roll's), orientation, and torques from its accelerations."""
    roll = pin.rpy.matrixToRpy(rotation(s.q))[0]
    return {"q_r": _rounded(np.append(s.q[7:], roll)), "qd_r": np.append(s.v[6:], s.v[3]),
            "qdd_r": np.append(s.a[6:], s.a[3]), "quat": s.q[3:7], "tau_ext": 10.0 * s.a[5:]}


def _reduced_reference(ref: PinocchioReference, kind: str, stance: StanceSet, s: FullState) -> np.ndarray:
    """Pinocchio-built value (SPEC section 5's independent reference) of reduced function ``kind``."""
    n = 13 if len(stance.feet) == 2 else 12
    x = {k: v[:n] for k, v in reduced_inputs(s).items() if k != "quat"}

    def id_r(qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        return ref.reduced_inverse_dynamics(stance.feet, stance.selection("paper"), x["q_r"], qd, qdd, s.q[3:7])

    zero = np.zeros(n)
    G = id_r(zero, zero)  # id_r is affine in qdd: M_r's columns are differences
    values = {"G_r": lambda: G, "CG_r": lambda: id_r(x["qd_r"], zero), "id_r": lambda: id_r(x["qd_r"], x["qdd_r"])}
    if kind in values:
        return values[kind]()
    M = np.column_stack([id_r(zero, e) - G for e in np.eye(n)])
    return M if kind == "M_r" else np.linalg.solve(M, x["tau_ext"] - id_r(x["qd_r"], zero))


def pinocchio_outputs(robot: Robot, ref: PinocchioReference, name: str, s: FullState) -> list[np.ndarray]:
    """Pinocchio's values of generated function ``name`` (without prefix) at state s."""
    reduced = _reduced_parts(name)
    if reduced:
        return [_reduced_reference(ref, *reduced, s)]
    if name == "M_full":
        return [ref.mass_matrix(s.q)]
    if name == "C_full":
        return [ref.nonlinear_effects(s.q, s.v) - ref.gravity(s.q)]
    if name == "G_full":
        return [ref.gravity(s.q)]
    if name == "nle_full":
        return [ref.nonlinear_effects(s.q, s.v)]
    if name == "id_full":
        R = rotation(s.q)
        full = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
        return [full[:6], full[6:]]
    if name.startswith("grf_"):
        stance = stance_set(name[4:].replace("_", "+"))
        r = ref.grf_solve(s.q, s.v, s.a, stance.feet, stance.selection("paper"))
        f = np.zeros((4, 3))
        f[list(stance.feet)] = r.f_b
        return [r.lam, f.ravel(), r.residual, r.tau]
    raise KeyError(f"no Pinocchio reference for generated function '{name}'")


def tolerance_scale(ref: PinocchioReference, name: str, s: FullState) -> float:
    """How much the conditioning at ``s`` amplifies rounding in generated function ``name``,
    beyond what the tolerances assume: for a reduced function cond(A) / GRF_COND_ASSUMED of its
    stance set's GRF system times cond(A_s) / MAP_COND_ASSUMED of its stance-foot rows (the
    velocity map), each at least 1, and for fd_r times cond(M_r) / GRF_COND_ASSUMED (the solve
    amplifies M_r's and C_r + G_r's errors by cond(M_r)). 1 otherwise."""
    reduced = _reduced_parts(name)
    if not reduced:
        return 1.0
    kind, stance = reduced
    q, v, a = s.q.copy(), np.zeros(NV_FULL), np.zeros(NV_FULL)
    q[7:] = reduced_inputs(s)["q_r"][:12]
    g = ref.grf_solve(q, v, a, stance.feet, stance.selection("paper"))
    scale = max(1.0, float(g.singular_values[0] / g.singular_values[g.rank - 1]) / GRF_COND_ASSUMED)
    r = ref.foot_positions(q)
    rows = [np.hstack([np.eye(3), -skew_np(r[i])]) for i in stance.feet]
    if len(stance.feet) == 2:
        rows.append(np.concatenate([np.zeros(3), roll_rate_row_np(rotation(q))])[None, :])
    scale *= max(1.0, float(np.linalg.cond(np.vstack(rows))) / MAP_COND_ASSUMED)
    if kind == "fd_r":  # the tolerances allow for ~GRF_COND_ASSUMED of amplification already
        scale *= max(1.0, float(np.linalg.cond(_reduced_reference(ref, "M_r", stance, s))) / GRF_COND_ASSUMED)
    return scale


def _nonzeros(dense: np.ndarray, sp: ca.Sparsity) -> np.ndarray:
    rows, cols = sp.get_triplet()
    return np.asarray(dense, dtype=float).reshape(sp.size1(), sp.size2(), order="F")[rows, cols]


def _c_array(name: str, values: np.ndarray) -> str:
    body = ", ".join(f"{float(x):.{REFERENCE_DIGITS}g}" for x in values) if len(values) else "0"
    return f"static const double {name}[{max(len(values), 1)}] = {{{body}}};"


def reference_header(robot: Robot, functions: list[ca.Function], work: dict[str, tuple[int, int]]) -> str:
    """C header: Pinocchio's values of every generated function at ``reference_state``."""
    ref = PinocchioReference(robot)
    s = reference_state(robot)
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel(), **reduced_inputs(s)}
    inputs = {k: v for k, v in inputs.items() if any(k in f.name_in() for f in functions)}
    lines = [
        f"/* Reference values for the generated functions of '{robot.name}', computed by Pinocchio",
        " * (crba, nonLinearEffects, computeGeneralizedGravity, rnea, contact Jacobians, SVD GRF)",
        " * at a fixed state near standing; 12 significant digits. Generated; do not edit. */",
        "typedef int (*qd_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);",
        "typedef struct { const char* name; qd_fn fn; int n_in, n_out; const double* in[4]; int in_len[4];",
        "                 const double* out[4]; int out_nnz[4]; double tol_scale; } qd_case;",
        "/* tol_scale: the conditioning beyond what the tolerances assume (codegen.tolerance_scale) */",
        f"#define QD_REL_TOL_DOUBLE {REL_TOL_TERMS:g}",
        f"#define QD_REL_TOL_FLOAT {FLOAT_REL_TOL:g}",
        f"#define QD_MAX_SZ_IW {max(iw for iw, _ in work.values())}",
        f"#define QD_MAX_SZ_W {max(w for _, w in work.values())}",
        f"#define QD_MAX_IN {max(len(x) for x in inputs.values())}",
        f"#define QD_MAX_OUT {max(f.nnz_out(i) for f in functions for i in range(f.n_out()))}",
        *[_c_array(f"qd_ref_{k}", x) for k, x in inputs.items()],
    ]
    cases = []
    for f in functions:
        name = f.name()[len(PREFIX):]
        expected = pinocchio_outputs(robot, ref, name, s)
        tol_scale = tolerance_scale(ref, name, s)
        outs = []
        for i, dense in enumerate(expected):
            nz = _nonzeros(dense, f.sparsity_out(i))
            lines.append(_c_array(f"{f.name()}_out{i}", nz))
            outs.append((f"{f.name()}_out{i}", len(nz)))
        ins = [(f"qd_ref_{f.name_in(i)}", f.nnz_in(i)) for i in range(f.n_in())]
        cases.append(
            f'  {{"{f.name()}", {f.name()}, {f.n_in()}, {f.n_out()}, {{{", ".join(n for n, _ in ins)}}}, '
            f'{{{", ".join(str(k) for _, k in ins)}}}, {{{", ".join(n for n, _ in outs)}}}, '
            f'{{{", ".join(str(k) for _, k in outs)}}}, {tol_scale:.3g}}},'
        )
    lines += ["static const qd_case QD_CASES[] = {", *cases, "};", f"#define QD_N_CASES {len(functions)}"]
    lines += [
        "/* Point arg/res of case k at in/out, filled with its reference inputs in casadi_real. */",
        "static void qd_case_args(const qd_case* k, casadi_real in[4][QD_MAX_IN], const casadi_real* arg[4],",
        "                         casadi_real out[4][QD_MAX_OUT], casadi_real* res[4]) {",
        "  for (int i = 0; i < k->n_in; ++i) {",
        "    for (int j = 0; j < k->in_len[i]; ++j) in[i][j] = (casadi_real)k->in[i][j];",
        "    arg[i] = in[i];",
        "  }",
        "  for (int i = 0; i < k->n_out; ++i) res[i] = out[i];",
        "}",
    ]
    return "\n".join(lines) + "\n"


def differing_files(robot: Robot, directory: Path) -> list[str]:
    """Names of the files in ``directory`` that a fresh generation would change (or add)."""
    with tempfile.TemporaryDirectory() as tmp:
        fresh = generate(robot, Path(tmp))
        return [p.name for p in fresh if not (Path(directory) / p.name).is_file()
                or (Path(directory) / p.name).read_bytes() != p.read_bytes()]
