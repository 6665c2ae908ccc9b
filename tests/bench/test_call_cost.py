"""The per-call counts under callgrind (bench/call_cost.py), checked on a hand-written function whose
instructions and code bytes are known from its source, and against ``nm -S``."""

from __future__ import annotations

import platform
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from quadruped_dyn.bench.call_cost import CODE_BUDGET_BYTES, callgrind_counts, measure
from quadruped_dyn.bench.harnesses import HARNESSES
from quadruped_dyn.errors import InputError

pytestmark = pytest.mark.skipif(shutil.which("valgrind") is None or platform.machine() != "x86_64",
                                reason="needs valgrind on x86-64 (the test function is x86-64 assembly)")

LOOP = 50  # iterations of the loop: 2 instructions each
COLD = 101  # bytes of the block no call reaches: 100 one-byte nops and a ret
#: mov; LOOP x (dec; jnz); test; jnz (not taken); ret
INSTRUCTIONS_PER_CALL = 1 + 2 * LOOP + 3

TINY = f"""
    .text
    .globl qd_tiny_loop
    .type qd_tiny_loop, @function
qd_tiny_loop:
    movl ${LOOP}, %ecx
1:  decl %ecx
    jnz 1b
    testl %edi, %edi
    jnz 2f
    ret
2:  .fill {COLD - 1}, 1, 0x90
    ret
    .size qd_tiny_loop, .-qd_tiny_loop
    .section .note.GNU-stack,"",@progbits
"""

#: A function that runs one more loop iteration on every call: no fixed per-call count.
GROWING = """
static int k;
void qd_growing(void) { for (int i = 0; i < k; ++i) __asm__ volatile(""); ++k; }
"""

MAIN = """
#include <stdlib.h>
int qd_tiny_loop(int cold);
void qd_growing(void);
int main(int argc, char** argv) {
  int n = atoi(argv[1]);
  for (int k = 0; k < n; ++k) { qd_tiny_loop(0); qd_growing(); }
  return 0;
}
"""


@pytest.fixture(scope="module")
def program(tmp_path_factory) -> Path:
    work = tmp_path_factory.mktemp("call_cost")
    for name, text in (("tiny.S", TINY), ("growing.c", GROWING), ("main.c", MAIN)):
        (work / name).write_text(text)
    exe = work / "tiny"
    subprocess.run(["gcc", "-O1", "-no-pie", "-static", "main.c", "growing.c", "tiny.S", "-o", str(exe)],
                   cwd=work, check=True)
    return exe


def symbol_size(exe: Path, symbol: str) -> int:
    out = subprocess.run(["nm", "-S", str(exe)], capture_output=True, text=True, check=True).stdout
    return next(int(line.split()[1], 16) for line in out.splitlines() if line.endswith(f" {symbol}"))


def test_counts_of_a_known_function(program, tmp_path):
    cost = measure(lambda n: [str(program), str(n)], "qd_tiny_loop", program, tmp_path)
    assert cost.instructions == INSTRUCTIONS_PER_CALL
    assert cost.i1_misses == 0  # 14 bytes stay in a 32 kB cache between calls
    assert cost.code_bytes == symbol_size(program, "qd_tiny_loop") - COLD  # every byte but the cold block
    assert not cost.over_budget and cost.code_bytes < CODE_BUDGET_BYTES


@pytest.mark.parametrize("calls", [1, 2, 7])
def test_instructions_scale_with_the_calls(program, tmp_path, calls):
    """Only the function is counted (not the harness's loop or process start): n calls, n times one call's count."""
    instructions, misses, addresses = callgrind_counts([str(program), str(calls)], "qd_tiny_loop", tmp_path / "out")
    assert instructions == calls * INSTRUCTIONS_PER_CALL
    assert 0 < misses <= 2  # the cold start: the function's 14 bytes span at most two 64-byte lines
    assert len(addresses) == 6  # mov, dec, jnz, test, jnz, ret


def test_a_function_without_a_fixed_count_is_refused(program, tmp_path):
    with pytest.raises(InputError, match="qd_growing: instructions .* expected the same count every call"):
        measure(lambda n: [str(program), str(n)], "qd_growing", program, tmp_path)



def test_harness_lists_its_cases_in_order(tmp_path, paper):
    """call_cost alone prints every case's name: the reference header's functions, in the header's order."""
    from quadruped_dyn.bench.call_cost import case_names
    from quadruped_dyn.codegen.library import compiled_library

    gen = Path(__file__).resolve().parents[2] / "casadi_gen"
    lib = compiled_library(paper)
    exe = tmp_path / "call_cost"
    subprocess.run(["gcc", "-std=c99", "-Dcasadi_real=double", f"-I{gen}", '-DQD_HEADER="qd_paper.h"',
                    '-DQD_REFERENCE="qd_paper-reference.h"', str(HARNESSES / "call_cost.c"), str(lib.path),
                    f"-Wl,-rpath,{lib.path.parent}", "-lm", "-o", str(exe)], check=True)
    header = (gen / "qd_paper.h").read_text()
    assert case_names(exe) == re.findall(r"^int (qd_\w+)\(const casadi_real\*\* arg", header, re.M)
