/*
 * The experiment's runs in native code (quadruped_dyn/experiment/native_run.py drives it; the
 * Python path of experiment/simulate.py and experiment/rigid_contact.py is the baseline it
 * is tested against).
 *
 * One call integrates one gait phase (fixed stance) with scipy's DOP853 step control and dense
 * output (the coefficients are scipy's arrays, passed in), keeps the reduced state on the
 * stance closure after every step, and records the samples.  Everything an evaluation needs is
 * here or in the generated functions it is given:
 *   - the target and id_r's torques: the per-phase barycentric interpolant of
 *     experiment/torque_table.py (its nodes, weights and values), plus the plan's trunk position;
 *   - the feet: qdx_feet / qdx_feet_rates, generated from dynamics/kinematics.robot_feet into
 *     the same library;
 *   - the trunk pose from the stance feet: the least-squares rigid fit (Horn's quaternion: the
 *     largest eigenvector of a 4x4 symmetric matrix, by Jacobi rotations) for three or four
 *     feet, the closed form of experiment/trunk_pose.py for two;
 *   - fd_r of the robot's generated library, or (rigid contacts) its M_full and nle_full with
 *     the KKT system solved here.
 * Frames and orders are the Python path's: quaternions (x, y, z, w), joints FL, FR, BL, BR x
 * HAA, HFE, KFE, matrices from CasADi column-major, everything else row-major.
 */
#include <math.h>
#include <string.h>

/* The working precision: double, or long double with -DQDX_LONG_DOUBLE (the extended-precision
 * runs of experiment/native_run.py, linked with the robot's generated C built with
 * casadi_real = long double); tgmath.h makes sqrt, sin, fabs, ... follow it. */
#ifdef QDX_LONG_DOUBLE
#include <tgmath.h>
typedef long double qdx_real;
#else
typedef double qdx_real;
#endif

typedef long long qdx_int;
typedef int (*qdx_fn)(const qdx_real **arg, qdx_real **res, qdx_int *iw, qdx_real *w, int mem);

/* What a call of a generated function needs from its caller, sized in Python from every called
 * function's _work entry: arg and res hold at least sz_arg / sz_res pointers (CasADi uses the
 * entries past a function's own inputs and outputs for the calls it makes), iw and w sz_iw / sz_w. */
typedef struct {
    const qdx_real **arg;
    qdx_real **res;
    qdx_int *iw;
    qdx_real *w;
} qdx_frame;

int qdx_feet(const qdx_real **arg, qdx_real **res, qdx_int *iw, qdx_real *w, int mem);
int qdx_feet_rates(const qdx_real **arg, qdx_real **res, qdx_int *iw, qdx_real *w, int mem);

/* Stop codes (0: the phase was integrated). */
#define QDX_FALLEN 1      /* closure or trunk beyond the fallen limits */
#define QDX_SINGULAR 2    /* fd_r's non-zero return, a singular solve, a non-finite value */
#define QDX_STEP_FAILED 3 /* DOP853's step fell below its minimum */

#define NMAX 40
#define NSTAGES 12
#define NEXT 16
#define NPOW 7

typedef struct {
    const qdx_real *A; /* (16, 16) */
    const qdx_real *B; /* (12,) */
    const qdx_real *C; /* (16,) */
    const qdx_real *E3, *E5; /* (13,) */
    const qdx_real *D; /* (4, 16) */
} qdx_dop853;

typedef struct {
    int m1, width; /* nodes; values per node */
    const qdx_real *nodes, *weights, *values; /* (m1,), (m1,), (m1, width) */
} qdx_table;

typedef struct {
    qdx_real scale, kp, kd;
    int roll_applied;
} qdx_law;

typedef struct qdx_problem qdx_problem;
struct qdx_problem {
    int n; /* state size */
    int (*rhs)(qdx_problem *p, qdx_real t, const qdx_real *y, qdx_real *f);
    int (*project)(qdx_problem *p, qdx_real t, qdx_real *y);                 /* NULL: none */
    int (*record)(qdx_problem *p, qdx_real t, const qdx_real *y, int index); /* sample index */
};

/* ---------------------------------------------------------------- small linear algebra */

