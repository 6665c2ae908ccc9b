"""The header a hand-written C file of ``c/`` includes when compiled alone (not pasted into a generated file, where
CasADi's ``CASADI_PREFIX`` is defined first): casadi_real and casadi_int as CasADi defaults them, the return codes and
``c/qd_prelude.h`` (``c_facts.prelude_c``), the precision wrappers (``precision_math``) and a declaration of each
function the including generated file provides (``PROVIDED``). tests/codegen/test_c_alone.py writes it and compiles
each template alone."""

from __future__ import annotations

from quadruped_dyn.codegen.c_facts import derivative_work_c, layouts_c, prelude_c, regularity_c
from quadruped_dyn.codegen.precision_math import PRECISION_MATH, wrappers_c
from quadruped_dyn.tolerances import FLOAT_ERR_PER_REGULARITY

#: The header's name, as the templates include it.
ALONE_HEADER = "qd_alone.h"
_SIGNATURE = "(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem)"
#: macro -> the function of qd_<robot>.c it names, with CasADi's signature (emit.py defines the macro from it).
PROVIDED = {"QD_ID_FULL_EVAL": "qd_id_full_eval"}
#: The functions a reduced file generates per stance set before c/qd_reduced_solve.c (emit._reduced_helpers_c), each
#: with CasADi's signature.
PER_STANCE = ("qd_stance_maps", "qd_dfd_r_lift", "qd_dfd_r_lift_dir")
#: The reduced file's sizes of the lift's tape and did_full's legs' outputs: any positive value compiles alone.
_PER_STANCE_SIZES = "#define QD_DFD_R_TAPE 1\n#define QD_DID_FULL_L 1\n"


def alone_header_c() -> str:
    """The text of ``ALONE_HEADER``."""
    calls = " ".join(f"qd_{f}(" for f in PRECISION_MATH)
    provided = [f"int {fn}{_SIGNATURE};\n#define {macro} {fn}\n" for macro, fn in PROVIDED.items()]
    provided += [f"int {fn}{_SIGNATURE};\n" for fn in PER_STANCE]
    provided += [regularity_c(FLOAT_ERR_PER_REGULARITY), _PER_STANCE_SIZES, derivative_work_c()]
    return ("/* quadruped_dyn: what a generated file defines before the hand-written C it holds (codegen/c_alone.py) */\n"
            "#ifndef QD_ALONE_H\n#define QD_ALONE_H\n#ifndef casadi_real\n#define casadi_real double\n#endif\n"
            "#ifndef casadi_int\n#define casadi_int long long int\n#endif\n#include <math.h>\n"
            + prelude_c() + layouts_c() + wrappers_c(calls) + "".join(provided) + "#endif\n")
