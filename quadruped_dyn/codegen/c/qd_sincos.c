/* quadruped_dyn: the cosines and sines of the joint angles, taken once per call at a generated function's entry
 * (docs/embedded.md, "The joints' sines and cosines"). In double: the angle reduced by pi/2 in three parts
 * (Cody and Waite; pi/2 to 119 bits, exact products for |x| <= QD_SINCOS_MAX) and FreeBSD's kernels
 * __kernel_sin / __kernel_cos on [-pi/4, pi/4] (msun, k_sin.c and k_cos.c: < 1 ulp), with no branch, so the loop
 * vectorises; within 1 ulp of libm (tests/codegen/test_sincos.py). libm for an angle beyond QD_SINCOS_MAX or not
 * finite, for float and long double, and where the reduction's rounding trick cannot be trusted (-ffast-math,
 * x87's excess precision). */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#define QD_SINCOS_MAX 200.0 /* rad: n = round(x 2/pi) < 2^7, so n pio2_1 and n pio2_2 are exact */
#if defined(__FAST_MATH__) || !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#define QD_SINCOS_LIBM 1
#else
#define QD_SINCOS_LIBM 0
#endif

/* (cos x, sin x) for |x| <= QD_SINCOS_MAX, no branch */
static inline void qd_sincos_kernel(double xi, double* c, double* s) {
  /* n = round(x 2/pi), ties to even, by the rounding of adding 1.5 2^52; its low bits are the quadrant */
  const double big = xi * 6.36619772367581382433e-01 + 0x1.8p52, fn = big - 0x1.8p52;
  uint64_t quadrant;
  memcpy(&quadrant, &big, sizeof quadrant);
  /* y0 + y1 = x - n pi/2 (pio2_1, pio2_2, pio2_2t of msun's e_rem_pio2.c) */
  const double t = xi - fn * 1.57079632673412561417e+00, w0 = fn * 6.07710050630396597660e-11, r = t - w0;
  const double w = fn * 2.02226624879595063154e-21 - ((t - r) - w0);
  const double y0 = r - w, y1 = (r - y0) - w;
  const double z = y0 * y0, zz = z * z, v = z * y0;
  const double ps = 8.33333333332248946124e-03 + z * (-1.98412698298579493134e-04 + z * 2.75573137070700676789e-06)
                    + z * zz * (-2.50507602534068634195e-08 + z * 1.58969099521155010221e-10);
  const double sin_y = y0 - ((z * (0.5 * y1 - v * ps) - y1) - v * -1.66666666666666324348e-01);
  const double pc = z * (4.16666666666666019037e-02 + z * (-1.38888888888741095749e-03 + z * 2.48015872894767294178e-05))
                    + zz * zz * (-2.75573143513906633035e-07 + z * (2.08757232129817482790e-09
                                                                    + z * -1.13596475577881948265e-11));
  const double hz = 0.5 * z, one_hz = 1.0 - hz;
  const double cos_y = one_hz + (((1.0 - one_hz) - hz) + (z * pc - y0 * y1));
  /* quadrant k: (sin, cos) = (sin y, cos y), (cos y, -sin y), (-sin y, -cos y), (-cos y, sin y) */
  uint64_t us, uc;
  memcpy(&us, &sin_y, sizeof us);
  memcpy(&uc, &cos_y, sizeof uc);
  const uint64_t odd = 0 - (quadrant & 1);
  uint64_t a = ((us & ~odd) | (uc & odd)) ^ ((quadrant & 2) << 62);
  uint64_t b = ((uc & ~odd) | (us & odd)) ^ (((quadrant + 1) & 2) << 62);
  double sa, cb;
  memcpy(&sa, &a, sizeof sa);
  memcpy(&cb, &b, sizeof cb);
  *s = sa;
  *c = cb;
}

/* c[i], s[i] = cos x[i], sin x[i] (n angles, rad): the kernel when every angle is within QD_SINCOS_MAX (and the
 * build is double without -ffast-math), else the precision wrappers qd_cos, qd_sin (libm) for all. */
static inline void qd_sincos(int n, const casadi_real* x, casadi_real* c, casadi_real* s) {
  int fast = !QD_SINCOS_LIBM && sizeof(casadi_real) == sizeof(double);
  /* in casadi_real: fabs is qd_fabs once generated (precision_math.template_c), and a float build compares in float */
  for (int i = 0; i < n; ++i) fast &= fabs(x[i]) <= (casadi_real)QD_SINCOS_MAX;  /* false for NaN */
  if (!fast) {
    for (int i = 0; i < n; ++i) {
      c[i] = qd_cos(x[i]);
      s[i] = qd_sin(x[i]);
    }
    return;
  }
  for (int i = 0; i < n; ++i) {
    double ci, si;
    qd_sincos_kernel((double)x[i], &ci, &si);
    c[i] = (casadi_real)ci;
    s[i] = (casadi_real)si;
  }
}
