"""The parametric library: compiled once per family, then 100 variants of go1 and a1 with no further build (its
cache entry untouched, no generation or compile called), each against Pinocchio on its own URDF; ``codegen
--parametric``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from quadruped_dyn import load_robot
from quadruped_dyn.codegen import parametric_library as parametric_library_module
from quadruped_dyn.codegen.parametric_library import parametric_library
from quadruped_dyn.errors import InputError
from quadruped_dyn.model.parameters import N_INERTIAL
from quadruped_dyn.model.state import random_state, rotation
from quadruped_dyn.references.pinocchio import PinocchioReference
from tests.conftest import assert_close
from tests.variants import variant

N_VARIANTS = 100


def _check(library, function, robot, seed: int) -> None:
    ref, p = PinocchioReference(robot), library.parameters(robot)
    s = random_state(robot.lower, robot.upper, np.random.default_rng(seed))
    assert_close(function("M_full")(s.q, p)[0], ref.mass_matrix(s.q), what=f"{robot.name} M_full")
    R = rotation(s.q)
    expected = ref.rnea(s.q, s.v, s.a) - ref.contact_jacobian(s.q, (0, 1, 2, 3)).T @ np.concatenate([R @ f for f in s.f])
    w_res, tau = function("id_full")(s.q, s.v, s.a, s.f.ravel(), p)
    assert_close(np.concatenate([w_res, tau]), expected, what=f"{robot.name} id_full")
    Y = function("regressor_full")(s.q, s.v, s.a, p)[0]
    assert_close(Y @ p[:N_INERTIAL], ref.rnea(s.q, s.v, s.a), what=f"{robot.name} tau = Y pi")


def test_one_build_serves_the_family(tmp_path, monkeypatch):
    go1 = load_robot("go1")
    library = parametric_library(go1)  # built here, or by an earlier run
    built = library.library.path.stat()

    def tripwire(*args: object) -> None:
        raise AssertionError("a variant or a1 built the parametric library again")

    for name in ("parametric_c", "compile_sources"):  # what a build of the cache entry calls
        monkeypatch.setattr(parametric_library_module, name, tripwire)
    function = {name: library.function(name) for name in ("M_full", "id_full", "regressor_full")}.__getitem__
    for seed in range(N_VARIANTS):
        robot = variant(go1, seed, tmp_path)
        assert parametric_library(robot).library.path == library.library.path
        _check(library, function, robot, seed)
    a1 = load_robot("a1")
    assert parametric_library(a1).library.path == library.library.path
    _check(library, function, a1, 0)
    assert library.library.path.stat().st_mtime_ns == built.st_mtime_ns, "the library was rebuilt"
    with pytest.raises(InputError, match="joint .* has the"):
        library.parameters(load_robot("paper"))


def test_codegen_parametric_make_check(tmp_path):
    """``codegen a1 --parametric`` writes the family's files and their check package at a1's p (a1 is not the robot
    that defines the family: p is a genuine input); its ``make check`` passes against Pinocchio in double and float,
    and fails when the p it is given is not a1's."""
    import re
    import subprocess

    from click.testing import CliRunner

    from quadruped_dyn.cli import main
    from quadruped_dyn.codegen.file_names import family_stem
    from quadruped_dyn.model.parameters import PARAMETER_NAMES, family_of

    run = CliRunner().invoke(main, ["codegen", "a1", "--out", str(tmp_path), "--parametric"])
    assert run.exit_code == 0, run.output
    stem = tmp_path / family_stem(family_of(load_robot("a1")).key)
    header = stem.with_suffix(".h").read_text()
    assert f"p[{len(PARAMETER_NAMES) - 3}..{len(PARAMETER_NAMES) - 1}] BR foot" in header
    assert "int qd_p_regressor_full(" in header
    make = subprocess.run(["make", "-C", str(tmp_path), "-j2", "check"], capture_output=True, text=True, check=False)
    assert make.returncode == 0 and make.stdout.count("5 passed, 0 failed") == 2, make.stdout + make.stderr
    reference = Path(f"{stem}-reference.h")  # a1's trunk mass doubled: M_full is off
    text = reference.read_text()
    start = text.index("qd_ref_p[")
    start = text.index("{", start) + 1
    mass = text[start:text.index(",", start)]
    reference.write_text(text[:start] + repr(2 * float(mass)) + text[start + len(mass):])
    subprocess.run(["make", "-C", str(tmp_path), "build/check_qd"], capture_output=True, check=True)  # double only
    wrong = subprocess.run([str(tmp_path / "build" / "check_qd")], capture_output=True, text=True, check=False)
    assert wrong.returncode != 0 and re.search(r"^qd_p_M_full .* FAIL$", wrong.stdout, re.M), wrong.stdout
    bad = CliRunner().invoke(main, ["codegen", "a1", "--out", str(tmp_path), "--parametric", "--check"])
    assert bad.exit_code == 2 and "expected --parametric alone" in bad.output and "Traceback" not in bad.output


