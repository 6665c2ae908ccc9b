"""Generated C: reproducible, standalone and warning-free, and equal to the CasADi graph and
to Pinocchio when compiled and loaded back (double), and to the double build (float)."""

from __future__ import annotations

import ctypes
import json
import re
import shutil
import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from quadruped_dyn.checks.check_program_values import (
    compare_generation,
    parse_reference_header,
    pinocchio_outputs,
    reference_differences,
    reference_state,
)
from quadruped_dyn.codegen.emit import (
    ALIASES,
    CODEGEN_FUNCTIONS,
    N_DERIVATIVE_FUNCTIONS,
    PREFIX,
    REDUCED_NAMES,
    REDUCED_STANCE_SETS,
    codegen_functions,
    reduced_symbol,
)
from quadruped_dyn.codegen.library import CompiledFunction, compiled_library, load_external
from quadruped_dyn.codegen.print_settings import UNGUARDED
from quadruped_dyn.math.compare import max_abs_error, scale_of
from quadruped_dyn.model.robot import load_robot
from quadruped_dyn.model.state import random_state
from quadruped_dyn.tolerances import FLOAT_REL_TOL, REL_TOL_GRAPH, REL_TOL_TERMS

CASADI_GEN = Path(__file__).resolve().parents[2] / "casadi_gen"


def _function_scale_error(ours: list[np.ndarray], expected: list[np.ndarray]) -> float:
    """Max error over a function's outputs, relative to its largest expected value."""
    err = max(max_abs_error(np.ravel(o), np.ravel(e)) for o, e in zip(ours, expected))  # inf for NaN/inf
    return err / scale_of(np.concatenate([np.ravel(e) for e in expected]))


def test_committed_code_is_reproducible():
    """The C, header and Makefile byte for byte; the Pinocchio-computed reference values (their
    last digits depend on the CPU and BLAS) within their tolerance, naming any that moved."""
    diff = compare_generation(load_robot("paper"), CASADI_GEN)
    assert not diff, f"casadi_gen: {diff.summary()}: run `quadruped-dyn codegen paper --out casadi_gen`"


def _perturbed(text: str, array: str, index: int, factor: float) -> str:
    """The reference header with entry ``index`` of C array ``array`` multiplied by ``factor``."""
    head, rest = text.split(f"static const double {array}[", 1)
    size, body = rest.split("] = {", 1)
    values, tail = body.split("};", 1)
    items = values.split(", ")
    items[index] = repr(float(items[index]) * factor)
    return f"{head}static const double {array}[{size}] = {{{', '.join(items)}}};{tail}"


def test_reference_values_are_compared_numerically():
    """Round-off of another CPU (a few ulps, a residual's tiny value tripled) is not a difference;
    a value moved beyond the tolerance is reported by name, index and amount; a change of the
    structure (an array's size, a case's name) is a difference whatever the values."""
    text = (CASADI_GEN / "qd_paper-reference.h").read_text()
    header = parse_reference_header(text)
    assert len(header.case_outputs) == (len(CODEGEN_FUNCTIONS) + len(REDUCED_NAMES) * len(REDUCED_STANCE_SETS)
                                        + N_DERIVATIVE_FUNCTIONS)
    assert header.rel_tol == REL_TOL_TERMS and all(np.isfinite(v).all() for v in header.arrays.values())
    residual = "qd_grf_FL_FR_BL_out2"  # the GRF residual: values at the round-off level
    assert reference_differences(text, text) == []
    assert reference_differences(text, _perturbed(text, "qd_M_full_out0", 0, 1 + 1e-14)) == []
    assert reference_differences(text, _perturbed(text, residual, 0, 3.0)) == []
    assert reference_differences(text, _perturbed(text, "qd_ref_q", 7, 1 + 1e-13)) == []
    bounds = header.arrays["qd_float_bound"]
    fd_r = int(np.flatnonzero(bounds)[0])  # fd_r's float bound: a condition number, compared as tol_scale is
    assert reference_differences(text, _perturbed(text, "qd_float_bound", fd_r, 1 + 1e-3)) == []
    moved = reference_differences(text, _perturbed(text, "qd_float_bound", fd_r, 1.1))
    assert len(moved) == 1 and moved[0].startswith(f"qd_float_bound[{fd_r}] "), moved
    moved = reference_differences(text, _perturbed(text, "qd_M_full_out0", 3, 1 + 1e-6))
    assert len(moved) == 1 and moved[0].startswith("qd_M_full_out0[3] ") and "tolerance 1.0e-10" in moved[0], moved
    moved = reference_differences(text, _perturbed(text, "qd_ref_v", 2, 2.0))
    assert len(moved) == 1 and moved[0].startswith("qd_ref_v[2] "), moved
    assert reference_differences(text, _perturbed(text, "qd_G_full_out0", 0, float("nan")))[0].startswith("qd_G_full_out0[0]")
    longer = text.replace("qd_ref_f[12] = {", "qd_ref_f[12] = {1, ", 1)
    assert "qd_ref_f has 13 values" in reference_differences(text, longer)[0]
    renamed = text.replace('"qd_M_full", qd_M_full', '"qd_M_fulx", qd_M_full')
    assert "structure differs" in reference_differences(text, renamed)[0]
    resized = text.replace("qd_ref_f[12]", "qd_ref_f[13]")
    assert "structure differs" in reference_differences(text, resized)[0]


