"""The README: its Python example runs as written, it stays a front page, and every number in
its marked block is what the code gives today.

The block (``<!-- numbers: ... -->`` ... ``<!-- /numbers -->``) is a two-column table. Each row
is recomputed here: structural numbers exactly (robot count, joints, masses, ranks, stance sets,
generated functions, bytes of generated C), the measured one (the worst relative error of a
term against Pinocchio) by a quick rerun of the check on fewer states, which must pass and land
within a factor of the stated value (round-off digits differ between machines, their size does
not). A row this file does not know fails, so a number cannot be added without a check.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
CASADI_GEN = ROOT / "casadi_gen"

#: The README's measured worst error is over 200 states; the rerun uses fewer. Its worst can be
#: lower (fewer states) or, on another machine's round-off, somewhat higher: a factor 30 either
#: way still catches a change of the algorithms (orders of magnitude) or a README left behind.
QUICK_SAMPLES = 3
MEASURED_FACTOR = 30.0


def numbers_block() -> dict[str, str]:
    found = re.search(r"<!-- numbers:[^>]*-->\n(.*?)<!-- /numbers -->", README.read_text(), flags=re.S)
    assert found, "the README has no <!-- numbers: ... --> block"
    rows = {}
    for line in found.group(1).splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 2 and cells[0] not in ("what", "") and not set(cells[0]) <= {"-"}:
            rows[cells[0]] = cells[1]
    return rows


def test_python_examples_run():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "the README has no Python example"
    for block in blocks:
        exec(compile(block, str(README), "exec"), {})  # noqa: S102 - our own README


def test_front_page_size_and_links():
    text = README.read_text()
    assert len(text.splitlines()) <= 150, "the README is a front page: put details into docs/"
    for target in re.findall(r"\]\(((?:docs/)[^)#]+)", text):
        assert (ROOT / target).is_file(), f"README links to {target}, which does not exist"


# ----------------------------------------------------------------------------- the numbers block


def _robots() -> str:
    from quadruped_dyn.model.registry import ROBOT_NAMES

    return f"{len(ROBOT_NAMES)}: {' '.join(ROBOT_NAMES)}"


def _joints() -> str:
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot("paper")
    per_leg = {len(leg.joints) for leg in robot.legs}
    assert len(per_leg) == 1
    return f"{len(robot.legs)} × {per_leg.pop()} = {sum(len(leg.joints) for leg in robot.legs)} joints"


def _mass() -> str:
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.model.robot_summary import robot_info

    return f"{robot_info(load_robot('paper'))['total_mass_kg']:.2f} kg"  # as the report's robot section prints it


def _ranks() -> str:
    from quadruped_dyn.model.stance import STANCE_SETS

    ranks: dict[int, set[int]] = {}
    for s in STANCE_SETS:
        ranks.setdefault(len(s.feet), set()).add(s.rank("paper"))
    assert all(len(r) == 1 for r in ranks.values()), ranks  # one rank per number of feet
    return " / ".join(str(ranks[k].pop()) for k in (4, 3, 2))


def _reduced() -> str:
    """Stance sets with a reduced model, and those whose M_r is singular at the standing posture
    with the trunk level (compiled library, cond(M_r) beyond the model's own limit)."""
    from quadruped_dyn.codegen.emit import REDUCED_STANCE_SETS, reduced_symbol
    from quadruped_dyn.codegen.library import CompiledFunction, compiled_library
    from quadruped_dyn.dynamics.reduced import MAX_COND_M_R
    from quadruped_dyn.errors import InputError, NumericalError
    from quadruped_dyn.model.robot import load_robot

    robot = load_robot("paper")
    library = compiled_library(robot)
    singular = []
    for s in REDUCED_STANCE_SETS:
        n = 13 if len(s.feet) == 2 else 12
        q_r = np.append(robot.standing_q, np.zeros(n - 12))
        try:
            (M,) = CompiledFunction(library, reduced_symbol("M_r", s))(q_r, np.array([0.0, 0.0, 0.0, 1.0]))
            cond = float(np.linalg.cond(np.asarray(M).reshape(n, n)))
        except (InputError, NumericalError):  # a non-finite M_r (QD_NONFINITE) or a singular one
            cond = float("inf")
        if not cond < MAX_COND_M_R:
            singular.append(s.name)
    return f"{len(REDUCED_STANCE_SETS)}; singular at a level trunk: {', '.join(singular)}"


def _functions() -> str:
    from quadruped_dyn.codegen.emit import CODEGEN_FUNCTIONS, N_DERIVATIVE_FUNCTIONS, REDUCED_NAMES, REDUCED_STANCE_SETS

    full, reduced = len(CODEGEN_FUNCTIONS), len(REDUCED_STANCE_SETS) * len(REDUCED_NAMES)
    derivatives = N_DERIVATIVE_FUNCTIONS
    header = (CASADI_GEN / "qd_paper.h").read_text()
    documented = re.findall(r"^ \*   (qd_\w+)\(.*iw \d+, w \d+", header, flags=re.M)
    assert len(documented) == full + reduced + derivatives, "casadi_gen/ is not what the code generates: regenerate it"
    return (f"{full + reduced + derivatives} = {full} full-coordinate and GRF + {reduced} reduced"
            f" + {derivatives} derivatives")


def _c_size() -> str:
    """The paper robot's library: its sources and the headers they include (codegen.emit.GeneratedFiles.library_sources)."""
    from quadruped_dyn.codegen.emit import REDUCED_TEMPLATES

    files = [*CASADI_GEN.glob("qd_paper*.c"), CASADI_GEN / "qd_paper.h", CASADI_GEN / REDUCED_TEMPLATES]
    return f"{sum(p.stat().st_size for p in files) / 1e6:.1f} MB"


EXACT: dict[str, Callable[[], str]] = {
    "built-in robots": _robots,
    "legs × joints": _joints,
    "mass of the paper's robot": _mass,
    "rank of the paper's GRF model with 4 / 3 / 2 feet": _ranks,
    "stance sets with a reduced model": _reduced,
    "generated C functions in `casadi_gen/`": _functions,
    "generated C of the library in `casadi_gen/`, headers included": _c_size,
}
MEASURED = ("terms checked against Pinocchio", "worst relative error of a term, 200 random states")


def test_numbers_block_has_only_checked_rows():
    assert set(numbers_block()) == set(EXACT) | set(MEASURED)


@pytest.mark.parametrize("what", list(EXACT))
def test_structural_number(what):
    assert numbers_block()[what] == EXACT[what](), f"README row '{what}' no longer matches the code"


def test_measured_check_numbers():
    """A quick rerun of `check paper` (QUICK_SAMPLES states): the term count exactly, the
    worst relative error within MEASURED_FACTOR of the README's, the tolerance exactly."""
    from quadruped_dyn.checks.terms import run_check
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.tolerances import REL_TOL_TERMS

    rows = numbers_block()
    found = re.fullmatch(r"(\S+) \(tolerance (\S+)\)", rows[MEASURED[1]])
    assert found, rows[MEASURED[1]]
    stated, tol = float(found.group(1)), float(found.group(2))
    assert tol == REL_TOL_TERMS
    report = run_check(load_robot("paper"), QUICK_SAMPLES, 0)
    assert report.passed
    assert rows[MEASURED[0]] == str(len(report.terms))
    worst = max(t.max_rel_err for t in report.terms)
    assert stated / MEASURED_FACTOR <= worst <= stated * MEASURED_FACTOR, (
        f"worst relative error now {worst:.1e}; the README says {stated:g}: rerun `check paper --samples 200` and update")
