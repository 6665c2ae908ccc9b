"""Pinocchio's values at a fixed state for the generated C's check program (``qd_<robot>-reference.h``)."""

from __future__ import annotations

import re
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin

from quadruped_dyn.checks.finite_differences import (
    ReducedFiniteDifferences,
    grf_derivatives_by_differences,
    grf_wrench_by_differences,
)
from quadruped_dyn.codegen import file_names
from quadruped_dyn.codegen.emit import (
    ALIASES,
    PREFIX,
    GeneratedFiles,
    file_layout,
    float_err_per_regularity,
    generate,
    reduced_parts,
)
from quadruped_dyn.codegen.emit_derivatives import REDUCED_DERIVATIVE_NAMES
from quadruped_dyn.dynamics.reduced import regularity_function
from quadruped_dyn.math.compare import relative_error, scale_of, within
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet, stance_set
from quadruped_dyn.model.state import NV_FULL, FullState, full_q, rotation
from quadruped_dyn.references.pinocchio import PinocchioDerivatives, PinocchioReference
from quadruped_dyn.tolerances import (
    FLOAT_MAX_BOUND,
    FLOAT_REL_TOL,
    FLT_EPSILON,
    GRF_COND_ASSUMED,
    MAP_COND_ASSUMED,
    REFERENCE_TOL_SCALE_REL_TOL,
    REL_TOL_FD_DERIVATIVES,
    REL_TOL_TERMS,
)

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
    qdd_r = np.append(s.a[6:], s.a[3])
    return {"q_r": _rounded(np.append(s.q[7:], roll)), "qd_r": np.append(s.v[6:], s.v[3]),
            "qdd_r": qdd_r, "quat": s.q[3:7], "tau_ext": 10.0 * s.a[5:]}


def wrench_inputs(s: FullState) -> dict[str, np.ndarray]:
    """Inputs of dgrf_dir: a trunk wrench (from the state's accelerations) and a tangent direction of q."""
    return {"w": _rounded(20.0 * s.a[:6]), "dq": s.v}

def reference_tau_full(s: FullState) -> np.ndarray:
    """The generalized force (18,) dfd_full is checked at: 5 a (rounded like the state)."""
    return _rounded(5.0 * s.a)

