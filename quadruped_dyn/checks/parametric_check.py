"""The parametric library's check package: Pinocchio's values at the check inputs for one robot's p and a Makefile.

``codegen ROBOT --parametric --out DIR`` writes, beside qdp_<family>.c/.h, ``qdp_<family>-reference.h`` (the fixed
library's reference header, ``check_program_values.reference_header``, for the parametric full terms at
``reference_state`` with ROBOT's p as their last input; regressor_full is left out: Pinocchio has no value of its own
for it) and a Makefile written here from data, whose ``make check`` builds the parametric library and check_qd.c
against them in double and float and runs both.
"""

from __future__ import annotations

from quadruped_dyn.checks.check_program_values import reference_header
from quadruped_dyn.codegen import c_facts
from quadruped_dyn.codegen.c_facts import TEMPLATES
from quadruped_dyn.codegen.file_names import CHECK_PROGRAM, MAKEFILE, family_stem
from quadruped_dyn.codegen.parametric_library import c_named, parametric_c
from quadruped_dyn.dynamics.parametric import parametric_dynamics
from quadruped_dyn.model.parameters import check_parameters, family_of, parameters_of
from quadruped_dyn.model.robot import Robot

#: The parametric functions the check program compares with Pinocchio (regressor_full has no Pinocchio value)
CHECKED = ("M_full", "C_full", "G_full", "nle_full", "id_full")


def parametric_makefile(stem: str) -> str:
    """The Makefile of the parametric check package: ``make check`` builds and runs check_qd in double and float."""
    header, reference = f"{stem}.h", f"{stem}-reference.h"
    # the return codes check_qd.c names (the parametric functions return none of them but 0 or QD_NONFINITE)
    codes = " ".join(f"-D{c.name}={c.value}" for c in c_facts.RETURN_CODES)
    lines = [
        f"# Builds the parametric library {stem} and the check program that compares it, at one robot's p, with",
        "# Pinocchio's reference values.   make check   builds and runs it in double and in float.",
        "CC ?= cc", "CFLAGS ?= -O2", "WARN = -std=c99 -pedantic -Wall -Wextra -Werror", "B = build",
        f"CHECK = {CHECK_PROGRAM} {stem}.c {codes} -DQD_HEADER='\"{header}\"' "
        f"-DQD_REFERENCE='\"{reference}\"' -lm",
        "", "all: $(B)/check_qd $(B)/check_qd_float", "",
        f"$(B)/check_qd: {CHECK_PROGRAM} {stem}.c {header} {reference}",
        "\tmkdir -p $(B)", "\t$(CC) $(WARN) $(CFLAGS) -Dcasadi_real=double $(CHECK) -o $@", "",
        f"$(B)/check_qd_float: {CHECK_PROGRAM} {stem}.c {header} {reference}",
        "\tmkdir -p $(B)", "\t$(CC) $(WARN) $(CFLAGS) -Dcasadi_real=float -DQD_FLOAT $(CHECK) -o $@", "",
        "check: all", "\t./$(B)/check_qd", "\t./$(B)/check_qd_float", "", ".PHONY: all check",
    ]
    return "\n".join(lines) + "\n"


def parametric_package(robot: Robot, precision: str = "double") -> dict[str, str]:
    """File name -> text of the parametric check package of ``robot``'s family at ``robot``'s p (module docstring)."""
    family = family_of(robot)
    stem = family_stem(family.key)
    source, header = parametric_c(family, precision)
    functions = [f for f in parametric_dynamics(family).functions() if f.name() in CHECKED]
    renamed = [c_named(f) for f in functions]
    work = {f.name(): (0, 0) for f in renamed}  # the parametric functions state no work (their _SZ_IW, _SZ_W: 0)
    reference = reference_header(robot, renamed, work, parameters=check_parameters(parameters_of(robot)))
    return {f"{stem}.c": source, f"{stem}.h": header, f"{stem}-reference.h": reference,
            CHECK_PROGRAM: (TEMPLATES / CHECK_PROGRAM).read_text(), MAKEFILE: parametric_makefile(stem)}