def test_docs_example_runs():
    """docs/embedded.md's example, as written (the library built by the test above or an earlier run)."""
    import re

    text = (Path(__file__).resolve().parents[2] / "docs" / "embedded.md").read_text()
    section = text[text.index("## Parametric C"):]
    exec(re.search(r"```python\n(.*?)```", section, flags=re.S).group(1), {})


def test_a_bad_p_is_refused_at_the_call(monkeypatch):
    """A p written by hand (not ``library.parameters``) is checked where it enters the compiled function, once per
    content: a loop over states with one p runs the validator once."""
    from quadruped_dyn.model.parameters import BODIES

    go1 = load_robot("go1")
    library = parametric_library(go1)
    M_full, q = library.function("M_full"), random_state(go1.lower, go1.upper, np.random.default_rng(0)).q
    good = library.parameters(go1)
    for body, change, message in (("FL_KFE", lambda pi: np.concatenate([[-1.0], pi[1:]]), "FL_KFE has mass -1 kg"),
                                  ("FR_HFE", lambda pi: np.array([1.0, 0, 0, 0, 0.01, 0, 0.01, 0, 0, 0.05]),
                                   "triangle inequality")):
        bad = good.copy()
        b = BODIES.index(body)
        bad[10 * b: 10 * b + 10] = change(bad[10 * b: 10 * b + 10])
        for call in (M_full, M_full.raw):
            with pytest.raises(InputError, match=message):
                call(q, bad)
    calls = []
    monkeypatch.setattr(parametric_library_module, "check_parameters", lambda p: calls.append(1))
    for _ in range(3):
        assert np.all(np.isfinite(M_full(q, good.copy())[0]))
    assert len(calls) == 1, "the same p was checked again"
    good[0] += 1.0
    M_full(q, good)
    assert len(calls) == 2, "a changed p was not checked"


def test_batch_shares_p():
    """A batch's states share p (one (178,) array, read once in C): each row equals its own call with that p, to the
    bit; an (N, 178) p -- rows that could differ -- is refused, not read as its first row."""
    go1 = load_robot("go1")
    library = parametric_library(go1)
    M_full, p = library.function("M_full"), library.parameters(go1)
    rng = np.random.default_rng(3)
    qs = np.array([random_state(go1.lower, go1.upper, rng).q for _ in range(3)])
    (rows,), status = M_full.batch(qs, p)
    assert not status.any()
    for q, row in zip(qs, rows):
        assert np.array_equal(row, M_full.raw(q, p)[0]), "a batch row differs from its own call"
    assert np.isfinite(rows).all()
    with pytest.raises(InputError, match=r"shared by every state.*expected one \(178,\) array; got shape \(3, 178\)"):
        M_full.batch(qs, np.tile(p, (3, 1)))
