"""Quotients by a shared denominator as products with its reciprocal, in CasADi's C (docs/benchmark.md, "Design
choices").

CasADi's graphs divide each entry by a common denominator (the closed-form solves' determinants, the squared length
of the feet's support line, a mean's foot count, and their derivatives): a reduced stance file's parts divide ~90
times by ~6 values, dfd_r's lift columns ~200 times by ~7. A division costs ~4 cycles of the divider's throughput
(~14 of latency), a product 0.5, and CasADi folds x * (1 / d) back into x / d in its graph. So the C is rewritten:
a denominator value that divides more than once, or a constant, gets one reciprocal right after it is computed,
``rcpK=(1./aZ);``, and each of its quotients ``aX=(aY/aZ);`` becomes ``aX=(aY*rcpK);``. Each such result moves by at
most an ulp or so (x * fl(1/d) against fl(x / d); exact when d is a power of two); a zero or non-finite denominator
still gives a non-finite result (x * inf, 0 * inf = NaN)."""

from __future__ import annotations

import re

_ASSIGN = re.compile(r"  (a\d+)=(.*);")
_QUOTIENT = re.compile(r"\((a\d+)/(a\d+)\)")
_CONSTANT = re.compile(r"-?\d+\.(?:\d*)?(?:e[-+]?\d+)?")
_BODY = re.compile(r"(static int \w+\(const casadi_real\*\* arg, casadi_real\*\* res, casadi_int\* iw, casadi_real\* w, "
                   r"int mem\) \{\n)(.*?\n)(\}\n)", re.S)


def _body_with_reciprocals(body: str) -> str:
    lines = body.split("\n")
    written: dict[str, int] = {}  # variable -> the line that last wrote it
    constants: set[int] = set()  # the lines that write a constant
    uses: dict[tuple[str, int], list[int]] = {}  # (denominator, its writing line) -> the quotient lines
    for k, line in enumerate(lines):
        assign = _ASSIGN.fullmatch(line)
        if not assign:
            continue
        quotient = _QUOTIENT.fullmatch(assign.group(2))
        if quotient and quotient.group(2) in written:
            uses.setdefault((quotient.group(2), written[quotient.group(2)]), []).append(k)
        if _CONSTANT.fullmatch(assign.group(2)):
            constants.add(k)
        written[assign.group(1)] = k
    shared = {key: quotients for key, quotients in uses.items() if len(quotients) > 1 or key[1] in constants}
    if not shared:
        return body
    after: dict[int, list[str]] = {}
    for n, ((den, at), quotients) in enumerate(sorted(shared.items(), key=lambda item: item[0][1])):
        after.setdefault(at, []).append(f"  rcp{n}=(1./{den});")
        for k in quotients:
            lines[k] = _QUOTIENT.sub(rf"(\1*rcp{n})", lines[k])
    out = []
    for k, line in enumerate(lines):
        out.append(line)
        out.extend(after.get(k, []))
    declared = "  casadi_real " + ", ".join(f"rcp{n}" for n in range(len(shared))) + ";"
    first_statement = next(k for k, line in enumerate(out) if line and not line.startswith(("  casadi_real ", "  (void)")))
    return "\n".join(out[:first_statement] + [declared] + out[first_statement:])


def shared_reciprocals(c_source: str) -> str:
    """``c_source`` (CasADi's C) with each evaluation function's quotients by a shared or constant denominator as
    products with its reciprocal (module docstring)."""
    return _BODY.sub(lambda m: m.group(1) + _body_with_reciprocals(m.group(2)) + m.group(3), c_source)
