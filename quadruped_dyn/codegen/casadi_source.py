"""CasADi's C for a list of Functions: the source and CasADi's header text (unused parameters
cast to void for -Wextra -Werror, the scalar helpers static inline), the work sizes it states, the entry-point
pattern, the C templates' folder.
The one place ``codegen.emit`` and ``codegen.emit_derivatives`` both build on."""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import casadi as ca

from quadruped_dyn.codegen.c_facts import TEMPLATES  # noqa: F401 -- the templates' folder, re-exported
from quadruped_dyn.codegen.printer import PrintOptions, print_function
from quadruped_dyn.codegen.reciprocals import shared_reciprocals

PREFIX = "qd_"


def work_sizes(casadi_header: str) -> dict[str, tuple[int, int]]:
    sizes = dict(re.findall(r"#define (\w+_SZ_(?:IW|W)) (\d+)", casadi_header))
    names = {k.rsplit("_SZ_", 1)[0] for k in sizes}
    return {n: (int(sizes[f"{n}_SZ_IW"]), int(sizes[f"{n}_SZ_W"])) for n in names}


_UNUSED = "(void)arg; (void)res; (void)iw; (void)w; (void)mem;"


def silence_unused_parameters(c_source: str) -> str:
    """CasADi's evaluation functions ignore some of their five parameters and its
    release hooks ignore ``mem``: cast them to void so -Wextra -Werror passes."""
    c_source = re.sub(r"(static int casadi_f\d+\([^)]*\) \{\n)", lambda m: m.group(1) + f"  {_UNUSED}\n", c_source)
    return re.sub(r"(void \w+_release\(int mem\) \{\n)", lambda m: m.group(1) + "  (void)mem;\n", c_source)


def static_helpers(c_source: str) -> str:
    """CasADi defines its scalar helpers (casadi_sq, casadi_fabs) with external linkage: in a -fPIC build gcc
    does not inline an interposable function, and a call in straight-line code spills every live floating-point
    register (all are caller-saved). ``static inline``, each file keeps its own (their names carry the file's prefix)."""
    return re.sub(r"\ncasadi_real (casadi_(?:sq|fabs))\(", r"\nstatic inline casadi_real \1(", c_source)


#: the sines and cosines of a vector of angles (qd_sincos), pasted into each file whose entry points call it
SINCOS = "qd_sincos.c"


def casadi_c(file_stem: str, functions: list[ca.Function], precision: str) -> tuple[str, str]:
    """(C source, CasADi's header) of ``functions`` generated into ``file_stem``.c, each shared denominator's
    quotients as products with its reciprocal (``reciprocals``)."""
    cg = ca.CodeGenerator(f"{file_stem}.c", {"with_header": True, "casadi_real": precision})
    for f in functions:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        c_source = (Path(tmp) / f"{file_stem}.c").read_text()
        c_source = shared_reciprocals(static_helpers(silence_unused_parameters(c_source)))
        return c_source, (Path(tmp) / f"{file_stem}.h").read_text()


#: The generated functions whose evaluation reads its inputs without CasADi's test of each input pointer at each
#: read (``arg[i]? arg[i][k] : 0``, ``unguarded_inputs``); their entry point gives a NULL input zeros (CasADi's
#: convention) before calling it. The tests split the reads into branches (gcc then takes an angle's sine and cosine
#: in two libm calls instead of one sincos, and keeps fewer values in registers): per call M_full and G_full run
#: fewer instructions without them, did_full too; id_full and nle_full measured more, and keep them
#: (docs/benchmark.md).
UNGUARDED = frozenset({"M_full", "G_full", "did_full"})


def unguarded_inputs(body: str, name: str) -> str:
    """``body``, one evaluation function of ``name`` (in ``UNGUARDED``), with its reads of the inputs unguarded."""
    if name not in UNGUARDED:
        raise AssertionError(f"{name} is not in UNGUARDED: its entry point passes NULL inputs on")
    body = re.sub(r"arg\[(\d+)\]\? (arg\[\1\]\[\d+\]) : 0;", r"\2;", body)
    if re.search(r"arg\[\d+\]\?", body):
        raise AssertionError(f"{name}: a test of an input pointer is left")
    return body


def drop_evaluation(c_text: str, raw: str) -> str:
    """Remove CasADi's evaluation function ``raw`` (``casadi_fN``: its #define, the comment naming it
    and its definition). For a signature-only Function whose entry point calls a hand-written
    template instead, its body (a placeholder filling every output) is dead code: ~0.4 MB per robot."""
    c_text, defines = re.subn(rf"#define {raw} CASADI_PREFIX\(f\d+\)\n", "", c_text)
    c_text, bodies = re.subn(rf"/\* [^\n]* \*/\nstatic int {raw}\(.*?\n\}}\n\n", "", c_text, count=1, flags=re.S)
    if (defines, bodies) != (1, 1) or re.search(rf"\b{raw}\b", c_text):
        raise AssertionError(f"{raw}: CasADi's evaluation function not found once, or still referenced")
    return c_text


def entry_point(name: str) -> str:
    return (rf"(CASADI_SYMBOL_EXPORT int {name}\(const casadi_real\*\* arg, casadi_real\*\* res, casadi_int\* iw, "
            rf"casadi_real\* w, int mem\)\{{\n)  return (casadi_f\d+)\(arg, res, iw, w, mem\);\n")


def evaluations(c_text: str, names: list[str]) -> dict[str, str]:
    """Entry point name -> the static evaluation function CasADi's entry point calls (casadi_fN)."""
    out = {}
    for name in names:
        found = re.search(entry_point(name), c_text)
        if not found:
            raise AssertionError(f"entry point of {name} not found in CasADi's output")
        out[name] = found.group(2)
    return out


def static_c(c_name: str, f: ca.Function, host_helpers: frozenset[str] = frozenset(), all_io: bool = False,
             inputs_given: bool = False) -> str:
    """``f`` as the static C function ``c_name`` (arg, res, iw, w, mem), printed by ``codegen.printer`` with the
    project's options (reciprocals, precision math, unused parameters cast to void): no work memory (its values are
    locals; the templates call it with none), checked to call no helper but casadi_sq and ``host_helpers`` (CasADi
    helpers the file it goes into defines). ``all_io``: the templates pass every input and output (none NULL), so
    the tests of each pointer at each read and write are left out; ``inputs_given``: only those of the inputs."""
    printed = print_function(f, PrintOptions(name=c_name, guard_inputs=not (all_io or inputs_given),
                                             guard_outputs=not all_io, reciprocals=True, precision_math=True,
                                             void_unused=True))
    if set(printed.helpers) - {"casadi_sq", *host_helpers}:
        raise AssertionError(f"{f.name()}: its C is not self-contained; the templates need it to be")
    return printed.text


def defined_helpers(c_text: str) -> frozenset[str]:
    """The CasADi helpers (e.g. casadi_sq, casadi_fabs) a generated file defines."""
    return frozenset(re.findall(r"\n(?:static (?:inline )?)?casadi_real (casadi_\w+)\(", c_text))