def _reduced_reference(ref: PinocchioReference, kind: str, stance: StanceSet, s: FullState) -> np.ndarray:
    """Pinocchio-built value (docs/formulation.md §8's independent reference) of reduced function ``kind``."""
    n = 13 if len(stance.feet) == 2 else 12
    x = {k: v[:n] for k, v in reduced_inputs(s).items() if k != "quat"}

    def id_r(qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        return ref.reduced_inverse_dynamics(stance.feet, stance.selection("paper"), x["q_r"], qd, qdd, s.q[3:7])

    zero = np.zeros(n)
    values = {"G_r": lambda: id_r(zero, zero), "CG_r": lambda: id_r(x["qd_r"], zero),
              "id_r": lambda: id_r(x["qd_r"], x["qdd_r"])}
    if kind in values:
        return values[kind]()
    M = ref.reduced_mass_matrix(stance.feet, stance.selection("paper"), x["q_r"], s.q[3:7])
    return M if kind == "M_r" else np.linalg.solve(M, x["tau_ext"] - id_r(x["qd_r"], zero))

def _derivative_reference(ref: PinocchioReference, name: str, s: FullState) -> list[np.ndarray] | None:
    """Central differences of the Pinocchio-built references (``checks.finite_differences``) for the
    reduced model's and the GRF solve's derivatives; None for any other function."""
    reduced = reduced_parts(name)
    if reduced and reduced[0] in REDUCED_DERIVATIVE_NAMES:
        _, stance = reduced
        n = 13 if len(stance.feet) == 2 else 12
        x = {k: v[:n] for k, v in reduced_inputs(s).items()}
        return list(ReducedFiniteDifferences(ref, stance).dfd_r(x["q_r"], x["qd_r"], x["tau_ext"], s.q[3:7]))
    if name.startswith("dgrf_dir_"):
        w = wrench_inputs(s)
        return list(grf_wrench_by_differences(ref, stance_set(name[9:].replace("_", "+")), s.q, w["w"], w["dq"]))
    if name.startswith("dgrf_"):
        return list(grf_derivatives_by_differences(ref, stance_set(name[5:].replace("_", "+")), s.q, s.v, s.a))
    return None


def pinocchio_outputs(robot: Robot, ref: PinocchioReference, name: str, s: FullState) -> list[np.ndarray]:
    """Pinocchio's values of generated function ``name`` (without prefix) at state s."""
    name = ALIASES.get(name, name)  # an alias (M_full_crba) is the function it names (M_full)
    derivative = _derivative_reference(ref, name, s)
    if derivative is not None:
        return derivative
    reduced = reduced_parts(name)
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
    if name == "feet_full":
        J = np.kron(np.eye(4), rotation(s.q).T) @ ref.contact_jacobian(s.q, (0, 1, 2, 3))
        return [ref.foot_positions(s.q).ravel(), J, ref.foot_accelerations(s.q, s.v, np.zeros(NV_FULL)).ravel()]
    if name in ("did_full", "dfd_full", "dfd_full_parts"):
        derivatives = PinocchioDerivatives(ref)
        if name == "did_full":
            return list(derivatives.rnea_derivatives(s.q, s.v, s.a))
        if name == "dfd_full":
            return list(derivatives.aba_derivatives(s.q, s.v, reference_tau_full(s)))
        return [ref.mass_matrix(s.q), ref.nonlinear_effects(s.q, s.v)]
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
    stance set's GRF system times c = cond(A_s) / MAP_COND_ASSUMED of its stance-foot rows (the
    velocity map), each at least 1: c^2 for the terms M_r, CG_r, G_r, id_r (the maps are solved by
    their normal equations, docs/formulation.md §6.2), c for fd_r and dfd_r times cond(M_r) /
    GRF_COND_ASSUMED (the solve amplifies M_r's and C_r + G_r's errors by cond(M_r); their map errors
    largely cancel in it: FL+FR's float fd_r is within 2e-6 where its M_r is off by 2e-6). 1 otherwise."""
    reduced = reduced_parts(name)
    if name == "dfd_full":  # M^-1 amplifies the errors of M and of d rnea by cond(M)
        return max(1.0, float(np.linalg.cond(ref.mass_matrix(s.q))) / GRF_COND_ASSUMED)
    if not reduced:
        return 1.0
    kind, stance = reduced
    q, v, a = s.q.copy(), np.zeros(NV_FULL), np.zeros(NV_FULL)
    q[7:] = reduced_inputs(s)["q_r"][:12]
    g = ref.grf_solve(q, v, a, stance.feet, stance.selection("paper"))
    scale = max(1.0, float(g.singular_values[0] / g.singular_values[g.rank - 1]) / GRF_COND_ASSUMED)
    c = max(1.0, float(np.linalg.cond(ref.velocity_map(q, stance.feet))) / MAP_COND_ASSUMED)
    if kind in ("fd_r", "dfd_r"):  # the tolerances allow for ~GRF_COND_ASSUMED of amplification already
        return scale * c * max(1.0, float(np.linalg.cond(_reduced_reference(ref, "M_r", stance, s))) / GRF_COND_ASSUMED)
    return scale * c**2


#: The reference header's array of fd_r's float bounds, a condition number like tol_scale: printed to 3 digits
#: and compared entry by entry within REFERENCE_TOL_SCALE_REL_TOL (an ill-conditioned K moves it by ~1e-6
#: relative between CPUs).
FLOAT_BOUND_ARRAY = "qd_float_bound"


def float_bound(ref: PinocchioReference, name: str, s: FullState) -> float:
    """The error bound the float build of generated function ``name`` computes at ``s`` and returns a non-zero code
    above QD_FLOAT_MAX_BOUND for (docs/embedded.md); 0 where it computes none. A reduced function of two feet:
    FLOAT_ERR_PER_REGULARITY x FLT_EPSILON / regularity (QD_DEGENERATE). fd_r also, and at least: FLT_EPSILON x
    cond_1 of the matrix its solve eliminates (M_r with four feet; with a swing leg K, M_r's Schur complement over the
    swing legs' joints: docs/formulation.md §6.2), from the Pinocchio-built M_r (QD_SINGULAR)."""
    reduced = reduced_parts(name)
    if not reduced:
        return 0.0
    kind, stance = reduced
    x = reduced_inputs(s)
    n = 13 if len(stance.feet) == 2 else 12
    per_regularity = float_err_per_regularity(stance)
    bound = per_regularity * FLT_EPSILON / float(regularity_function(ref.robot, stance)(x["q_r"][:n], x["quat"])) \
        if per_regularity else 0.0
    if kind != "fd_r":
        return bound
    M = _reduced_reference(ref, "M_r", stance, s)
    L = [3 * leg + c for leg in stance.lifted for c in range(3)]
    R = [i for i in range(len(M)) if i not in L]
    K = M[np.ix_(R, R)] - M[np.ix_(R, L)] @ np.linalg.solve(M[np.ix_(L, L)], M[np.ix_(L, R)]) if L else M
    return max(bound, float(FLT_EPSILON * np.linalg.cond(K, 1)))


def tolerance_floor(name: str) -> float:
    """The least relative tolerance of generated function ``name`` in either precision: the accuracy of
    its reference. The derivatives of the reduced model and of the GRF solve are checked against central
    differences (``checks.finite_differences``; REL_TOL_FD_DERIVATIVES); 0 for the others. Like the
    tolerances, it is multiplied by ``tolerance_scale``: the differences' round-off grows with the
    conditioning as the generated code's does."""
    reduced = reduced_parts(name)
    fd = (reduced is not None and reduced[0] in REDUCED_DERIVATIVE_NAMES) or name.startswith("dgrf_")
    return REL_TOL_FD_DERIVATIVES if fd else 0.0


def _nonzeros(dense: np.ndarray, sp: ca.Sparsity) -> np.ndarray:
    rows, cols = sp.get_triplet()
    return np.asarray(dense, dtype=float).reshape(sp.size1(), sp.size2(), order="F")[rows, cols]

def _c_array(name: str, values: np.ndarray) -> str:
    body = ", ".join(f"{float(x):.{REFERENCE_DIGITS}g}" for x in values) if len(values) else "0"
    return f"static const double {name}[{max(len(values), 1)}] = {{{body}}};"

def _base_name(f: ca.Function) -> str:
    """The name of generated function ``f`` without its prefix (qd_ or, parametric, qd_p_)."""
    return f.name()[len(PREFIX):].removeprefix("p_")

def reference_header(robot: Robot, functions: list[ca.Function], work: dict[str, tuple[int, int]],
                     outputs: dict[str, list[np.ndarray]] | None = None, parameters: np.ndarray | None = None) -> str:
    """C header: Pinocchio's values of every generated function at ``reference_state``; ``outputs``
    (if given) receives them at full precision, by function name without prefix (the report checks
    its compiled library against them instead of computing them again). ``parameters``: the robot's p, the input p
    of parametric functions (``checks.parametric_check``)."""
    ref = PinocchioReference(robot)
    s = reference_state(robot)
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel(), "tau_full": reference_tau_full(s), **reduced_inputs(s),
              **wrench_inputs(s)}
    if parameters is not None:
        inputs["p"] = parameters
    inputs = {k: v for k, v in inputs.items() if any(k in f.name_in() for f in functions)}
    lines = [
        f"/* Reference values for the generated functions of '{robot.name}', computed by Pinocchio",
        " * (crba, nonLinearEffects, computeGeneralizedGravity, rnea, contact Jacobians, SVD GRF,",
        " * computeRNEADerivatives, computeABADerivatives)",
        " * at a fixed state near standing; 12 significant digits. Generated; do not edit. */",
        "typedef int (*qd_fn)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int);",
        f"#define QD_MAX_N_IN {max(f.n_in() for f in functions)}",
        "typedef int (*qd_batch_fn)(casadi_int, const casadi_real* const*, casadi_real* const*, int*, casadi_real*);",
        "typedef struct { const char* name; qd_fn fn; qd_batch_fn batch; int n_in, n_out; const double* in[QD_MAX_N_IN];",
        "                 int in_len[QD_MAX_N_IN]; const double* out[4]; int out_nnz[4]; double tol_scale, tol_floor; } qd_case;",
        "/* tol_scale: the conditioning beyond what the tolerances assume (check_program_values.tolerance_scale); tol_floor:",
        " * the reference's own accuracy (finite differences: check_program_values.tolerance_floor); the relative tolerance",
        " * is max(QD_REL_TOL_<precision>, tol_floor) * tol_scale */",
        f"#define QD_REL_TOL_DOUBLE {REL_TOL_TERMS:g}",
        f"#define QD_REL_TOL_FLOAT {FLOAT_REL_TOL:g}",
        "/* qd_float_bound[k]: the error bound case k's float build computes (check_program_values.float_bound:",
        " * fd_r's FLT_EPSILON x cond_1 of the matrix it eliminates, a two-feet function's FLOAT_ERR_PER_REGULARITY x",
        " * FLT_EPSILON / regularity; 0 where none); the float build returns QD_SINGULAR or QD_DEGENERATE above",
        " * QD_FLOAT_MAX_BOUND */",
        f"#define QD_FLOAT_MAX_BOUND {FLOAT_MAX_BOUND!r}",
        f"#define QD_MAX_SZ_IW {max(iw for iw, _ in work.values())}",
        f"#define QD_MAX_SZ_W {max(w for _, w in work.values())}",
        f"#define QD_MAX_IN {max(len(x) for x in inputs.values())}",
        f"#define QD_MAX_OUT {max(f.nnz_out(i) for f in functions for i in range(f.n_out()))}",
        *[_c_array(f"qd_ref_{k}", x) for k, x in inputs.items()],
    ]
    cases = []
    for f in functions:
        name = _base_name(f)
        expected = pinocchio_outputs(robot, ref, name, s)
        if outputs is not None:
            outputs[name] = expected
        tol_scale = tolerance_scale(ref, name, s)
        outs = []
        for i, dense in enumerate(expected):
            nz = _nonzeros(dense, f.sparsity_out(i))
            lines.append(_c_array(f"{f.name()}_out{i}", nz))
            outs.append((f"{f.name()}_out{i}", len(nz)))
        ins = [(f"qd_ref_{f.name_in(i)}", f.nnz_in(i)) for i in range(f.n_in())]
        cases.append(
            f'  {{"{f.name()}", {f.name()}, {f.name()}_batch, {f.n_in()}, {f.n_out()}, {{{", ".join(n for n, _ in ins)}}}, '
            f'{{{", ".join(str(k) for _, k in ins)}}}, {{{", ".join(n for n, _ in outs)}}}, '
            f'{{{", ".join(str(k) for _, k in outs)}}}, {tol_scale:.3g}, {tolerance_floor(name):g}}},'
        )
    bounds = ", ".join(f"{float_bound(ref, _base_name(f), s):.3g}" for f in functions)
    lines += ["static const qd_case QD_CASES[] = {", *cases, "};", f"#define QD_N_CASES {len(functions)}",
              f"static const double {FLOAT_BOUND_ARRAY}[{len(functions)}] = {{{bounds}}};"]
    lines += [
        "/* Point arg/res of case k at in/out, filled with its reference inputs in casadi_real. */",
        "static void qd_case_args(const qd_case* k, casadi_real in[QD_MAX_N_IN][QD_MAX_IN], const casadi_real* arg[QD_MAX_N_IN],",
        "                         casadi_real out[4][QD_MAX_OUT], casadi_real* res[4]) {",
        "  for (int i = 0; i < k->n_in; ++i) {",
        "    for (int j = 0; j < k->in_len[i]; ++j) in[i][j] = (casadi_real)k->in[i][j];",
        "    arg[i] = in[i];",
        "  }",
        "  for (int i = 0; i < k->n_out; ++i) res[i] = out[i];",
        "}",
    ]
    return "\n".join(lines) + "\n"