#: casadi_gen's check program reports at most this many float cases as skipped: the back pair's six reduced functions,
#: which the float build refuses at the reference state (QD_DEGENERATE: its error bound 20 eps / regularity is 2.1e-2)
MAX_FLOAT_SKIPPED = 6
#: ... and in double at most this many: dfd_r of the back pair, whose conditioning at the reference state
#: times its finite-difference reference's accuracy (REL_TOL_FD_DERIVATIVES) exceeds 1e-2
MAX_DOUBLE_SKIPPED = 1


def test_c_program_builds_and_passes(tmp_path):
    """`make check` in a copy of casadi_gen: -std=c99 -pedantic -Wall -Wextra -Werror, double and float."""
    work = tmp_path / "casadi_gen"
    shutil.copytree(CASADI_GEN, work, ignore=shutil.ignore_patterns("build"))
    proc = subprocess.run(["make", "-C", str(work), "-j2", "check"], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    n = len(CODEGEN_FUNCTIONS) + len(REDUCED_NAMES) * len(REDUCED_STANCE_SETS) + N_DERIVATIVE_FUNCTIONS
    summaries = re.findall(r"\n(\d+) passed, 0 failed(?:, (\d+) skipped)?\n", proc.stdout)
    assert len(summaries) == 2, proc.stdout[-500:]
    (passed, skipped), (passed_float, skipped_float) = ((int(p), int(k or 0)) for p, k in summaries)
    assert passed + skipped == n and skipped <= MAX_DOUBLE_SKIPPED, "double: every function checked and passing"
    assert passed_float + skipped_float == n and skipped_float <= MAX_FLOAT_SKIPPED, proc.stdout[-500:]
    assert not [p.name for p in CASADI_GEN.glob("qd_paper*.c") if "malloc" in p.read_text()]


@pytest.mark.parametrize("kind", ["qd_paper.c", "qd_paper-r-FL_BL.c", "qd_paper-d.c"])
def test_generated_source_compiles_without_precision_flag(kind):
    """A user's plain build (no -Dcasadi_real: double, CasADi's default) compiles every kind of
    generated file with the project's warnings as errors (the precision wrappers need the default)."""
    from quadruped_dyn.codegen.library import C_FLAGS

    proc = subprocess.run(["gcc", *C_FLAGS, "-fsyntax-only", str(CASADI_GEN / kind)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.parametrize("kind", ["qd_paper.c", "qd_paper-r-FL_BL.c", "qd_paper-d.c"])
def test_float_build_has_no_double_promotion(kind):
    """The float build computes in float (docs/embedded.md: `-Wdouble-promotion` clean): no float is promoted to
    double anywhere in the generated file or the templates it includes, as generated (fabs is qd_fabs there)."""
    from quadruped_dyn.codegen.library import C_FLAGS

    proc = subprocess.run(["gcc", *C_FLAGS, "-Dcasadi_real=float", "-Wdouble-promotion", "-fsyntax-only",
                           str(CASADI_GEN / kind)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.parametrize("precision", ["double", "float"])
@pytest.mark.parametrize("kind", ["qd_paper.c", "qd_paper-r-FL_BL.c", "qd_paper-r-FL_FR_BL_BR.c", "qd_paper-d.c"])
def test_generated_source_compiles_with_clang(kind, precision):
    """`make CC=clang` (the Makefile's -std=c99 -pedantic -Wall -Wextra -Werror): no warning from clang either
    (before: every file defined precision wrappers it never called, e.g. qd_tan, -Wunused-function)."""
    if not shutil.which("clang"):
        pytest.skip("clang is not installed")
    proc = subprocess.run(["clang", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", f"-Dcasadi_real={precision}",
                           "-fsyntax-only", str(CASADI_GEN / kind)], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.parametrize("kind", ["qd_paper-r-FL_BL.c", "qd_paper-r-FL_FR_BL_BR.c"])
def test_generated_source_builds_unoptimised(kind, tmp_path):
    """`make CFLAGS=-O0` (a debug build) with the Makefile's -Werror: before, GCC's -O0 stringop check failed every
    two-feet file on fd_r's dead four-feet branch (13 x 13 + 13 reals into M_r's 169)."""
    proc = subprocess.run(["gcc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O0", "-g", "-c",
                           str(CASADI_GEN / kind), "-o", str(tmp_path / "r.o")], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_header_defines_the_return_codes_it_documents(tmp_path):
    """A caller tests the documented codes by name with the header alone (before, QD_SINGULAR was undeclared), and
    they are the values the library returns."""
    from quadruped_dyn.codegen.library import C_FLAGS, QD_DEGENERATE, QD_NO_WORK, QD_NONFINITE, QD_SINGULAR

    program = tmp_path / "codes.c"
    program.write_text('#include "qd_paper.h"\n'
                       f"typedef char codes_agree[QD_NONFINITE == {QD_NONFINITE} && QD_SINGULAR == {QD_SINGULAR}"
                       f" && QD_DEGENERATE == {QD_DEGENERATE} && QD_NO_WORK == {QD_NO_WORK} ? 1 : -1];\n"
                       "int main(void) { return (int)sizeof(codes_agree) - 1; }\n")
    proc = subprocess.run(["gcc", *C_FLAGS, "-I", str(CASADI_GEN), "-fsyntax-only", str(program)],
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr[-2000:]


@pytest.mark.parametrize("precision", ["double", "float"])
def test_precision_wrappers_follow_the_casadi_real_default(precision):
    """In both precisions' generation (CasADi writes its own default of casadi_real, double or
    float) the wrappers come after that default, so their signatures compile."""
    import casadi as ca

    from quadruped_dyn.codegen.c_file import Entry, FileOptions, c_file
    from quadruped_dyn.codegen.print_settings import EVALUATION

    x = ca.SX.sym("x")
    f = ca.Function("qd_t", [x], [ca.sin(x)])
    c_text, _ = c_file("qd_t", [Entry(f, EVALUATION)], FileOptions(precision, precision_math=True))
    assert c_text.index(f"#define casadi_real {precision}") < c_text.index("QD_MATH(sin)")


def test_build_error_names_the_first_diagnostic(tmp_path):
    """A failed compile says what failed, not gcc's closing 'all warnings being treated as errors'."""
    from quadruped_dyn.codegen.library import C_FLAGS, run_tool
    from quadruped_dyn.errors import BuildError

    bad = tmp_path / "bad.c"
    bad.write_text("int f(void) { int unused; return 0; }\n")
    with pytest.raises(BuildError, match="unused variable"):
        run_tool(["gcc", *C_FLAGS, "-c", str(bad), "-o", str(tmp_path / "bad.o")])


def test_header_documents_every_function():
    header = (CASADI_GEN / "qd_paper.h").read_text()
    doc = header[: header.index("*/")]
    for name in [*CODEGEN_FUNCTIONS, *(reduced_symbol(k, st) for k in REDUCED_NAMES for st in REDUCED_STANCE_SETS)]:
        assert f" *   {PREFIX}{name}(" in doc
    for signal in ("quaternion (x, y, z, w)", "SPATIAL acceleration", "trunk frame [N]", "[N m]", "trunk roll phi",
                   "QD_NONFINITE", "QD_SINGULAR", "foot-to-foot line"):
        assert signal in doc


def _evaluate(f, inputs: dict[str, np.ndarray]) -> list[np.ndarray]:
    out = f(*[inputs[f.name_in(i)] for i in range(f.n_in())])
    return [np.asarray(x.full()) for x in (out if isinstance(out, tuple) else [out])]


def test_loaded_back_equals_graph_and_pinocchio(robot, ref, library):
    """Against the graph at a random state; against Pinocchio near standing, where every GRF
    system is well conditioned (random states can make 3-foot systems nearly singular)."""
    graphs = {f.name(): f for f in codegen_functions(robot)}
    random = random_state(robot.lower, robot.upper, np.random.default_rng(11))
    near_standing = reference_state(robot)
    for name in CODEGEN_FUNCTIONS:
        ext = load_external(library, name)
        for s in (random, near_standing):
            inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel()}
            compiled = _evaluate(ext, inputs)
            assert _function_scale_error(compiled, _evaluate(graphs[PREFIX + name], inputs)) <= REL_TOL_GRAPH, name
        expected = pinocchio_outputs(robot, ref, name, near_standing)
        err = _function_scale_error([c.ravel(order="F") for c in compiled], [np.ravel(e, order="F") for e in expected])
        assert err <= REL_TOL_TERMS, f"{name}: compiled vs Pinocchio {err:.1e}"
        fast = CompiledFunction(library, name)(*[inputs[n] for n in ext.name_in()])
        assert _function_scale_error(fast, compiled) == 0.0, f"{name}: ctypes call differs from casadi.external"


def test_aliases_are_calls_of_the_function_they_name(paper):
    """qd_M_full_crba and qd_G_full_crb (each algorithm's Python name) call qd_M_full and qd_G_full, no second copy of
    their code, and state the same metadata (names, sparsity, work sizes) and outputs, bit for bit."""
    text, header = (CASADI_GEN / "qd_paper.c").read_text(), (CASADI_GEN / "qd_paper.h").read_text()
    lib = compiled_library(paper)
    q = random_state(paper.lower, paper.upper, np.random.default_rng(2)).q
    for alias, name in ALIASES.items():
        body = re.search(rf"^CASADI_SYMBOL_EXPORT int {PREFIX}{alias}\(const casadi_real\*\* arg.*?\{{\n(.*?)^\}}",
                         text, re.M | re.S)
        assert body and body.group(1) == f"  return {PREFIX}{name}(arg, res, iw, w, mem);\n", alias
        sizes = [re.findall(rf"^#define {PREFIX}{n}_SZ_(\w+) (\d+)$", header, re.M) for n in (alias, name)]
        assert sizes[0] == sizes[1] and len(sizes[0]) == 4, (alias, sizes)
        f, g = load_external(lib, alias), load_external(lib, name)
        assert f.name_in() == g.name_in() and f.name_out() == g.name_out() and f.sparsity_out(0) == g.sparsity_out(0)
        assert np.array_equal(CompiledFunction(lib, alias)(q)[0], CompiledFunction(lib, name)(q)[0]), alias


def test_cache_key_tracks_the_source(paper):
    a, b = compiled_library(paper), compiled_library(paper)
    assert a.key == b.key and a.path == b.path, "same source, same key"
    assert compiled_library(paper, "float").key != a.key
    assert compiled_library(load_robot("solo12")).key != a.key


def test_float_build_matches_double_build(paper):
    double, single = compiled_library(paper, "double"), compiled_library(paper, "float")
    s = random_state(paper.lower, paper.upper, np.random.default_rng(3))
    inputs = {"q": s.q, "v": s.v, "a": s.a, "f": s.f.ravel()}
    for name in CODEGEN_FUNCTIONS:
        d, x = CompiledFunction(double, name), CompiledFunction(single, name)
        args = [inputs[k] for k in d.names_in]
        assert _function_scale_error(x(*args), d(*args)) <= FLOAT_REL_TOL, name


@pytest.mark.slow
def test_bench_reports_ratios_against_pinocchio(paper):
    """The benchmark harnesses build and run (no timing asserted: speed is a benchmark's job)."""
    from quadruped_dyn.bench.call_cost import CODE_BUDGET_BYTES, NOT_MEASURED, valgrind_available
    from quadruped_dyn.bench.timing import PAIRS, run_bench

    report = run_bench(paper, calls=200, reps=3, call_cost=True)
    entries = {e.name: e for e in report.entries}
    for name, (algo, _) in PAIRS.items():
        e = entries[name]
        assert e.pinocchio == algo and e.pinocchio_ns > 0 and e.ratio == pytest.approx(e.generated_ns / e.pinocchio_ns)
    assert report.code_bytes > 0 and report.library_bytes > 0
    sizes = dict(re.findall(r"^#define (qd_\w+_SZ_(?:IW|W)) (\d+)$", (CASADI_GEN / "qd_paper.h").read_text(), re.M))
    assert report.work_bytes == max(8 * (int(sizes[f"{PREFIX}{n}_SZ_IW"]) + int(sizes[f"{PREFIX}{n}_SZ_W"]))
                                    for n in entries if n != "C_full + G_full") > 0  # the header's largest
    assert report.cpu_model and report.compiler and json.dumps(report.as_dict())
    if not valgrind_available():
        assert report.call_costs == [] and report.call_cost_note == NOT_MEASURED
        return
    costs = {c.function[len(PREFIX):]: c for c in report.call_costs}
    assert set(costs) == set(entries) - {"C_full + G_full"}  # every timed function counted
    graphs = {f.name()[len(PREFIX):] for f in codegen_functions(paper)}  # one CasADi graph each: operations known
    for name, c in costs.items():
        assert c.instructions > 0 and c.code_bytes > 0 and c.i1_misses >= 0, c
        assert c.over_budget == (c.code_bytes > CODE_BUDGET_BYTES)
        assert (c.operations is not None and c.operations > 0) == (name in graphs), c


def test_missing_compiler_is_a_clear_error(paper):
    from quadruped_dyn.errors import InputError

    with pytest.raises(InputError, match="'no-such-cc' not found"):
        compiled_library(paper, cc="no-such-cc")


def test_codegen_cli_bad_input(tmp_path):
    from click.testing import CliRunner

    from quadruped_dyn.cli import main

    (tmp_path / "file").write_text("x")
    result = CliRunner().invoke(main, ["codegen", "paper", "--out", str(tmp_path / "file")])
    assert result.exit_code == 2 and "Traceback" not in result.output
    result = CliRunner().invoke(main, ["codegen", "paper", "--out", str(tmp_path), "--precision", "half"])
    assert result.exit_code == 2


def test_codegen_check_compares_at_the_precision_asked_for(tmp_path):
    """`codegen --precision float --check` compares with a float generation (it compared with a
    double one and reported a false difference); the source and the reference values are
    reported separately."""
    from click.testing import CliRunner

    from quadruped_dyn.checks.check_program_values import generate_checked
    from quadruped_dyn.cli import main

    generate_checked(load_robot("paper"), tmp_path, "float")
    ok = CliRunner().invoke(main, ["codegen", "paper", "--out", str(tmp_path), "--precision", "float", "--check"])
    assert ok.exit_code == 0 and "(float): up to date" in ok.output, ok.output
    (tmp_path / "qd_paper-reference.h").write_text(
        _perturbed((tmp_path / "qd_paper-reference.h").read_text(), "qd_C_full_out0", 1, 1.01))
    bad = CliRunner().invoke(main, ["codegen", "paper", "--out", str(tmp_path), "--check"])
    assert bad.exit_code == 1, bad.output
    assert "source differs from a fresh generation: qd_paper.c, qd_paper.h" in bad.output, bad.output
    assert "reference values differ beyond tolerance: qd_paper-reference.h: qd_C_full_out0[1] " in bad.output


def _evaluation_body(text: str, name: str) -> str:
    """The body of the function that evaluates ``name`` in the committed C: the joint-rows-first one (emit.py) or
    the one did_full's entry point passes to qd_d_all_inputs (emit_derivatives.py)."""
    called = re.search(rf"int qd_{name}\(const casadi_real\*\* arg.*?\n  return (?:qd_d_finite\(qd_d_all_inputs\()?(\w+)[(,]",
                       text, re.S)
    assert called, name
    inner = f"qd_{name}_joint_rows_first" if called.group(1) == f"qd_{name}_eval" else called.group(1)
    body = re.search(rf"\nstatic int {inner}\(.*?\n\}}\n", text, re.S)
    assert body, inner
    trig = re.search(r"return (qd_\w+_trig)\(", body.group(0))  # did_full: the graph after qd_sincos (joint_trig)
    if trig:
        body = re.search(rf"\n(?:static )?int {trig.group(1)}\(.*?\n\}}\n", text, re.S)  # exported: dfd_r calls it too
        assert body, trig.group(1)
        inner = re.search(r"return (qd_did_full_trig_in)\(", body.group(0))  # did_full by leg (codegen.by_leg)
        if inner:
            body = re.search(r"\nint qd_did_full_trig_in\(.*?\n\}\n", text, re.S)
            assert body, "qd_did_full_trig_in"
            names = set(re.findall(r"\n {2,4}(?:return )?(qd_did_full_trig_(?:head|leg\d+|tail))\(", body.group(0)))
            bodies = [re.search(rf"\n(?:QD_NOINLINE )?static int {n}\(.*?\n\}}\n", text, re.S) for n in sorted(names)]
            assert names and all(bodies), names  # the pieces it calls read the inputs
            return "".join(b.group(0) for b in bodies if b)
    return body.group(0)


def test_unguarded_functions_read_no_input_pointer_and_a_null_input_as_zeros(paper):
    """Each UNGUARDED function's evaluation reads its inputs without testing the pointers; its entry point still
    gives a NULL input zeros (CasADi's convention): the same outputs, bit for bit, as zeros passed."""
    text = "".join((CASADI_GEN / f).read_text() for f in ("qd_paper.c", "qd_paper-d.c"))
    assert UNGUARDED == {"M_full", "G_full", "did_full"}
    for name in sorted(UNGUARDED):
        body = _evaluation_body(text, name)
        assert re.search(r"arg\[\d+\]\[\d+\]", body) and not re.search(r"arg\[\d+\]\?", body), name
    assert re.search(r"arg\[\d+\]\? arg\[\d+\]\[\d+\] : 0;", _evaluation_body(text, "id_full")), "id_full stays guarded"
    lib = ctypes.CDLL(str(compiled_library(paper).path))
    s = random_state(paper.lower, paper.upper, np.random.default_rng(5))
    for name, given in (("M_full", {}), ("G_full", {}), ("did_full", {0: s.q})):  # G at q = 0: a zero quaternion
        graph = ca.external(PREFIX + name, str(compiled_library(paper).path))
        ptr = ctypes.POINTER(ctypes.c_double)
        outs = []
        for null in (True, False):
            ins = [np.asarray(given.get(i, np.zeros(graph.nnz_in(i))), dtype=float) for i in range(graph.n_in())]
            res = [np.full(graph.nnz_out(i), 7.0) for i in range(graph.n_out())]
            arg = (ptr * 8)(*[None if null and i not in given else x.ctypes.data_as(ptr) for i, x in enumerate(ins)])
            flag = getattr(lib, PREFIX + name)(arg, (ptr * 8)(*[r.ctypes.data_as(ptr) for r in res]), None, None, 0)
            outs.append((flag, np.concatenate(res)))
        assert outs[0][0] == outs[1][0] and np.array_equal(outs[0][1], outs[1][1], equal_nan=True), name


def _header_function_names() -> list[str]:
    return re.findall(r"^int (qd_\w+)\(const casadi_real\*\* arg", (CASADI_GEN / "qd_paper.h").read_text(), re.M)


def test_header_says_which_functions_read_a_null_input_as_zeros(tmp_path):
    """Each function the header names as reading a null arg[i] as zeros does, for every input, bit for bit (the
    others dereference their inputs: the header says so, since they are not CasADi's graphs)."""
    from quadruped_dyn.codegen.emit import NULL_INPUT_AS_ZEROS

    header = (CASADI_GEN / "qd_paper.h").read_text()
    assert ", ".join(NULL_INPUT_AS_ZEROS) in " ".join(line.lstrip(" *") for line in header[: header.index("*/")].split("\n"))
    patterns = [re.compile(PREFIX + name.replace("<feet>", "(?:FL|FR|BL|BR|none)(?:_(?:FR|BL|BR))*") + "$")
                for name in NULL_INPUT_AS_ZEROS]
    names = [n for n in _header_function_names() if any(p.match(n) for p in patterns)]
    assert len(names) == 7 + 16 + 2 + 15, names  # full terms and aliases, GRF solves, did_full, dfd_full_parts, dgrf_dir
    lib_path = tmp_path / "libfull.so"
    subprocess.run(["gcc", "-std=c99", "-O0", "-fPIC", "-shared", str(CASADI_GEN / "qd_paper.c"),
                    str(CASADI_GEN / "qd_paper-d.c"), "-o", str(lib_path), "-lm"], check=True, capture_output=True)
    lib = ctypes.CDLL(str(lib_path))
    ptr, rng = ctypes.POINTER(ctypes.c_double), np.random.default_rng(11)

    def nnz(sp) -> int:  # the short form {nrow, ncol, 1} of a dense pattern, else colind[ncol]
        return sp[0] * sp[1] if sp[2] == 1 else sp[2 + sp[1]]

    for name in names:
        fn = getattr(lib, name)
        getattr(lib, name + "_sparsity_in").restype = getattr(lib, name + "_sparsity_out").restype = \
            ctypes.POINTER(ctypes.c_longlong)
        n_in, n_out = getattr(lib, name + "_n_in")(), getattr(lib, name + "_n_out")()
        n_arg, n_w = ctypes.c_longlong(), ctypes.c_longlong()
        getattr(lib, name + "_work")(ctypes.byref(n_arg), None, None, ctypes.byref(n_w))
        sizes_in = [nnz(getattr(lib, name + "_sparsity_in")(i)) for i in range(n_in)]
        sizes_out = [nnz(getattr(lib, name + "_sparsity_out")(i)) for i in range(n_out)]
        values = [rng.uniform(-1, 1, k) for k in sizes_in]
        values[0][3:7] = [0.1, -0.2, 0.05, 0.97]  # q's quaternion: not zero
        w = np.zeros(max(n_w.value, 1))  # exactly the stated work memory
        for i in range(n_in):
            outs = []
            for null in (True, False):
                ins = [np.zeros(k) if j == i else values[j] for j, k in enumerate(sizes_in)]
                res = [np.full(max(k, 1), 7.0) for k in sizes_out]
                arg = (ptr * n_arg.value)(*[None if null and j == i else x.ctypes.data_as(ptr) for j, x in enumerate(ins)])
                flag = fn(arg, (ptr * n_out)(*[r.ctypes.data_as(ptr) for r in res]), None, w.ctypes.data_as(ptr), 0)
                outs.append((flag, np.concatenate(res)))
            assert outs[0][0] == outs[1][0] and np.array_equal(outs[0][1], outs[1][1], equal_nan=True), (name, i)


def test_dense_patterns_are_the_short_form_the_header_states():
    """The header tells a caller that a dense input or output's pattern is {nrow, ncol, 1}: reading it as a full
    compressed-column pattern (colind[ncol]) runs past the array (found by ASan in a caller's program)."""
    header = (CASADI_GEN / "qd_paper.h").read_text()
    assert "{nrow, ncol, 1}" in header[: header.index("*/")]
    sparsity = re.findall(r"static const casadi_int casadi_s\d+\[(\d+)\] = \{(\d+), (\d+), (\d+)[,}]",
                          (CASADI_GEN / "qd_paper-r-FL_BR.c").read_text())
    assert any(size == "3" and third == "1" for size, _, _, third in sparsity)  # e.g. q_r, M_r: dense, 3 entries


def test_header_return_notes_match_the_codes_returned(tmp_path):
    """A NaN joint angle: each full-coordinate, GRF and derivative function returns 0 or a code its header note lists,
    and always 0 where the header says it returns 0 always (before, did_full and dfd_full_parts returned QD_NONFINITE with no
    note); M_r, CG_r, G_r and id_r factor nothing and are not said to return QD_SINGULAR."""
    from quadruped_dyn.codegen.library import QD_DEGENERATE, QD_NO_WORK, QD_NONFINITE, QD_SINGULAR

    header = (CASADI_GEN / "qd_paper.h").read_text()
    doc = header[: header.index("*/")]
    notes = dict(re.findall(r"^ \*   (qd_\w+)\(.*?;  iw \d+, w \d+(.*)$", doc, re.M))
    codes = {"QD_NONFINITE": QD_NONFINITE, "QD_SINGULAR": QD_SINGULAR, "QD_DEGENERATE": QD_DEGENERATE,
             "QD_NO_WORK": QD_NO_WORK}
    lib_path = tmp_path / "libfull.so"
    subprocess.run(["gcc", "-std=c99", "-O0", "-fPIC", "-shared", str(CASADI_GEN / "qd_paper.c"),
                    str(CASADI_GEN / "qd_paper-d.c"), "-o", str(lib_path), "-lm"], check=True, capture_output=True)
    lib = ctypes.CDLL(str(lib_path))
    ptr = ctypes.POINTER(ctypes.c_double)
    checked = 0
    for name, note in notes.items():
        if not hasattr(lib, name):
            continue  # a reduced function: in its own file
        n_in, n_out = getattr(lib, name + "_n_in")(), getattr(lib, name + "_n_out")()
        ins = [np.full(400, 0.1) for _ in range(n_in)]
        ins[0][3:7] = [0.0, 0.0, 0.0, 1.0]
        ins[0][8] = np.nan  # a joint angle of q
        res = [np.zeros(400) for _ in range(n_out)]
        w = np.zeros(4000)
        flag = getattr(lib, name)((ptr * n_in)(*[x.ctypes.data_as(ptr) for x in ins]),
                                  (ptr * n_out)(*[r.ctypes.data_as(ptr) for r in res]), None, w.ctypes.data_as(ptr), 0)
        listed = {codes[c] for c in re.findall(r"QD_[A-Z_]+", note)}
        assert flag in listed | {0} if listed else flag == 0, (name, flag, note)  # 0 where the NaN does not enter
        checked += 1
    # full terms with feet_full and the aliases, GRF solves, did_full + dfd_full(_parts), dgrf(_dir)
    assert checked == 6 + len(ALIASES) + 16 + 3 + 2 * 15
    for name, note in notes.items():
        kind = re.match(r"qd_(\w+?_r)_", name)
        if kind:
            assert ("QD_SINGULAR" in note) == (kind.group(1) in ("fd_r", "dfd_r")), (name, note)


def test_header_signal_names_stand_apart_from_their_text():
    """Every signal line of the header reads 'name text': a name longer than the old fixed column ran into its
    description ('dlambda_wdirectional derivative', 'dqdd_dtaud qdd_r')."""
    from quadruped_dyn.codegen.emit import SIGNAL_DOCS

    header = (CASADI_GEN / "qd_paper.h").read_text()
    block = header[header.index(" * Signals:\n"): header.index(" * Functions (work sizes")]
    lines = [line for line in block.split("\n")[1:] if line.strip(" *")]
    assert lines
    for line in lines:
        name, _, text = line[len(" *   "):].partition(" ")
        assert name in SIGNAL_DOCS and text.strip() == SIGNAL_DOCS[name], line