/* Solve A x = b in place (A n x n row-major, destroyed), LU with partial pivoting. 0 or QDX_SINGULAR. */
static int solve(int n, qdx_real *A, qdx_real *b) {
    int i, j, k;
    for (k = 0; k < n; ++k) {
        int piv = k;
        qdx_real big = fabs(A[k * n + k]);
        for (i = k + 1; i < n; ++i)
            if (fabs(A[i * n + k]) > big) {
                big = fabs(A[i * n + k]);
                piv = i;
            }
        if (!(big > 0.0)) return QDX_SINGULAR;
        if (piv != k) {
            qdx_real t;
            for (j = 0; j < n; ++j) {
                t = A[k * n + j];
                A[k * n + j] = A[piv * n + j];
                A[piv * n + j] = t;
            }
            t = b[k];
            b[k] = b[piv];
            b[piv] = t;
        }
        for (i = k + 1; i < n; ++i) {
            qdx_real l = A[i * n + k] / A[k * n + k];
            if (l == 0.0) continue;
            for (j = k + 1; j < n; ++j) A[i * n + j] -= l * A[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (i = n - 1; i >= 0; --i) {
        qdx_real s = b[i];
        for (j = i + 1; j < n; ++j) s -= A[i * n + j] * b[j];
        b[i] = s / A[i * n + i];
    }
    for (i = 0; i < n; ++i)
        if (!isfinite(b[i])) return QDX_SINGULAR;
    return 0;
}

/* Least squares min |A x - b| (A m x 6 row-major, m <= 13, full column rank), Householder QR. */
static int lstsq6(int m, qdx_real *A, qdx_real *b, qdx_real *x) {
    int i, j, k;
    for (k = 0; k < 6; ++k) {
        qdx_real norm = 0.0, alpha, vnorm2, s;
        for (i = k; i < m; ++i) norm += A[i * 6 + k] * A[i * 6 + k];
        norm = sqrt(norm);
        if (!(norm > 0.0)) return QDX_SINGULAR;
        alpha = A[k * 6 + k] > 0 ? -norm : norm;
        A[k * 6 + k] -= alpha; /* v = column k below the diagonal, v_k = a_kk - alpha */
        vnorm2 = 0.0;
        for (i = k; i < m; ++i) vnorm2 += A[i * 6 + k] * A[i * 6 + k];
        for (j = k + 1; j < 6; ++j) {
            s = 0.0;
            for (i = k; i < m; ++i) s += A[i * 6 + k] * A[i * 6 + j];
            s = 2.0 * s / vnorm2;
            for (i = k; i < m; ++i) A[i * 6 + j] -= s * A[i * 6 + k];
        }
        s = 0.0;
        for (i = k; i < m; ++i) s += A[i * 6 + k] * b[i];
        s = 2.0 * s / vnorm2;
        for (i = k; i < m; ++i) b[i] -= s * A[i * 6 + k];
        A[k * 6 + k] = alpha; /* R's diagonal; R's upper part is in place */
    }
    for (k = 5; k >= 0; --k) {
        qdx_real s = b[k];
        for (j = k + 1; j < 6; ++j) s -= A[k * 6 + j] * x[j];
        x[k] = s / A[k * 6 + k];
        if (!isfinite(x[k])) return QDX_SINGULAR;
    }
    return 0;
}

/* The eigenvector (4,) of the largest eigenvalue of a symmetric 4x4 matrix (cyclic Jacobi). */
static void top_eigenvector4(qdx_real N[4][4], qdx_real v[4]) {
    qdx_real V[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    int sweep, p, q, r, best = 0;
    for (sweep = 0; sweep < 60; ++sweep) {
        qdx_real off = 0.0, diag = 0.0;
        for (p = 0; p < 4; ++p) {
            diag += N[p][p] * N[p][p];
            for (q = p + 1; q < 4; ++q) off += N[p][q] * N[p][q];
        }
        if (off == 0.0 || off < 1e-40 * diag) break;
        for (p = 0; p < 3; ++p)
            for (q = p + 1; q < 4; ++q) {
                qdx_real apq = N[p][q], theta, t, c, s;
                if (apq == 0.0) continue;
                theta = (N[q][q] - N[p][p]) / (2.0 * apq);
                t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                c = 1.0 / sqrt(t * t + 1.0);
                s = t * c;
                for (r = 0; r < 4; ++r) { /* N <- N J (columns p, q) */
                    qdx_real rp = N[r][p], rq = N[r][q];
                    N[r][p] = c * rp - s * rq;
                    N[r][q] = s * rp + c * rq;
                }
                for (r = 0; r < 4; ++r) { /* N <- J^T N (rows p, q) */
                    qdx_real pr = N[p][r], qr = N[q][r];
                    N[p][r] = c * pr - s * qr;
                    N[q][r] = s * pr + c * qr;
                }
                N[p][q] = N[q][p] = 0.0;
                for (r = 0; r < 4; ++r) {
                    qdx_real rp = V[r][p], rq = V[r][q];
                    V[r][p] = c * rp - s * rq;
                    V[r][q] = s * rp + c * rq;
                }
            }
    }
    for (p = 1; p < 4; ++p)
        if (N[p][p] > N[best][best]) best = p;
    for (r = 0; r < 4; ++r) v[r] = V[r][best];
}

/* ---------------------------------------------------------------- rotations */

/* R (row-major) of a unit quaternion (x, y, z, w). */
static void quat_to_R(const qdx_real *q, qdx_real *R) {
    qdx_real x = q[0], y = q[1], z = q[2], w = q[3];
    R[0] = 1 - 2 * (y * y + z * z); R[1] = 2 * (x * y - z * w);     R[2] = 2 * (x * z + y * w);
    R[3] = 2 * (x * y + z * w);     R[4] = 1 - 2 * (x * x + z * z); R[5] = 2 * (y * z - x * w);
    R[6] = 2 * (x * z - y * w);     R[7] = 2 * (y * z + x * w);     R[8] = 1 - 2 * (x * x + y * y);
}

/* Quaternion (x, y, z, w) of a rotation matrix (Eigen's algorithm, as pin.Quaternion(R)). */
static void R_to_quat(const qdx_real *R, qdx_real *q) {
    qdx_real trace = R[0] + R[4] + R[8], t;
    if (trace > 0) {
        t = sqrt(trace + 1.0);
        q[3] = 0.5 * t;
        t = 0.5 / t;
        q[0] = (R[7] - R[5]) * t;
        q[1] = (R[2] - R[6]) * t;
        q[2] = (R[3] - R[1]) * t;
    } else {
        int i = 0, j, k;
        if (R[4] > R[0]) i = 1;
        if (R[8] > R[i * 3 + i]) i = 2;
        j = (i + 1) % 3;
        k = (j + 1) % 3;
        t = sqrt(R[i * 3 + i] - R[j * 3 + j] - R[k * 3 + k] + 1.0);
        q[i] = 0.5 * t;
        t = 0.5 / t;
        q[3] = (R[k * 3 + j] - R[j * 3 + k]) * t;
        q[j] = (R[j * 3 + i] + R[i * 3 + j]) * t;
        q[k] = (R[k * 3 + i] + R[i * 3 + k]) * t;
    }
}

/* Roll and pitch of R = Rz(yaw) Ry(pitch) Rx(roll) (Pinocchio's matrixToRpy away from pitch +-90 deg). */
static void roll_pitch(const qdx_real *R, qdx_real *roll, qdx_real *pitch) {
    qdx_real m = sqrt(R[7] * R[7] + R[8] * R[8]);
    *pitch = atan2(-R[6], m);
    *roll = atan2(R[7], R[8]);
}

static void rpy_to_R(qdx_real r, qdx_real p, qdx_real y, qdx_real *R) {
    qdx_real cr = cos(r), sr = sin(r), cp = cos(p), sp = sin(p), cy = cos(y), sy = sin(y);
    R[0] = cy * cp; R[1] = cy * sp * sr - sy * cr; R[2] = cy * sp * cr + sy * sr;
    R[3] = sy * cp; R[4] = sy * sp * sr + cy * cr; R[5] = sy * sp * cr - cy * sr;
    R[6] = -sp;     R[7] = cp * sr;                R[8] = cp * cr;
}

/* ---------------------------------------------------------------- trunk pose from the feet */

/* experiment/trunk_pose.pose_from_feet: R (row-major), p, the closure (m) for k stance feet
 * rb (k, 3) on footholds P (k, 3); roll used for k = 2 with the pitch nearer *hint. */
static int pose_from_feet(int k, const qdx_real *rb, const qdx_real *P, qdx_real roll, qdx_real hint, qdx_real *R,
                          qdx_real *p, qdx_real *closure) {
    qdx_real rm[3] = {0, 0, 0}, Pm[3] = {0, 0, 0};
    int i, a, b;
    for (i = 0; i < k; ++i)
        for (a = 0; a < 3; ++a) {
            rm[a] += rb[3 * i + a];
            Pm[a] += P[3 * i + a];
        }
    for (a = 0; a < 3; ++a) {
        rm[a] /= k;
        Pm[a] /= k;
    }
    if (k >= 3) {
        qdx_real S[3][3] = {{0}}, N[4][4], v[4], quat[4], nv;
        for (i = 0; i < k; ++i)
            for (a = 0; a < 3; ++a)
                for (b = 0; b < 3; ++b) S[a][b] += (rb[3 * i + a] - rm[a]) * (P[3 * i + b] - Pm[b]);
        N[0][0] = S[0][0] + S[1][1] + S[2][2];
        N[0][1] = N[1][0] = S[1][2] - S[2][1];
        N[0][2] = N[2][0] = S[2][0] - S[0][2];
        N[0][3] = N[3][0] = S[0][1] - S[1][0];
        N[1][1] = S[0][0] - S[1][1] - S[2][2];
        N[1][2] = N[2][1] = S[0][1] + S[1][0];
        N[1][3] = N[3][1] = S[2][0] + S[0][2];
        N[2][2] = -S[0][0] + S[1][1] - S[2][2];
        N[2][3] = N[3][2] = S[1][2] + S[2][1];
        N[3][3] = -S[0][0] - S[1][1] + S[2][2];
        top_eigenvector4(N, v); /* (w, x, y, z) */
        nv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        quat[0] = v[1] / nv;
        quat[1] = v[2] / nv;
        quat[2] = v[3] / nv;
        quat[3] = v[0] / nv;
        quat_to_R(quat, R);
    } else if (k == 2) {
        qdx_real c = cos(roll), s = sin(roll), d0[3], u[3], d[3], nd, nu, rho, beta, base, th[2], w0, w1, psi, theta;
        int j;
        for (a = 0; a < 3; ++a) d0[a] = rb[a] - rb[3 + a];
        u[0] = d0[0];
        u[1] = c * d0[1] - s * d0[2];
        u[2] = s * d0[1] + c * d0[2];
        nd = sqrt((P[0] - P[3]) * (P[0] - P[3]) + (P[1] - P[4]) * (P[1] - P[4]) + (P[2] - P[5]) * (P[2] - P[5]));
        nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        for (a = 0; a < 3; ++a) d[a] = (P[a] - P[3 + a]) / nd * nu;
        rho = hypot(u[0], u[2]);
        beta = atan2(u[0], u[2]);
        base = d[2] / rho;
        base = acos(base < -1.0 ? -1.0 : (base > 1.0 ? 1.0 : base));
        th[0] = base - beta;
        th[1] = -base - beta;
        theta = th[0];
        for (j = 1; j < 2; ++j)
            if (fabs(atan2(sin(th[j] - hint), cos(th[j] - hint))) < fabs(atan2(sin(theta - hint), cos(theta - hint))))
                theta = th[j];
        w0 = u[0] * cos(theta) + u[2] * sin(theta);
        w1 = u[1];
        psi = atan2(d[1], d[0]) - atan2(w1, w0);
        rpy_to_R(roll, theta, psi, R);
    } else {
        return QDX_SINGULAR;
    }
    for (a = 0; a < 3; ++a) p[a] = Pm[a] - (R[3 * a] * rm[0] + R[3 * a + 1] * rm[1] + R[3 * a + 2] * rm[2]);
    *closure = 0.0;
    for (i = 0; i < k; ++i) {
        qdx_real e2 = 0.0;
        for (a = 0; a < 3; ++a) {
            qdx_real e = R[3 * a] * rb[3 * i] + R[3 * a + 1] * rb[3 * i + 1] + R[3 * a + 2] * rb[3 * i + 2] + p[a] - P[3 * i + a];
            e2 += e * e;
        }
        if (sqrt(e2) > *closure) *closure = sqrt(e2);
    }
    if (!isfinite(*closure)) return QDX_SINGULAR;
    return 0;
}

/* The pose fit on its own (tests compare it with experiment/trunk_pose.pose_from_feet). */
int qdx_pose(int k, const qdx_real *rb, const qdx_real *P, qdx_real roll, qdx_real hint, qdx_real *R, qdx_real *p,
             qdx_real *closure) {
    return pose_from_feet(k, rb, P, roll, hint, R, p, closure);
}

/* ---------------------------------------------------------------- the target table */

/* Barycentric interpolant at t (experiment/torque_table._Phase): out (width,). */
static void table_at(const qdx_table *tb, qdx_real t, qdx_real *out) {
    int j, c;
    qdx_real den = 0.0;
    for (j = 0; j < tb->m1; ++j)
        if (t == tb->nodes[j]) {
            memcpy(out, tb->values + (size_t)j * tb->width, sizeof(qdx_real) * tb->width);
            return;
        }
    for (c = 0; c < tb->width; ++c) out[c] = 0.0;
    for (j = 0; j < tb->m1; ++j) {
        qdx_real w = tb->weights[j] / (t - tb->nodes[j]);
        const qdx_real *row = tb->values + (size_t)j * tb->width;
        den += w;
        for (c = 0; c < tb->width; ++c) out[c] += w * row[c];
    }
    for (c = 0; c < tb->width; ++c) out[c] /= den;
}

/* ---------------------------------------------------------------- DOP853 (scipy's) */

static qdx_real rms(int n, const qdx_real *x) {
    qdx_real s = 0.0;
    int i;
    for (i = 0; i < n; ++i) s += x[i] * x[i];
    return sqrt(s) / sqrt((qdx_real)n);
}

/* One phase [t0, t1] of scipy.integrate.DOP853 (rtol, atol), with the state projected after
 * every accepted step (project: y and the stored derivative replaced) and the samples
 * (ascending) recorded from the dense output. *y in: the start, out: the end. */
static int dop853_phase(qdx_problem *P, const qdx_dop853 *co, qdx_real t0, qdx_real t1, qdx_real rtol, qdx_real atol,
                        qdx_real *y, const qdx_real *samples, int n_samples) {
    const int n = P->n;
    qdx_real K[NEXT][NMAX], f[NMAX], ynew[NMAX], yold[NMAX], ytmp[NMAX], scale[NMAX], F[NPOW][NMAX];
    qdx_real t = t0, h_abs, h = 0.0, told = t0, d0, d1, d2, h0, h1;
    const qdx_real err_exp = -1.0 / 8.0, SAFETY = 0.9, MIN_FACTOR = 0.2, MAX_FACTOR = 10.0;
    int i, j, s, code, next = 0, finished = 0;

    if ((code = P->rhs(P, t, y, f))) return code;
    /* select_initial_step (scipy/integrate/_ivp/common.py), order 7 */
    for (i = 0; i < n; ++i) scale[i] = atol + fabs(y[i]) * rtol;
    for (i = 0; i < n; ++i) ytmp[i] = y[i] / scale[i];
    d0 = rms(n, ytmp);
    for (i = 0; i < n; ++i) ytmp[i] = f[i] / scale[i];
    d1 = rms(n, ytmp);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > t1 - t0) h0 = t1 - t0;
    for (i = 0; i < n; ++i) ynew[i] = y[i] + h0 * f[i];
    if ((code = P->rhs(P, t0 + h0, ynew, K[0]))) return code;
    for (i = 0; i < n; ++i) ytmp[i] = (K[0][i] - f[i]) / scale[i];
    d2 = rms(n, ytmp) / h0;
    h1 = (d1 <= 1e-15 && d2 <= 1e-15) ? (1e-6 > h0 * 1e-3 ? 1e-6 : h0 * 1e-3) : pow(0.01 / (d1 > d2 ? d1 : d2), 1.0 / 8.0);
    h_abs = 100 * h0;
    if (h1 < h_abs) h_abs = h1;
    if (t1 - t0 < h_abs) h_abs = t1 - t0;

    while (next < n_samples && samples[next] <= t0 + 1e-12) {
        if ((code = P->record(P, samples[next], y, next))) return code;
        ++next;
    }
    if (t == t1) finished = 1;
    while (!finished) {
        qdx_real min_step = 10 * fabs(nextafter(t, INFINITY) - t), t_new = t, e5, e3;
        int accepted = 0, rejected = 0;
        if (h_abs < min_step) h_abs = min_step;
        while (!accepted) {
            qdx_real error_norm, factor;
            if (h_abs < min_step) return QDX_STEP_FAILED;
            h = h_abs;
            t_new = t + h;
            if (t_new - t1 > 0) t_new = t1;
            h = t_new - t;
            h_abs = fabs(h);
            /* rk_step */
            memcpy(K[0], f, sizeof(qdx_real) * n);
            for (s = 1; s < NSTAGES; ++s) {
                for (i = 0; i < n; ++i) {
                    qdx_real dy = 0.0;
                    for (j = 0; j < s; ++j) dy += K[j][i] * co->A[s * NEXT + j];
                    ytmp[i] = y[i] + dy * h;
                }
                if ((code = P->rhs(P, t + co->C[s] * h, ytmp, K[s]))) return code;
            }
            for (i = 0; i < n; ++i) {
                qdx_real dy = 0.0;
                for (j = 0; j < NSTAGES; ++j) dy += K[j][i] * co->B[j];
                ynew[i] = y[i] + h * dy;
            }
            if ((code = P->rhs(P, t + h, ynew, K[NSTAGES]))) return code;
            /* _estimate_error_norm */
            e5 = e3 = 0.0;
            for (i = 0; i < n; ++i) {
                qdx_real a5 = 0.0, a3 = 0.0, sc = atol + (fabs(y[i]) > fabs(ynew[i]) ? fabs(y[i]) : fabs(ynew[i])) * rtol;
                for (j = 0; j <= NSTAGES; ++j) {
                    a5 += K[j][i] * co->E5[j];
                    a3 += K[j][i] * co->E3[j];
                }
                a5 /= sc;
                a3 /= sc;
                e5 += a5 * a5;
                e3 += a3 * a3;
            }
            if (e5 == 0 && e3 == 0)
                error_norm = 0.0;
            else
                error_norm = fabs(h) * e5 / sqrt((e5 + 0.01 * e3) * n);
            if (error_norm < 1) {
                factor = error_norm == 0 ? MAX_FACTOR : SAFETY * pow(error_norm, err_exp);
                if (factor > MAX_FACTOR) factor = MAX_FACTOR;
                if (rejected && factor > 1) factor = 1;
                h_abs *= factor;
                accepted = 1;
            } else {
                factor = SAFETY * pow(error_norm, err_exp);
                h_abs *= factor > MIN_FACTOR ? factor : MIN_FACTOR;
                rejected = 1;
            }
        }
        told = t;
        memcpy(yold, y, sizeof(qdx_real) * n);
        t = t_new;
        memcpy(y, ynew, sizeof(qdx_real) * n);
        if (t - t1 >= 0) finished = 1;
        if (P->project) {
            if ((code = P->project(P, t, y))) return code;
            if ((code = P->rhs(P, t, y, f))) return code;
        } else {
            memcpy(f, K[NSTAGES], sizeof(qdx_real) * n);
        }
        if (next < n_samples && samples[next] <= t + 1e-12) {
            int have_dense = 0;
            while (next < n_samples && samples[next] <= t + 1e-12) {
                qdx_real ts = samples[next];
                if (fabs(ts - t) < 1e-12) {
                    if ((code = P->record(P, ts, y, next))) return code;
                } else {
                    qdx_real x = (ts - told) / h;
                    if (!have_dense) { /* Dop853's _dense_output_impl: three more stages */
                        for (s = NSTAGES + 1; s < NEXT; ++s) {
                            for (i = 0; i < n; ++i) {
                                qdx_real dy = 0.0;
                                for (j = 0; j < s; ++j) dy += K[j][i] * co->A[s * NEXT + j];
                                ytmp[i] = yold[i] + dy * h;
                            }
                            if ((code = P->rhs(P, told + co->C[s] * h, ytmp, K[s]))) return code;
                        }
                        for (i = 0; i < n; ++i) {
                            F[0][i] = y[i] - yold[i];
                            F[1][i] = h * K[0][i] - F[0][i];
                            F[2][i] = 2 * F[0][i] - h * (f[i] + K[0][i]);
                        }
                        for (s = 0; s < NPOW - 3; ++s)
                            for (i = 0; i < n; ++i) {
                                qdx_real dk = 0.0;
                                for (j = 0; j < NEXT; ++j) dk += co->D[s * NEXT + j] * K[j][i];
                                F[3 + s][i] = h * dk;
                            }
                        have_dense = 1;
                    }
                    for (i = 0; i < n; ++i) { /* Dop853DenseOutput._call_impl */
                        qdx_real v = 0.0;
                        for (s = 0; s < NPOW; ++s) {
                            v += F[NPOW - 1 - s][i];
                            v *= (s % 2 == 0) ? x : 1 - x;
                        }
                        ytmp[i] = v + yold[i];
                    }
                    if ((code = P->record(P, ts, ytmp, next))) return code;
                }
                ++next;
            }
        }
    }
    return 0;
}

/* ---------------------------------------------------------------- the reduced model's runs */

typedef struct {
    qdx_table table;         /* width 4 n + 3: q_r, qd_r, qdd_r, id_r (n each), the plan's trunk position */
    qdx_law law;
    qdx_fn fd_r;             /* the stance's generated fd_r: (q_r, qd_r, tau_ext, quat) -> qdd_r */
    qdx_frame frame;         /* for fd_r */
    int n, k, project;       /* coordinates (12, 13); stance feet; project onto the closure */
    int legs[4];             /* the stance legs (0..3) */
    qdx_real holds[12];        /* their footholds (k, 3), world, m */
    qdx_real fallen_closure, fallen_trunk; /* m */
    qdx_real pitch;            /* in/out: the pitch hint of the two-feet pose */
    long long evaluations;   /* in/out */
    qdx_real *out_t, *out_y, *out_qdd, *out_closure; /* (samples,), (samples, 2n), (samples, n), (samples,) */
    int recorded;            /* out: samples recorded */
} qdx_reduced;

typedef struct {
    qdx_problem base;
    qdx_reduced *c;
} reduced_problem;

static int feet_of(const qdx_real *q, qdx_real *r, qdx_real *J) {
    const qdx_real *arg[1];
    qdx_real *res[2];
    arg[0] = q;
    res[0] = r;
    res[1] = J;
    return qdx_feet(arg, res, 0, 0, 0);
}

/* qdd_r at (t, y) and the closure (the Python path's qdd_of). */
static int reduced_qdd(qdx_reduced *c, qdx_real t, const qdx_real *y, qdx_real *qdd, qdx_real *closure) {
    const int n = c->n, k = c->k;
    const qdx_real *q = y, *qd = y + n;
    qdx_real v[4 * 13 + 3], tau[13], r[12], J[36], rb[12], R[9], p[3], quat[4], roll, pitch, dx, dy, dz;
    const qdx_real *ref_q, *ref_qd, *tau_ik, *trunk;
    const qdx_real **arg = c->frame.arg;
    qdx_real **res = c->frame.res;
    int i, a;
    c->evaluations++;
    table_at(&c->table, t, v);
    ref_q = v;
    ref_qd = v + n;
    tau_ik = v + 3 * n;
    trunk = v + 4 * n;
    for (i = 0; i < 12; ++i)
        tau[i] = c->law.scale * tau_ik[i] + c->law.kp * (ref_q[i] - q[i]) + c->law.kd * (ref_qd[i] - qd[i]);
    if (n == 13) tau[12] = (c->law.roll_applied && k == 2) ? tau_ik[12] : 0.0;
    if (feet_of(q, r, J)) return QDX_SINGULAR;
    for (i = 0; i < k; ++i)
        for (a = 0; a < 3; ++a) rb[3 * i + a] = r[3 * c->legs[i] + a];
    if (pose_from_feet(k, rb, c->holds, k == 2 ? q[12] : 0.0, c->pitch, R, p, closure)) return QDX_SINGULAR;
    roll_pitch(R, &roll, &pitch);
    c->pitch = pitch;
    dx = p[0] - trunk[0];
    dy = p[1] - trunk[1];
    dz = p[2] - trunk[2];
    if (*closure > c->fallen_closure || sqrt(dx * dx + dy * dy + dz * dz) > c->fallen_trunk) return QDX_FALLEN;
    R_to_quat(R, quat);
    arg[0] = q;
    arg[1] = qd;
    arg[2] = tau;
    arg[3] = quat;
    res[0] = qdd;
    if (c->fd_r(arg, res, c->frame.iw, c->frame.w, 0)) return QDX_SINGULAR;
    return 0;
}

static int reduced_rhs(qdx_problem *P, qdx_real t, const qdx_real *y, qdx_real *f) {
    qdx_reduced *c = ((reduced_problem *)P)->c;
    qdx_real closure;
    memcpy(f, y + c->n, sizeof(qdx_real) * c->n);
    return reduced_qdd(c, t, y, f + c->n, &closure);
}

static int reduced_record(qdx_problem *P, qdx_real t, const qdx_real *y, int index) {
    qdx_reduced *c = ((reduced_problem *)P)->c;
    const int n = c->n;
    qdx_real qdd[13], closure;
    int code = reduced_qdd(c, t, y, qdd, &closure);
    if (code) return code;
    c->out_t[index] = t;
    memcpy(c->out_y + (size_t)index * 2 * n, y, sizeof(qdx_real) * 2 * n);
    memcpy(c->out_qdd + (size_t)index * n, qdd, sizeof(qdx_real) * n);
    c->out_closure[index] = closure;
    c->recorded = index + 1;
    return 0;
}

/* experiment/simulate.project_on_stance: two Newton steps of each stance leg's IK onto the
 * footholds for the fitted pose, then the stance legs' rates from the least-squares trunk twist. */
static int reduced_project(qdx_problem *P, qdx_real t, qdx_real *y) {
    qdx_reduced *c = ((reduced_problem *)P)->c;
    const int n = c->n, k = c->k;
    qdx_real *q = y, *qd = y + n;
    qdx_real r[12], J[36], rb[12], R[9], p[3], closure, A[13 * 6], b[13], xi[6];
    int it, i, a, m = 0;
    (void)t;
    for (it = 0; it < 2; ++it) {
        if (feet_of(q, r, J)) return QDX_SINGULAR;
        for (i = 0; i < k; ++i)
            for (a = 0; a < 3; ++a) rb[3 * i + a] = r[3 * c->legs[i] + a];
        if (pose_from_feet(k, rb, c->holds, k == 2 ? q[12] : 0.0, c->pitch, R, p, &closure)) return QDX_SINGULAR;
        for (i = 0; i < k; ++i) {
            int leg = c->legs[i], col, row;
            qdx_real Jl[9], e[3], d[3];
            for (a = 0; a < 3; ++a) d[a] = c->holds[3 * i + a] - p[a];
            for (a = 0; a < 3; ++a) e[a] = R[a] * d[0] + R[3 + a] * d[1] + R[6 + a] * d[2] - rb[3 * i + a];
            for (row = 0; row < 3; ++row)
                for (col = 0; col < 3; ++col) Jl[row * 3 + col] = J[3 * (3 * leg + col) + row];
            if (solve(3, Jl, e)) return QDX_SINGULAR;
            for (a = 0; a < 3; ++a) q[3 * leg + a] += e[a];
        }
    }
    if (feet_of(q, r, J)) return QDX_SINGULAR;
    for (i = 0; i < k; ++i) {
        int leg = c->legs[i], row, col;
        const qdx_real *ri = r + 3 * leg;
        qdx_real sk[9] = {0, -ri[2], ri[1], ri[2], 0, -ri[0], -ri[1], ri[0], 0};
        for (row = 0; row < 3; ++row) {
            qdx_real s = 0.0;
            for (col = 0; col < 6; ++col) A[m * 6 + col] = col < 3 ? (col == row ? 1.0 : 0.0) : -sk[row * 3 + col - 3];
            for (col = 0; col < 3; ++col) s += J[3 * (3 * leg + col) + row] * qd[3 * leg + col];
            b[m] = -s;
            ++m;
        }
    }
    if (k == 2) {
        qdx_real roll, pitch;
        roll_pitch(R, &roll, &pitch);
        A[m * 6 + 0] = A[m * 6 + 1] = A[m * 6 + 2] = 0.0;
        A[m * 6 + 3] = 1.0;
        A[m * 6 + 4] = sin(roll) * tan(pitch);
        A[m * 6 + 5] = cos(roll) * tan(pitch);
        b[m] = qd[12];
        ++m;
    }
    if (lstsq6(m, A, b, xi)) return QDX_SINGULAR;
    for (i = 0; i < k; ++i) {
        int leg = c->legs[i], row, col;
        const qdx_real *ri = r + 3 * leg;
        qdx_real Jl[9], v[3];
        v[0] = -(xi[0] + (xi[4] * ri[2] - xi[5] * ri[1]));
        v[1] = -(xi[1] + (xi[5] * ri[0] - xi[3] * ri[2]));
        v[2] = -(xi[2] + (xi[3] * ri[1] - xi[4] * ri[0]));
        for (row = 0; row < 3; ++row)
            for (col = 0; col < 3; ++col) Jl[row * 3 + col] = J[3 * (3 * leg + col) + row];
        if (solve(3, Jl, v)) return QDX_SINGULAR;
        for (a = 0; a < 3; ++a) qd[3 * leg + a] = v[a];
    }
    return 0;
}

/* One phase of a reduced run; 0 or a stop code (c->recorded says how many samples were kept). */
int qdx_reduced_phase(const qdx_dop853 *co, qdx_reduced *c, qdx_real t0, qdx_real t1, qdx_real rtol, qdx_real *y,
                      const qdx_real *samples, int n_samples) {
    reduced_problem P;
    P.base.n = 2 * c->n;
    P.base.rhs = reduced_rhs;
    P.base.project = c->project ? reduced_project : 0;
    P.base.record = reduced_record;
    P.c = c;
    c->recorded = 0;
    return dop853_phase(&P.base, co, t0, t1, rtol, rtol, y, samples, n_samples);
}

/* ---------------------------------------------------------------- rigid contacts */

typedef struct {
    qdx_table table;     /* as for the reduced runs (the first 12 joints used) */
    qdx_law law;
    qdx_fn M_full, nle_full; /* the robot's generated full-coordinate terms */
    const qdx_int *M_rows, *M_cols; /* M_full's nonzeros (row, column) */
    int M_nnz, M_mirror; /* mirror: only one triangle is stored */
    qdx_frame frame;     /* for M_full and nle_full */
    int k;
    int legs[4];
    const qdx_real *trunk; /* the trunk position to compare with at every sample (samples, 3) */
    qdx_real fallen_trunk;
    long long evaluations;
    qdx_real *out_t, *out_y, *out_a, *out_off; /* (samples,), (samples, 37), (samples, 18), (samples,) */
    int recorded;
} qdx_rigid;

typedef struct {
    qdx_problem base;
    qdx_rigid *c;
} rigid_problem;

/* a = vdot (18,) of the KKT system [M Jc^T; Jc 0] [a; -f] = [(0, tau) - nle; -drift], with the
 * stance feet's velocity Jacobian and drift in the trunk frame. */
static int rigid_accel(qdx_rigid *c, qdx_real t, const qdx_real *y, qdx_real *acc) {
    const qdx_real *q = y, *v = y + 19;
    qdx_real vals[4 * 13 + 3], Mnz[18 * 18], h[18], K[30 * 30], rhs[30], r[12], J[36], Jdqd[12], tau[12];
    const qdx_real **arg = c->frame.arg;
    qdx_real **res = c->frame.res;
    const int n = (c->table.width - 3) / 4, m = 18 + 3 * c->k; /* n: the gait's reduced coordinates */
    int i, j, a;
    c->evaluations++;
    table_at(&c->table, t, vals);
    for (i = 0; i < 12; ++i) /* TorqueLaw.joints */
        tau[i] = c->law.scale * vals[3 * n + i] + c->law.kp * (vals[i] - q[7 + i]) + c->law.kd * (vals[n + i] - v[6 + i]);
    arg[0] = q;
    res[0] = Mnz;
    if (c->M_full(arg, res, c->frame.iw, c->frame.w, 0)) return QDX_SINGULAR;
    arg[1] = v;
    res[0] = h;
    if (c->nle_full(arg, res, c->frame.iw, c->frame.w, 0)) return QDX_SINGULAR;
    memset(K, 0, sizeof(qdx_real) * m * m);
    for (i = 0; i < c->M_nnz; ++i) {
        K[c->M_rows[i] * m + c->M_cols[i]] = Mnz[i];
        if (c->M_mirror) K[c->M_cols[i] * m + c->M_rows[i]] = Mnz[i];
    }
    for (i = 0; i < 18; ++i) rhs[i] = (i < 6 ? 0.0 : tau[i - 6]) - h[i];
    arg[0] = q + 7;
    arg[1] = v + 6;
    res[0] = r;
    res[1] = J;
    res[2] = Jdqd;
    if (qdx_feet_rates(arg, res, 0, 0, 0)) return QDX_SINGULAR;
    for (i = 0; i < c->k; ++i) {
        int leg = c->legs[i];
        const qdx_real *ri = r + 3 * leg, *w = v + 3, *qdl = v + 6 + 3 * leg;
        qdx_real Jq[3], u[3];
        for (a = 0; a < 3; ++a) Jq[a] = J[3 * (3 * leg) + a] * qdl[0] + J[3 * (3 * leg + 1) + a] * qdl[1] +
                                        J[3 * (3 * leg + 2) + a] * qdl[2];
        /* u = v_b + omega x r + J qd: the foot's velocity in the trunk frame */
        u[0] = v[0] + (w[1] * ri[2] - w[2] * ri[1]) + Jq[0];
        u[1] = v[1] + (w[2] * ri[0] - w[0] * ri[2]) + Jq[1];
        u[2] = v[2] + (w[0] * ri[1] - w[1] * ri[0]) + Jq[2];
        for (a = 0; a < 3; ++a) {
            int row = 18 + 3 * i + a;
            qdx_real sk[3];
            /* rows [I, -skew(r), J] */
            K[row * m + a] = 1.0;
            sk[0] = a == 0 ? 0.0 : (a == 1 ? ri[2] : -ri[1]);
            sk[1] = a == 0 ? -ri[2] : (a == 1 ? 0.0 : ri[0]);
            sk[2] = a == 0 ? ri[1] : (a == 1 ? -ri[0] : 0.0);
            for (j = 0; j < 3; ++j) K[row * m + 3 + j] = -sk[j];
            for (j = 0; j < 3; ++j) K[row * m + 6 + 3 * leg + j] = J[3 * (3 * leg + j) + a];
            for (j = 0; j < 18; ++j) K[j * m + row] = K[row * m + j];
        }
        /* drift = omega x u + omega x (J qd) + Jdot qd */
        rhs[18 + 3 * i + 0] = -((w[1] * u[2] - w[2] * u[1]) + (w[1] * Jq[2] - w[2] * Jq[1]) + Jdqd[3 * leg + 0]);
        rhs[18 + 3 * i + 1] = -((w[2] * u[0] - w[0] * u[2]) + (w[2] * Jq[0] - w[0] * Jq[2]) + Jdqd[3 * leg + 1]);
        rhs[18 + 3 * i + 2] = -((w[0] * u[1] - w[1] * u[0]) + (w[0] * Jq[1] - w[1] * Jq[0]) + Jdqd[3 * leg + 2]);
    }
    if (solve(m, K, rhs)) return QDX_SINGULAR;
    memcpy(acc, rhs, sizeof(qdx_real) * 18);
    return 0;
}

static int rigid_rhs(qdx_problem *P, qdx_real t, const qdx_real *y, qdx_real *f) {
    qdx_rigid *c = ((rigid_problem *)P)->c;
    const qdx_real *q = y, *v = y + 19;
    qdx_real nq = sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]), quat[4], R[9];
    qdx_real x, yy, z, w;
    const qdx_real *om = v + 3;
    int i, code = rigid_accel(c, t, y, f + 19);
    if (code) return code;
    for (i = 0; i < 4; ++i) quat[i] = q[3 + i] / nq;
    quat_to_R(quat, R);
    for (i = 0; i < 3; ++i) f[i] = R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2];
    x = quat[0];
    yy = quat[1];
    z = quat[2];
    w = quat[3];
    f[3] = 0.5 * (w * om[0] - z * om[1] + yy * om[2]);
    f[4] = 0.5 * (z * om[0] + w * om[1] - x * om[2]);
    f[5] = 0.5 * (-yy * om[0] + x * om[1] + w * om[2]);
    f[6] = 0.5 * (-x * om[0] - yy * om[1] - z * om[2]);
    for (i = 0; i < 12; ++i) f[7 + i] = v[6 + i];
    return 0;
}