def reference_header_name(robot: Robot) -> str:
    """File name of the reference values beside the generated C: ``qd_<robot>-reference.h``."""
    return file_names.reference_header_name(robot.name)


def checked_files(robot: Robot, out_dir: Path) -> GeneratedFiles:
    """The files ``generate_checked`` writes into ``out_dir``, known before it runs (``codegen.emit.file_layout``)."""
    return file_layout(robot.name, out_dir, (reference_header_name(robot),))


def generate_checked(robot: Robot, out_dir: Path, precision: str = "double") -> GeneratedFiles:
    """``codegen.emit.generate`` plus ``qd_<robot>-reference.h`` (in ``extra``, under
    ``reference_header_name``): the C package that checks itself against Pinocchio (``make check``)."""
    return generate(robot, out_dir, precision,
                    extra_files=lambda functions, work: {reference_header_name(robot): reference_header(robot, functions, work)})


#: A C array of the reference header: ``static const double <name>[<n>] = {<values>};``
_ARRAY = re.compile(r"static const double (\w+)\[(\d+)\] = \{([^}]*)\};")
#: A row of the case table: ``{"<name>", ..., {<output arrays>}, {<nnz>}, <tol_scale>},``
_CASE = re.compile(r'^  \{"(\w+)", .*\{([\w, ]*)\}, \{[\d, ]*\}, ([-+.\deE]+|inf|nan), ([-+.\deE]+)\},$', re.M)


