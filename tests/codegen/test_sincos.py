"""The joints' cosines and sines of the generated C (codegen/c/qd_sincos.c, docs/formulation.md "The joints' sines
and cosines") against mpmath at 40 digits: within SINCOS_MAX_ULP of the correctly rounded value over the joint range,
near the multiples of pi/2 (where the reduction cancels), at the ends of its fast range and beyond (libm), and in
float and long double builds (libm); a NaN or inf angle gives NaN."""

from __future__ import annotations

import ctypes
import math
import subprocess
from pathlib import Path

import mpmath
import numpy as np
import pytest

from quadruped_dyn.codegen.c_alone import ALONE_HEADER, alone_header_c
from quadruped_dyn.codegen.c_facts import TEMPLATES

#: ulps of the correctly rounded value: the final rounding (0.5) plus FreeBSD's k_sin.c / k_cos.c error before it
#: (their polynomials to 2^-58 relative on [-pi/4, pi/4], the sums' roundings ~0.2 ulp) and the reduction's 2^-62
#: (pi/2 to 119 bits, |n| < 2^7). Measured 0.71 over these angles; dropping either kernel's tail y1 or the
#: reduction's third part gives 0.97-1.0 and fails.
SINCOS_MAX_ULP = 0.8
#: rad, qd_sincos.c's QD_SINCOS_MAX: beyond it libm
FAST_MAX = 200.0


def _library(tmp_path: Path, real: str) -> ctypes.CDLL:
    src = tmp_path / "sincos.c"
    # the template alone: its header gives the precision wrappers qd_fabs, ... (codegen/c_alone.py)
    (tmp_path / ALONE_HEADER).write_text(alone_header_c())
    src.write_text(f"#define casadi_real {real}\n#include \"{TEMPLATES / 'qd_sincos.c'}\"\n"
                   + "void qd_sincos_n(int n, const casadi_real* x, casadi_real* c, casadi_real* s)"
                   " { qd_sincos(n, x, c, s); }\n"
                   "void qd_kernel_n(int n, const double* x, double* c, double* s)"
                   " { for (int i = 0; i < n; ++i) qd_sincos_kernel(x[i], c + i, s + i); }\n")
    lib = tmp_path / f"sincos_{real.replace(' ', '_')}.so"
    subprocess.run(["gcc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-Wdouble-promotion", "-O3",
                    "-fPIC", "-shared", "-I", str(tmp_path), str(src), "-o", str(lib), "-lm"],
                   check=True, capture_output=True, text=True)
    return ctypes.CDLL(str(lib))


def _sincos(lib: ctypes.CDLL, x: np.ndarray, entry: str = "qd_sincos_n") -> tuple[np.ndarray, np.ndarray]:
    """(cos x, sin x) by ``entry``: qd_sincos (one call for all of x) or the kernel alone."""
    x = np.ascontiguousarray(x, dtype=float)
    c, s = np.empty_like(x), np.empty_like(x)
    ptr = ctypes.POINTER(ctypes.c_double)
    getattr(lib, entry)(ctypes.c_int(len(x)), x.ctypes.data_as(ptr), c.ctypes.data_as(ptr), s.ctypes.data_as(ptr))
    return c, s


def _ulp_errors(got: np.ndarray, x: np.ndarray, f: str) -> np.ndarray:
    """|got - f(x)| in ulps of the correctly rounded f(x) (mpmath, 40 digits)."""
    mpmath.mp.dps = 40
    exact = [getattr(mpmath, f)(mpmath.mpf(float(v))) for v in x]
    want = np.array([float(e) for e in exact])
    ulp = np.array([math.ulp(w) if w != 0 else math.ulp(0.0) for w in want])
    return np.array([abs(float(mpmath.mpf(float(g)) - e)) for g, e in zip(got, exact)]) / ulp


