"""The elementary functions in casadi_real's precision: the generated C calls qd_sin, qd_cos, ... (``PRECISION_MATH``),
wrappers a file defines after its casadi_real default (``wrappers_c``). A float build (-Dcasadi_real=float) calls sinf,
cosf, ... instead of promoting to double (-Wdouble-promotion clean); a long double build calls sinl, cosl, ...; a
double build sin, cos, ... The printer writes these names (``PrintOptions.precision_math``); the hand-written
templates are written with libm's names and read through ``template_c``."""

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
_MATH_CALL = re.compile(rf"(?<![\w.])({'|'.join(PRECISION_MATH)})\(")
_UNWRAPPED = re.compile(r"(?<![\w.])(atan2?|asin|acos|exp|log|pow|tanh|sinh|cosh|floor|ceil|fmin|fmax|erf)\(")


def precision_calls(c_text: str) -> str:
    """``c_text`` (hand-written C) with its elementary functions as the wrappers (sin( -> qd_sin() and double literals
    in products and quotients as integers ((2.*a) -> (2*a), (1./a) -> (1/a): the same value in double, no promotion
    in float)."""
    unknown = set(_UNWRAPPED.findall(c_text))
    if unknown:
        raise AssertionError(f"elementary functions {sorted(unknown)} have no precision wrapper in PRECISION_MATH")
    c_text = _MATH_CALL.sub(r"qd_\1(", c_text)
    c_text = re.sub(r"\((\d+)\.\*", r"(\1*", c_text)
    return re.sub(r"\((\d+)\./", r"(\1/", c_text)


def template_c(name: str) -> str:
    """The hand-written template ``c/<name>`` as the generated files hold it: its elementary functions in casadi_real's
    precision (``precision_calls``)."""
    return precision_calls((TEMPLATES / name).read_text())


def wrappers_c(calls: str) -> str:
    """The wrappers the C ``calls`` calls (only those: clang warns of an unused static inline function, an error
    under the Makefile's -Werror), to follow the casadi_real default; empty if it calls none."""
    wrapped = [f for f in PRECISION_MATH if re.search(rf"(?<![\w.])qd_{f}\(", calls)]
    return _BLOCK + " ".join(f"QD_MATH({f})" for f in wrapped) + "\n" if wrapped else ""
