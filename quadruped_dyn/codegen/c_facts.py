"""Facts the generated C and the Python that calls it share, with their one source here: the return codes (the C
``#define`` lines are written from ``RETURN_CODES``, ``return_codes_c``), the layouts of the leg-by-leg pieces'
outputs the reduced templates read (``layouts_c``, from ``codegen.forms.leg_pieces``), the work sizes of the derivative
templates (``derivative_work_c``, from ``DERIVATIVE_SZ_W``) and the definitions every hand-written C file uses
(``c/qd_prelude.h``, ``prelude_c``)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from quadruped_dyn.codegen.forms.leg_pieces import FOOT_PARTS, LEG_MASS_BLOCKS, TRUNK_MASS_BLOCKS
from quadruped_dyn.model.state import NV_FULL
from quadruped_dyn.tolerances import FLOAT_MAX_BOUND, REGULARITY_MIN

#: The hand-written C (templates, check programs, the Cortex-M start-up, the Makefile).
TEMPLATES = Path(__file__).resolve().parent / "c"
PRELUDE = "qd_prelude.h"


@dataclass(frozen=True)
class ReturnCode:
    """A non-zero return code of the generated functions."""

    name: str  # the C macro
    value: int
    c_comment: str  # what the macro's line says
    meaning: str  # what a Python caller is told (``codegen.library.CompiledFunction``)
    numerical: bool  # True: the model is singular or degenerate there (NumericalError); False: bad input (InputError)


RETURN_CODES: tuple[ReturnCode, ...] = (
    ReturnCode("QD_NONFINITE", 1, "an output is NaN/inf",
               "an output is not finite (the trunk pitched 90 deg with two stance feet, a zero quaternion, or a "
               "non-finite input); expected a stance the model can hold", False),
    ReturnCode("QD_SINGULAR", 2, "M_r or M singular to working precision",
               "M_r is singular to working precision here (in float also where fd_r's error bound exceeds 1/4 %); "
               "expected a configuration where the reduced model is regular", True),
    ReturnCode("QD_DEGENERATE", 3, "the stance is degenerate",
               "the stance is degenerate here (coincident or collinear stance feet, or two feet whose line is "
               "perpendicular to the roll axis: the front or back pair at zero pitch or roll, or two feet with the "
               "trunk pitched within 2 deg of 90 deg; regularity at most QD_REGULARITY_MIN; in float, with two feet, "
               "below FLOAT_REGULARITY_MIN); the reduced model is undefined to this precision", True),
    ReturnCode("QD_NO_WORK", 4, "the work memory w the function needs (its _SZ_W > 0) is a null pointer",
               "the function needs work memory w (its _SZ_W entries) and w is a null pointer; expected the caller's w",
               False),
)
#: By name.
RETURN_CODE = {c.name: c for c in RETURN_CODES}


_NV = NV_FULL
#: Reals of the caller's w that c/qd_derivatives_solve.c's qd_dfd_full and qd_dgrf_<feet> use for their temporaries
#: (QD_<name>_SZ_W; the generator states them as the functions' _SZ_W): name -> (reals, what they hold).
DERIVATIVE_SZ_W = {
    "DFD_FULL": (4 * _NV * _NV + 2 * _NV + 4 * 9 + 4 * 18 + 36,
                 "M, M^-1, dtau/dq, dtau/dv (18 x 18 each), nle, a (18), the blocks (4 * 9 + 4 * 18 + 36)"),
    "DGRF": (3 * _NV * _NV + 2 * _NV + 6 + 6 * 6 + 6 * _NV,
             "M, dtau/dq, dtau/dv (18 x 18 each), nle, seed (18), wrench (6), P (6 x 6), d(P w)/dq (6 x 18)"),
}


def derivative_work_c() -> str:
    """``DERIVATIVE_SZ_W`` as the C macros c/qd_derivatives_solve.c reads."""
    return ("/* Reals of the caller's w that qd_dfd_full and qd_dgrf_<feet> use for their temporaries (the generator states\n"
            " * them as the functions' _SZ_W, so the Cortex-M stack holds none of the 18 x 18 arrays). */\n"
            + "".join(f"#define QD_{name}_SZ_W {reals} /* {what} */\n" for name, (reals, what) in DERIVATIVE_SZ_W.items()))


def return_codes_c() -> str:
    """The return codes as C macros, once per translation unit (guarded)."""
    defines = [f"#define {c.name} {c.value} /* {c.c_comment} */" for c in RETURN_CODES]
    return "\n".join(["#ifndef QD_RETURN_CODES", "#define QD_RETURN_CODES", *defines, "#endif", ""])


def prelude_c() -> str:
    """The return codes and ``c/qd_prelude.h`` (epsilon, inlining attributes): what the hand-written C pasted into a
    generated file, or compiled alone, expects defined first."""
    return return_codes_c() + (TEMPLATES / PRELUDE).read_text()


def regularity_c(err_per_regularity: float) -> str:
    """QD_REGULARITY_MIN, QD_FLOAT_MAX_BOUND and QD_FLOAT_ERR_PER_REGULARITY (``err_per_regularity``: a stance set's
    ``emit.float_err_per_regularity``), the thresholds c/qd_reduced_solve.c's qd_regular_value reads."""
    return (f"#define QD_REGULARITY_MIN ((casadi_real){REGULARITY_MIN!r}) /* quadruped_dyn.tolerances.REGULARITY_MIN */\n"
            f"#define QD_FLOAT_MAX_BOUND ((casadi_real){FLOAT_MAX_BOUND!r}) /* tolerances.FLOAT_MAX_BOUND */\n"
            f"#define QD_FLOAT_ERR_PER_REGULARITY ((casadi_real){err_per_regularity!r}) "
            "/* tolerances.FLOAT_ERR_PER_REGULARITY; 0: three or four feet */\n")