@dataclass(frozen=True)
class ReferenceHeader:
    """A ``qd_<robot>-reference.h`` split into what must be reproduced byte for byte (``skeleton``: the
    text with every value replaced by a placeholder: names, sizes, the case table's layout) and the
    values Pinocchio computed (``arrays`` by C name; ``tol_scale``, ``tol_floor`` and output arrays per case), whose
    last digits depend on the CPU and the BLAS kernel."""

    skeleton: str
    arrays: dict[str, np.ndarray]
    case_outputs: dict[str, tuple[str, ...]]
    tol_scale: dict[str, float]
    tol_floor: dict[str, float]
    rel_tol: float


def parse_reference_header(text: str) -> ReferenceHeader:
    arrays = {m.group(1): np.array([float(x) for x in m.group(3).split(",")]) for m in _ARRAY.finditer(text)}
    cases = {m.group(1): tuple(x.strip() for x in m.group(2).split(",")) for m in _CASE.finditer(text)}
    scales = {m.group(1): float(m.group(3)) for m in _CASE.finditer(text)}
    floors = {m.group(1): float(m.group(4)) for m in _CASE.finditer(text)}
    skeleton = _ARRAY.sub(lambda m: f"static const double {m.group(1)}[{m.group(2)}] = {{...}};", text)
    skeleton = re.sub(r", ([-+.\deE]+|inf|nan)(, [-+.\deE]+)\},$", r", ...\2},", skeleton, flags=re.M)
    tol = re.search(r"#define QD_REL_TOL_DOUBLE (\S+)", text)
    return ReferenceHeader(skeleton, arrays, cases, scales, floors, float(tol.group(1)) if tol else float("nan"))


