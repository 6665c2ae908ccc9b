"""The facts Python and the generated C share have one source (``codegen.c_facts``): the C side is written from it,
and no hand-written file states them again."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

from quadruped_dyn.codegen import c_facts
from quadruped_dyn.codegen.c_facts import PRELUDE, RETURN_CODES, TEMPLATES, prelude_c, return_codes_c
from quadruped_dyn.codegen.library import C_FLAGS
from quadruped_dyn.codegen.library import RETURN_CODES as LIBRARY_CODES
from quadruped_dyn.errors import InputError, NumericalError

ROOT = Path(__file__).resolve().parents[2]
PACKAGE_C_AND_PY = [*TEMPLATES.glob("*.c"), *TEMPLATES.glob("*.h"), *(ROOT / "quadruped_dyn" / "codegen").glob("*.py")]


def test_codes_are_distinct_and_python_reads_them():
    assert len({c.value for c in RETURN_CODES}) == len({c.name for c in RETURN_CODES}) == len(RETURN_CODES)
    assert LIBRARY_CODES == {c.value: c.meaning for c in RETURN_CODES}
    assert 0 not in LIBRARY_CODES


@pytest.mark.parametrize("path", PACKAGE_C_AND_PY, ids=lambda p: p.name)
def test_no_hand_written_file_defines_a_code_or_an_attribute_again(path):
    """The codes' macros come from ``return_codes_c`` alone, the layouts' from ``layouts_c``, QD_NOINLINE /
    QD_INLINE / QD_EPS from qd_prelude.h alone."""
    text = path.read_text()
    for c in RETURN_CODES:
        assert not re.search(rf"#\s*define\s+{c.name}\b", text), (path.name, c.name)
    if path.name not in (PRELUDE, "c_facts.py"):
        for macro in ("QD_NOINLINE", "QD_INLINE", "QD_EPS", "QD_SINGULAR_RTOL", "QD_FOOT", "QD_FOOT_J", "QD_M_BLOCKS",
                      "QD_M_BL", "QD_M_LL"):
            assert not re.search(rf"#\s*define\s+{macro}\b", text), (path.name, macro)


def test_generated_macros_have_pythons_values(tmp_path):
    """A C program built from the written macros agrees with Python's values (a negative array size otherwise)."""
    checks = " && ".join(f"{c.name} == {c.value}" for c in RETURN_CODES)
    program = tmp_path / "codes.c"
    program.write_text("#define casadi_real double\n" + prelude_c() + return_codes_c()  # twice: guarded
                       + f"typedef char codes_agree[{checks} ? 1 : -1];\n"
                       "int main(void) { return (int)sizeof(codes_agree) - 1 + (QD_EPS > 1 ? 1 : 0); }\n")
    proc = subprocess.run(["gcc", *C_FLAGS, "-fsyntax-only", str(program)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.parametrize("code", RETURN_CODES, ids=lambda c: c.name)
def test_python_raises_by_the_codes_kind(code, paper):
    """``CompiledFunction`` raises NumericalError for a code of the model, InputError for one of the input."""
    from quadruped_dyn.codegen.library import CompiledFunction

    fn = object.__new__(CompiledFunction)
    fn.name = "qd_f"
    with pytest.raises(NumericalError if code.numerical else InputError, match=re.escape(code.meaning[:40])):
        fn._raise_for(code.value)
    assert c_facts.RETURN_CODE[code.name] is code


def test_layout_macros_read_what_python_stacks(tmp_path):
    """The C macros of ``layouts_c`` read M's blocks from ``mass_blocks`` and a foot's parts from ``FOOT_PARTS``'
    stacking at the entries Python put them (a C program compares every entry)."""
    import casadi as ca
    import numpy as np

    from quadruped_dyn.codegen.c_facts import layouts_c
    from quadruped_dyn.codegen.forms.leg_pieces import FOOT_PARTS, mass_blocks
    from quadruped_dyn.math.spatial import stacked

    M = np.arange(18 * 18, dtype=float).reshape(18, 18) + 1
    Mc = np.asarray(mass_blocks(ca.DM(M))).ravel()
    parts = [np.arange(r * c, dtype=float).reshape(r, c, order="F") + 100 * k for k, (_, r, c) in enumerate(FOOT_PARTS)]
    y = np.asarray(ca.evalf(stacked(tuple(ca.DM(p) for p in parts)))).ravel()
    M, (r, J, Jqd, Jdqd) = M.astype(object), (p.astype(object) for p in parts)  # entries print as Python floats

    def array(name: str, x: np.ndarray) -> str:
        return f"static const double {name}[{x.size}] = {{{', '.join(repr(float(v)) for v in x)}}};\n"

    checks = [f"QD_M_BB(Mc, {i}, {k}) == {M[i, k]!r}" for i in range(6) for k in range(6)]
    checks += [f"QD_M_BL(Mc, {l}, {i}, {c}) == {M[i, 6 + 3 * l + c]!r}" for l in range(4) for i in range(6) for c in range(3)]
    checks += [f"QD_M_LL(Mc, {l}, {i}, {c}) == {M[6 + 3 * l + i, 6 + 3 * l + c]!r}"
               for l in range(4) for i in range(3) for c in range(3)]
    checks += [f"QD_FOOT_R(y, {d}) == {r[d, 0]!r} && QD_FOOT_JQD(y, {d}) == {Jqd[d, 0]!r} && "
               f"QD_FOOT_JDQD(y, {d}) == {Jdqd[d, 0]!r}" for d in range(3)]
    checks += [f"QD_FOOT_J(y, {d}, {c}) == {J[d, c]!r}" for d in range(3) for c in range(3)]
    program = tmp_path / "layouts.c"
    program.write_text(layouts_c() + array("Mc", Mc) + array("y", y)
                       + f"int main(void) {{ return !(QD_M_BLOCKS == {Mc.size} && QD_FOOT == {y.size} && "
                       + " && ".join(checks) + "); }\n")
    exe = tmp_path / "layouts"
    subprocess.run(["gcc", *C_FLAGS, str(program), "-o", str(exe)], check=True, capture_output=True)
    assert subprocess.run([str(exe)], check=False).returncode == 0