static int rigid_record(qdx_problem *P, qdx_real t, const qdx_real *y, int index) {
    qdx_rigid *c = ((rigid_problem *)P)->c;
    qdx_real a[18], off = 0.0;
    int i, code = rigid_accel(c, t, y, a);
    if (code) return code;
    for (i = 0; i < 3; ++i) off += (y[i] - c->trunk[3 * index + i]) * (y[i] - c->trunk[3 * index + i]);
    off = sqrt(off);
    c->out_t[index] = t;
    memcpy(c->out_y + (size_t)index * 37, y, sizeof(qdx_real) * 37);
    memcpy(c->out_a + (size_t)index * 18, a, sizeof(qdx_real) * 18);
    c->out_off[index] = off;
    c->recorded = index + 1;
    return off > c->fallen_trunk ? QDX_FALLEN : 0;
}

/* One phase of a rigid-contact run; 0 or a stop code. */
int qdx_rigid_phase(const qdx_dop853 *co, qdx_rigid *c, qdx_real t0, qdx_real t1, qdx_real rtol, qdx_real *y,
                    const qdx_real *samples, int n_samples) {
    rigid_problem P;
    P.base.n = 37;
    P.base.rhs = rigid_rhs;
    P.base.project = 0;
    P.base.record = rigid_record;
    P.c = c;
    c->recorded = 0;
    return dop853_phase(&P.base, co, t0, t1, rtol, rtol, y, samples, n_samples);
}
