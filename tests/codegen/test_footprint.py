# ruff: noqa: E501  (the call-graph sample keeps gcc's long lines)
"""Flash and stack of the generated C on Cortex-M (docs/embedded.md): the call-graph walk on
the compiler's own .ci output, and (slow, needs arm-none-eabi-gcc) the paper robot's footprint
against the issue's budgets."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from quadruped_dyn.checks.embedded import library_work_memory
from quadruped_dyn.codegen.emit import REDUCED_STANCE_SETS
from quadruped_dyn.codegen.footprint import (
    BUDGET_FULL_CODE,
    BUDGET_REDUCED_CODE,
    BUDGET_ROBOT,
    BUDGET_STACK,
    _register_count,
    _worst_stack,
    measure,
    parse_callgraph,
    summary,
)
from quadruped_dyn.codegen.targets import TARGETS, skip_reason
from quadruped_dyn.model.robot import load_robot

CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"

# the shape of gcc 12's -fcallgraph-info=su output (abridged from a real qd_paper_r_FL_BR.ci)
_CI = """graph: { title: "qd_paper_r_FL_BR.c"
node: { title: "qd_paper_r_FL_BR.c:qd_paper_r_FL_BR_f0" label: "qd_paper_r_FL_BR_f0\\nqd_paper_r_FL_BR.c:176:12\\n1336 bytes (static)" }
node: { title: "sqrt" label: "sqrt\\n/usr/include/newlib/math.h:112:15" shape : ellipse }
node: { title: "qd_paper_r_FL_BR.c:qd_fd_r_solve.constprop.0" label: "qd_fd_r_solve.constprop\\nqd_paper_r_FL_BR.c:120:19\\n1552 bytes (static)" }
node: { title: "qd_fd_r_FL_BR" label: "qd_fd_r_FL_BR\\nqd_paper_r_FL_BR.c:9700:26\\n32 bytes (static)" }
edge: { sourcename: "qd_paper_r_FL_BR.c:qd_paper_r_FL_BR_f0" targetname: "sqrt" label: "qd_paper_r_FL_BR.c:1382:8" }
edge: { sourcename: "qd_paper_r_FL_BR.c:qd_fd_r_solve.constprop.0" targetname: "qd_paper_r_FL_BR.c:qd_paper_r_FL_BR_f0" }
edge: { sourcename: "qd_fd_r_FL_BR" targetname: "qd_paper_r_FL_BR.c:qd_fd_r_solve.constprop.0" }
}
"""


def test_call_graph_walk_adds_the_deepest_chain():
    frames, calls = parse_callgraph(_CI)
    assert frames["qd_fd_r_FL_BR"] == (32, True) and frames["qd_fd_r_solve.constprop.0"] == (1552, True)
    assert frames["sqrt"] is None  # external: its frame comes from the disassembly
    frames["sqrt"] = (24, True)
    assert _worst_stack("qd_fd_r_FL_BR", frames, calls, {}) == (32 + 1552 + 1336 + 24, True)
    del frames["sqrt"]  # a callee of unknown frame makes the bound unknown, never silently small
    assert _worst_stack("qd_fd_r_FL_BR", frames, calls, {})[1] is False


def test_register_lists():
    assert _register_count("r4, r5, r6, r7, lr") == 5
    assert _register_count("r4-r11, lr") == 9
    assert _register_count("d8-d15") == 8


def test_caller_memory_is_what_the_generated_header_states():
    """``codegen --json``'s caller memory (compiled ``_work`` entries and Functions) against the committed paper
    header: the functions in its order, its _SZ_ARG/RES/IW/W macros, its double/float byte counts."""
    header = (CASADI_GEN / "qd_paper.h").read_text()
    memory = library_work_memory(load_robot("paper"))
    assert list(memory) == re.findall(r"^ \*   (qd_\w+)\(", header, re.M)
    defines = {(n, k): int(v) for n, k, v in re.findall(r"#define (\w+)_SZ_(ARG|RES|IW|W) (\d+)", header)}
    assert {(n, k): getattr(m, f"sz_{k.lower()}") for n, m in memory.items() for k in ("ARG", "RES", "IW", "W")} == defines
    stated = {n: (int(d), int(f)) for n, d, f in re.findall(r" (qd_\w+) (\d+)/(\d+);", header)}
    assert stated == {n: (m.bytes(8), m.bytes(4)) for n, m in memory.items()}


def _paper_footprint(tmp_path: Path, name: str) -> tuple[object, dict, list[str]]:
    reason = skip_reason(TARGETS[name], run=False)
    if reason:
        pytest.skip(reason)
    names = list(library_work_memory(load_robot("paper")))
    fp = measure(CASADI_GEN, tmp_path / "build", name, names, "qd_paper", "-Os")
    return fp, summary(fp, names, [st.name.replace("+", "_") for st in REDUCED_STANCE_SETS]), names


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cortex-m7", "cortex-m4f"])
def test_paper_footprint_meets_the_budgets(tmp_path, name):
    """casadi_gen at -Os: M + C+G + id <= 64 kB, M_r + CG_r + fd_r of every stance set <= 48 kB,
    every function's stack bounded and <= 8 kB, the derivatives' included."""
    fp, s, names = _paper_footprint(tmp_path, name)
    assert set(fp.functions) == set(names)
    assert s["all_bounded"]
    assert 0 < s["full_code"] <= BUDGET_FULL_CODE, s["full_code"]
    assert all(0 < v <= BUDGET_REDUCED_CODE for v in s["reduced_code"].values()), s["reduced_code"]
    stacks = {n: f.stack for n, f in fp.functions.items()}  # the derivatives' temporaries are the caller's w
    assert any(n.startswith(("qd_dfd_r_", "qd_dfd_full", "qd_dgrf_")) for n in stacks)
    assert stacks and all(0 < v <= BUDGET_STACK for v in stacks.values()), max(stacks.items(), key=lambda x: x[1])
    # fd_r runs the stance's parts, M_full and rnea below its own frame (M_r's and the LU's arrays)
    for st in REDUCED_STANCE_SETS:
        k = st.name.replace("+", "_")
        assert fp.functions[f"qd_fd_r_{k}"].stack > fp.functions[f"qd_M_r_{k}"].stack


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cortex-m7"])
def test_paper_footprint_with_the_derivatives_meets_the_budgets(tmp_path, name):
    """The same stack and whole-robot budgets with the derivative functions counted (met since
    the reduced files call the robot's M_full, G_full and id_full instead of their own copies; before, the
    whole robot was ~1.2 MB of 1 MB on Cortex-M7 -Os)."""
    fp, s, _ = _paper_footprint(tmp_path, name)
    assert 0 < s["max_stack"] <= BUDGET_STACK, s["max_stack"]
    assert 0 < s["total"] <= BUDGET_ROBOT, s["total"]