def _angles() -> np.ndarray:
    rng = np.random.default_rng(7)
    k = rng.integers(-127, 128, 3000)
    return np.concatenate([
        rng.uniform(-2 * np.pi, 2 * np.pi, 6000),                       # joint angles
        rng.uniform(-FAST_MAX, FAST_MAX, 3000),
        k * (np.pi / 2) + rng.uniform(-1e-6, 1e-6, 3000),              # next to multiples of pi/2
        np.array([np.nextafter(v * np.pi / 2, np.inf) for v in k[:300]]),
        rng.uniform(-1e-8, 1e-8, 300), np.array([0.0, -0.0, 5e-324, -1e-300, np.pi / 4, -np.pi / 4]),
        np.array([FAST_MAX, -FAST_MAX]),
    ])


@pytest.fixture(scope="module")
def double_lib(tmp_path_factory) -> ctypes.CDLL:
    return _library(tmp_path_factory.mktemp("sincos"), "double")


def test_kernel_within_one_ulp_of_the_exact_values(double_lib):
    x = _angles()
    c, s = _sincos(double_lib, x, "qd_kernel_n")
    for got, f in ((c, "cos"), (s, "sin")):
        err = _ulp_errors(got, x, f)
        assert np.all(np.isfinite(err)) and err.max() <= SINCOS_MAX_ULP, (f, x[np.argmax(err)], err.max())


def test_joint_angles_take_the_kernel_and_others_libm(double_lib):
    """Twelve joint angles within QD_SINCOS_MAX: qd_sincos gives the kernel's values; one angle beyond it (or not
    finite): libm's for all twelve, to the bit."""
    x = np.random.default_rng(5).uniform(-3, 3, 12)
    assert all(np.array_equal(a, b) for a, b in zip(_sincos(double_lib, x), _sincos(double_lib, x, "qd_kernel_n")))
    libm = ctypes.CDLL("libm.so.6")
    libm.sin.restype = libm.cos.restype = ctypes.c_double
    libm.sin.argtypes = libm.cos.argtypes = [ctypes.c_double]
    for outlier in (np.nextafter(FAST_MAX, np.inf), -1e6, 1e300):
        y = np.append(x[:11], outlier)
        c, s = _sincos(double_lib, y)
        assert np.array_equal(c, [libm.cos(v) for v in y]) and np.array_equal(s, [libm.sin(v) for v in y])


def test_signed_zero_and_tiny_angles(double_lib):
    """sin(+-0) = +-0 and sin x = x, cos x = 1 for |x| < 2^-27, as libm."""
    x = np.array([0.0, -0.0, 1e-20, -1e-20, 5e-324])
    c, s = _sincos(double_lib, x, "qd_kernel_n")
    assert list(np.signbit(s)) == list(np.signbit(x)) and np.array_equal(s, x) and np.all(c == 1.0)


@pytest.mark.parametrize("angle", [np.nan, np.inf, -np.inf])
def test_nonfinite_angle_gives_nan(double_lib, angle):
    c, s = _sincos(double_lib, np.array([0.3, angle, -1.2]))
    assert np.isnan(c[1]) and np.isnan(s[1]) and np.isfinite(c[[0, 2]]).all()


def test_float_build_is_libm(tmp_path):
    """A float build takes the wrappers (sinf, cosf): the same values as libm's, to the bit."""
    lib, libm = _library(tmp_path, "float"), ctypes.CDLL("libm.so.6")
    libm.sinf.restype = libm.cosf.restype = ctypes.c_float
    libm.sinf.argtypes = libm.cosf.argtypes = [ctypes.c_float]
    x = np.random.default_rng(3).uniform(-7, 7, 200).astype(np.float32)
    c, s = np.empty_like(x), np.empty_like(x)
    ptr = ctypes.POINTER(ctypes.c_float)
    lib.qd_sincos_n(ctypes.c_int(len(x)), x.ctypes.data_as(ptr), c.ctypes.data_as(ptr), s.ctypes.data_as(ptr))
    assert np.array_equal(c, [libm.cosf(float(v)) for v in x]) and np.array_equal(s, [libm.sinf(float(v)) for v in x])


def test_long_double_build_compiles(tmp_path):
    assert hasattr(_library(tmp_path, "long double"), "qd_sincos_n")