def reference_differences(committed: str, fresh: str) -> list[str]:
    """How the reference values of ``committed`` differ from ``fresh`` beyond their tolerance, one
    line per value that moved (empty if they agree): the structure must be identical; each case's
    outputs must agree within the tolerance ``check_qd.c`` applies to the generated code
    (max(QD_REL_TOL_DOUBLE, tol_floor) x tol_scale, relative to the case's largest output), the inputs within
    QD_REL_TOL_DOUBLE of their own scale, and each tol_scale within REFERENCE_TOL_SCALE_REL_TOL.
    Two machines' Pinocchio differ by round-off (~1e-15 relative), far inside these."""
    a, b = parse_reference_header(committed), parse_reference_header(fresh)
    if a.skeleton != b.skeleton:
        old, new = a.skeleton.splitlines(), b.skeleton.splitlines()
        line = next((i for i, (x, y) in enumerate(zip(old, new)) if x != y), min(len(old), len(new)))
        return [f"the structure differs (not only values) from line {line + 1}"]
    moved = [f"{k} has {len(b.arrays[k])} values in one and {len(a.arrays[k])} in the other"
             for k in b.arrays if len(a.arrays[k]) != len(b.arrays[k])]
    if moved:
        return moved
    in_case = {name for outs in b.case_outputs.values() for name in outs}
    groups = [(case, outs, max(b.rel_tol, b.tol_floor[case]) * b.tol_scale[case]) for case, outs in b.case_outputs.items()]
    groups += [(name, (name,), b.rel_tol) for name in b.arrays if name not in in_case and name != FLOAT_BOUND_ARRAY]
    for _case, outs, tol in groups:
        scale = scale_of(np.concatenate([b.arrays[o] for o in outs]))
        for o in outs:
            diff = np.abs(a.arrays[o] - b.arrays[o]) / scale
            diff[~(np.isfinite(a.arrays[o]) & np.isfinite(b.arrays[o]))] = np.inf
            for i in np.flatnonzero(~(diff <= tol)):
                moved.append(f"{o}[{i}] {a.arrays[o][i]:.12g} -> {b.arrays[o][i]:.12g} "
                             f"(moved {diff[i]:.1e} of the case's scale {scale:.3g}; tolerance {tol:.1e})")
    for case in b.tol_scale:
        x, y = a.tol_scale[case], b.tol_scale[case]
        if not within(relative_error(x, y), REFERENCE_TOL_SCALE_REL_TOL):
            moved.append(f"tol_scale of {case} {x:.3g} -> {y:.3g}")
    for k, (x, y) in enumerate(zip(a.arrays.get(FLOAT_BOUND_ARRAY, []), b.arrays.get(FLOAT_BOUND_ARRAY, []))):
        if not within(relative_error(x, y), REFERENCE_TOL_SCALE_REL_TOL):
            moved.append(f"{FLOAT_BOUND_ARRAY}[{k}] {x:.3g} -> {y:.3g}")
    return moved


