/* quadruped_dyn: the definitions the hand-written C shares (hand-written; written once into each generated file that
 * uses them, after the return codes of quadruped_dyn/codegen/c_facts.py). casadi_real is defined before it. */
#ifndef QD_PRELUDE
#define QD_PRELUDE
#include <float.h>

/* Machine epsilon of casadi_real (float, double or long double builds). */
#define QD_EPS (sizeof(casadi_real) == sizeof(float) ? (casadi_real)FLT_EPSILON \
                : sizeof(casadi_real) == sizeof(double) ? (casadi_real)DBL_EPSILON : (casadi_real)LDBL_EPSILON)
/* A pivot this small relative to the largest entry of the matrix eliminated (M_r, or with a swing leg its blocks of M
 * and the folded rest K; M in dfd_full) means the matrix is singular to working precision (condition number beyond
 * ~1 / (QD_SINGULAR_RTOL)): 1e-13 in double, 5e-5 in float. */
#define QD_SINGULAR_RTOL (450 * QD_EPS)

/* QD_INLINE: a template inlined into its callers, each specialised for its constant arguments and every call direct,
 * so a static stack walk (-fcallgraph-info, docs/embedded.md) can bound it. QD_NOINLINE: a function kept out of line,
 * its code once for all its calls (in the instruction cache). */
#if defined(__GNUC__)
#define QD_INLINE static inline __attribute__((always_inline))
#define QD_NOINLINE __attribute__((noinline))
#else
#define QD_INLINE static inline
#define QD_NOINLINE
#endif
#endif