def _offsets(layout: tuple[tuple[str, int, int], ...], start: int = 0) -> dict[str, tuple[int, int]]:
    """name -> (first entry, rows) of each part of a column-by-column stacked ``layout``."""
    out = {}
    for name, rows, cols in layout:
        out[name] = (start, rows)
        start += rows * cols
    return out


def layouts_c() -> str:
    """Macros reading a foot's ``FOOT_PARTS`` (QD_FOOT reals: QD_FOOT_R(y, d), QD_FOOT_J(y, d, c), QD_FOOT_JQD(y, d),
    QD_FOOT_JDQD(y, d)) and M's nonzero blocks (``mass_blocks``, QD_M_BLOCKS reals: QD_M_BB(Mc, i, k),
    QD_M_BL(Mc, l, i, c), QD_M_LL(Mc, l, i, c), leg l), as ``codegen.forms.leg_pieces`` stacks them."""
    foot = _offsets(FOOT_PARTS)
    trunk = _offsets(TRUNK_MASS_BLOCKS)
    trunk_reals = sum(r * c for _, r, c in TRUNK_MASS_BLOCKS)
    leg_reals = sum(r * c for _, r, c in LEG_MASS_BLOCKS)
    leg = _offsets(LEG_MASS_BLOCKS, trunk_reals)
    lines = [
        "/* quadruped_dyn: layouts of the pieces' outputs (written from quadruped_dyn/codegen/forms/leg_pieces.py) */",
        "#ifndef QD_LAYOUTS",
        "#define QD_LAYOUTS",
        f"#define QD_FOOT {sum(r * c for _, r, c in FOOT_PARTS)}",
        f"#define QD_FOOT_R(y, d) (y)[{foot['r'][0]} + (d)]",
        f"#define QD_FOOT_J(y, d, c) (y)[{foot['J'][0]} + (d) + {foot['J'][1]} * (c)]",
        f"#define QD_FOOT_JQD(y, d) (y)[{foot['J_qd'][0]} + (d)]",
        f"#define QD_FOOT_JDQD(y, d) (y)[{foot['Jdot_qd'][0]} + (d)]",
        f"#define QD_M_BLOCKS ({trunk_reals} + 4 * {leg_reals})",
        f"#define QD_M_BB(Mc, i, k) (Mc)[{trunk['M_bb'][0]} + (i) + {trunk['M_bb'][1]} * (k)]",
        f"#define QD_M_BL(Mc, l, i, c) (Mc)[{leg['M_bl'][0]} + {leg_reals} * (l) + (i) + {leg['M_bl'][1]} * (c)]",
        f"#define QD_M_LL(Mc, l, i, c) (Mc)[{leg['M_ll'][0]} + {leg_reals} * (l) + (i) + {leg['M_ll'][1]} * (c)]",
        "#endif",
        "",
    ]
    return "\n".join(lines)