@dataclass(frozen=True)
class GenerationDiff:
    """How a directory differs from a fresh generation: ``missing`` (files a generation writes that are not
    there), ``sources`` (files there that must be byte for byte equal and are not: the C, the header, the
    Makefile) and ``references`` (one line per reference value beyond its tolerance, ``reference_differences``)."""

    sources: list[str]
    references: list[str]
    missing: list[str] = field(default_factory=list)

    def __bool__(self) -> bool:
        return bool(self.sources or self.references or self.missing)

    def summary(self) -> str:
        parts = []
        if self.missing:
            parts.append(f"missing: {', '.join(self.missing)}")
        if self.sources:
            parts.append(f"source differs from a fresh generation: {', '.join(self.sources)}")
        if self.references:
            more = f"; ... ({len(self.references)} in all)" if len(self.references) > 5 else ""
            shown = "; ".join(self.references[:5]) + more
            parts.append(f"reference values differ beyond tolerance: {shown}")
        return "; ".join(parts) or "up to date"


def compare_generation(robot: Robot, directory: Path, precision: str = "double") -> GenerationDiff:
    """Compare ``directory`` with a fresh generation at ``precision`` (``compare_files``); a directory holding none
    of the files is answered without generating them (all missing)."""
    expected = checked_files(robot, Path(directory)).all()
    if not any(p.is_file() for p in expected):
        return GenerationDiff([], [], [p.name for p in expected])
    with tempfile.TemporaryDirectory() as tmp:
        return compare_files(robot, directory, generate_checked(robot, Path(tmp), precision))


def compare_files(robot: Robot, directory: Path, fresh: GeneratedFiles) -> GenerationDiff:
    """Compare ``directory`` with ``fresh``, a generation of ``robot``: a file not in ``directory`` is missing,
    every other byte for byte, except ``qd_<robot>-reference.h`` whose values are compared numerically
    (``reference_differences``)."""
    sources, references, missing = [], [], []
    for p in fresh.all():
        old = Path(directory) / p.name
        if not old.is_file():
            missing.append(p.name)
        elif p.name == reference_header_name(robot):
            references += [f"{p.name}: {m}" for m in reference_differences(old.read_text(), p.read_text())]
        elif old.read_bytes() != p.read_bytes():
            sources.append(p.name)
    return GenerationDiff(sources, references, missing)


def differing_files(robot: Robot, directory: Path, precision: str = "double") -> list[str]:
    """Names of the files in ``directory`` that a fresh generation would change (or add); the
    reference header only if its values moved beyond their tolerance."""
    diff = compare_generation(robot, directory, precision)
    return diff.missing + diff.sources + sorted({m.split(":", 1)[0] for m in diff.references})
