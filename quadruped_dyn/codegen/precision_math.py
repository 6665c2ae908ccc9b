"""The elementary functions in casadi_real's precision: the generated C calls qd_sin, qd_cos, ... (``PRECISION_MATH``),
wrappers a file defines after its casadi_real default (``wrappers_c``). A float build (-Dcasadi_real=float) calls sinf,
cosf, ... instead of promoting to double (-Wdouble-promotion clean); a long double build calls sinl, cosl, ...; a
double build sin, cos, ... The printer writes these names (``PrintOptions.precision_math``), and so do the
hand-written templates (read through ``template_c``, which checks it)."""

from __future__ import annotations

import re

from quadruped_dyn.codegen.c_facts import TEMPLATES

#: The elementary functions the generated code calls, each through a wrapper in casadi_real's precision
PRECISION_MATH = ("sin", "cos", "tan", "sqrt", "fabs")
_BLOCK = """
/* quadruped_dyn: the elementary functions in casadi_real's precision. A float build
 * (-Dcasadi_real=float) calls sinf, cosf, ... instead of promoting to double, so it does no
 * double arithmetic (none on a single-precision FPU: -Wdouble-promotion clean); a long double
 * build wider than double (x87's 64-bit significand) calls sinl, cosl, ...; a double build
 * calls sin, cos, ... exactly as before. */
#define QD_REAL_IS_FLOAT (sizeof(casadi_real) == sizeof(float))
#define QD_REAL_IS_EXTENDED (sizeof(casadi_real) > sizeof(double))
#define QD_MATH(fn) static inline casadi_real qd_##fn(casadi_real x) { return QD_REAL_IS_FLOAT ? (casadi_real)fn##f((float)x) \\
  : QD_REAL_IS_EXTENDED ? (casadi_real)fn##l((long double)x) : (casadi_real)fn((double)x); }
"""
_LIBM = "sin|cos|tan|sqrt|fabs|atan2?|asin|acos|exp|log|pow|tanh|sinh|cosh|floor|ceil|fmin|fmax|erf"
_LIBM_CALL = re.compile(rf"(?<![\w.])({_LIBM})\(")


def template_c(name: str) -> str:
    """The hand-written template ``c/<name>``, which calls the elementary functions by their wrappers (qd_sqrt,
    qd_fabs, ...: ``PRECISION_MATH``) itself, never libm's names (an AssertionError names any it calls)."""
    text = (TEMPLATES / name).read_text()
    unwrapped = set(_LIBM_CALL.findall(text))
    if unwrapped:
        raise AssertionError(f"{name} calls {sorted(unwrapped)} by libm's names; expected qd_<fn> wrappers of {PRECISION_MATH}")
    return text


def wrappers_c(calls: str) -> str:
    """The wrappers the C ``calls`` calls (only those: clang warns of an unused static inline function, an error
    under the Makefile's -Werror), to follow the casadi_real default; empty if it calls none."""
    wrapped = [f for f in PRECISION_MATH if re.search(rf"(?<![\w.])qd_{f}\(", calls)]
    return _BLOCK + " ".join(f"QD_MATH({f})" for f in wrapped) + "\n" if wrapped else ""
