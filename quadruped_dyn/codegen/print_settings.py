"""The project's print settings of the generated C: the prefix of its names, how the evaluation functions of the
shipped files print (``EVALUATION``, ``UNGUARDED``), the static pieces the templates call (``static_c``) and the
template of sines and cosines (``SINCOS``)."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

from quadruped_dyn.codegen.printer import PrintOptions, print_function

PREFIX = "qd_"


#: How the evaluation functions of the shipped files print (``codegen.printer``): each shared denominator's quotients
#: as products with its reciprocal, the elementary functions in casadi_real's precision, the unused parameters cast
#: to void
EVALUATION = PrintOptions(reciprocals=True, precision_math=True, void_unused=True)


#: the sines and cosines of a vector of angles (qd_sincos), pasted into each file whose entry points call it
SINCOS = "qd_sincos.c"


#: The generated functions whose evaluation reads its inputs without CasADi's test of each input pointer at each
#: read (``arg[i]? arg[i][k] : 0``; ``static_c``'s ``inputs_given``); their entry point gives a NULL input zeros (CasADi's
#: convention) before calling it. The tests split the reads into branches (gcc then takes an angle's sine and cosine
#: in two libm calls instead of one sincos, and keeps fewer values in registers): per call M_full and G_full run
#: fewer instructions without them, did_full too; id_full and nle_full measured more, and keep them
#: (docs/benchmark.md).
UNGUARDED = frozenset({"M_full", "G_full", "did_full"})


def static_c(c_name: str, f: ca.Function, host_helpers: frozenset[str] = frozenset(), all_io: bool = False,
             inputs_given: bool = False) -> str:
    """``f`` as the static C function ``c_name`` (arg, res, iw, w, mem), printed by ``codegen.printer`` with the
    project's options (reciprocals, precision math, unused parameters cast to void): no work memory (its values are
    locals; the templates call it with none), checked to call no helper but casadi_sq and ``host_helpers`` (CasADi
    helpers the file it goes into defines). ``all_io``: the templates pass every input and output (none NULL), so
    the tests of each pointer at each read and write are left out; ``inputs_given``: only those of the inputs."""
    printed = print_function(f, replace(EVALUATION, name=c_name, guard_inputs=not (all_io or inputs_given),
                                        guard_outputs=not all_io))
    if set(printed.helpers) - {"casadi_sq", *host_helpers}:
        raise AssertionError(f"{f.name()}: its C is not self-contained; the templates need it to be")
    return printed.text
