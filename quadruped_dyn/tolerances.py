"""Every numeric tolerance of the project, each with the reason for its size.

All are relative to the norm of the reference quantity unless the name says otherwise.
"""

import math

#: The machine epsilons of float64 and float32, C's DBL_EPSILON and FLT_EPSILON.
DBL_EPSILON = 2.0**-52
FLT_EPSILON = 2.0**-23

#: Two double-precision evaluations of the same rigid-body quantity by different
#: algorithms (CasADi recursion vs Pinocchio): round-off grows with the number of
#: operations (~1e3) times machine epsilon (2.2e-16), so 1e-10 leaves a wide margin
#: while catching any modelling error (those are >= 1e-6 relative).
REL_TOL_TERMS = 1e-10

#: Rotation / orthonormality checks on input (R^T R = I, |quaternion| = 1): inputs are
#: typically produced by float64 code and accumulate ~1e-15 per operation.
ORTHONORMAL_TOL = 1e-9

#: Central finite differences with step FD_STEP: truncation error O(h^2) ~ 1e-10 times
#: the third derivative, round-off ~ eps/h ~ 2e-11; 1e-6 relative is safely above both.
FD_STEP = 1e-5
REL_TOL_FD = 1e-6

#: Numerical rank of a GRF system: singular values below RANK_RTOL * sigma_max count as zero.
#: Structurally zero ones come out at ~1e-16 relative; the genuine smallest ones of the
#: paper's systems stay above ~1e-4 relative for any foot layout a leg can reach.
RANK_RTOL = 1e-9

#: A reduced model's stance is regular where ``dynamics.stance_regularity.regularity`` (the square
#: of a relative singular value of the stance feet's layout) exceeds this: the GRF rank test's
#: relative singular value, squared. Measured at the walk's and trot's states of every built-in
#: robot and b1: at least 6.5e-2 (docs/reliability.md §7). The generated C compares with the
#: same number (QD_REGULARITY_MIN, written by codegen.emit; in float at least (64 FLT_EPSILON)^2).
REGULARITY_MIN = RANK_RTOL**2

#: With two feet the reduced forms the generated C uses (dynamics/reduced_projection.py: the roll-rate row e_phi has
#: tan(pitch), its rigid-motion solve e_phi e_phi^T) lose accuracy as the trunk pitches toward +-90 deg: against the
#: paper's recipe, paper FL+BR, ~PITCH_ERR_PER_COS3 * eps / cos(pitch)^3 (1.7e-9 at 0.57 deg from 90 deg, 0.1 at
#: 6e-4 deg, all returned as success before; docs/reliability.md §7). The stance's regularity is 0 (degenerate) where
#: cos(pitch) < TRUNK_PITCH_COS_MIN, where that term would exceed REL_TOL_TERMS: within 2.0 deg of +-90 deg. (The
#: layout's term, ~20 eps / regularity as in float, is not bounded in double: up to 1e-8 at 2 deg, FR+BL.)
PITCH_ERR_PER_COS3 = 20.0
TRUNK_PITCH_COS_MIN = (PITCH_ERR_PER_COS3 * DBL_EPSILON / REL_TOL_TERMS) ** (1 / 3)
TRUNK_PITCH_DEG_MARGIN = math.degrees(math.asin(TRUNK_PITCH_COS_MIN))  # 90 deg - arccos(TRUNK_PITCH_COS_MIN)

#: Two backward-stable solves of the same linear system agree to about cond(A) * eps in
#: relative terms; a GRF solution is compared with the SVD reference within
#: max(REL_TOL_TERMS, COND_ERR_FACTOR * cond(A) * eps), the factor covering the ~100
#: operations that build A and w_req. Only ill-conditioned stances (cond > 1e4) get slack.
COND_ERR_FACTOR = 100.0

#: The float build of the generated C against double values: float rounds at 6e-8 relative,
#: inputs included; sums of link contributions and the GRF solves (cond <~ GRF_COND_ASSUMED
#: near standing) amplify that by up to ~1e2 (measured: at most 5e-7 on the paper robot).
FLOAT_REL_TOL = 1e-5

#: Condition number of a GRF system that FLOAT_REL_TOL and REL_TOL_TERMS allow for. The reduced
#: model of a stance set whose GRF system is worse conditioned at a checked state gets its
#: tolerance scaled by cond / GRF_COND_ASSUMED, and fd_r additionally by cond(M_r): errors of a
#: backward-stable solve grow with the condition number, whatever the precision.
GRF_COND_ASSUMED = 100.0

#: Condition number of the reduced model's stance-foot rows [I, -[r_i]x] (+ the roll row for two
#: feet) that the tolerances allow for: 6-20 for three or four feet and the diagonal and side
#: pairs near standing. The front and back pairs (FL+FR, BL+BR) reach ~1e2-1e3: their support
#: line is lateral, nearly perpendicular to the roll axis, so the roll row barely fixes the
#: pitch about that line (exactly not at zero pitch and roll: singular there). The generated code
#: solves the maps by their normal equations (docs/formulation.md §6.2), so its rounding grows with
#: cond(A_s)^2: measured on solo12's BL+BR, CG_r's error is 0.015-0.024 eps cond(A_s)^2 in double and
#: in float at cond(A_s) 145-472 (2-11 eps cond(A_s)); the terms' tolerances scale by (cond / this)^2
#: (fd_r's and dfd_r's by cond / this, times their cond(M_r): checks.check_program_values.tolerance_scale).
MAP_COND_ASSUMED = 20.0

#: Canonical leg frames (``leg_frames``): entries of a re-expressed axis, offset, CoM (m) or
#: inertia (relative to the largest entry) within this of 0 or +-1 are set exactly. The loaded
#: model's placements are already snapped (``robot.SNAP_TOL``), so what is left is the round-off
#: of composing the frame rotations (~1e-16); 1e-12 leaves a wide margin and is far below any
#: number a URDF means (and below REL_TOL_TERMS as a change of the model).
FRAME_SNAP_TOL = 1e-12

#: A typeset formula (coefficients rounded to symbolic.DISPLAY_DIGITS = 4 significant digits,
#: each off by <= 5e-5 relative) against Pinocchio: a sum of a few such terms stays within
#: ~2e-4 of the largest entry; 1e-3 catches any wrong term or sign.
FORMULA_DISPLAY_REL_TOL = 1e-3

#: A URDF inertia's principal moments may miss positive semi-definiteness or the triangle
#: inequality A + B >= C by this much relative to the largest moment and still count as
#: physical: URDF numbers are printed with 6-7 significant digits (CAD exports), so a thin
#: rod or a flat plate (A + B = C exactly) arrives broken by ~1e-7 relative.
INERTIA_REL_TOL = 1e-6

#: Derivatives of the dynamics (dynamics/derivatives.py) against Pinocchio's analytical
#: derivatives (computeRNEADerivatives, computeABADerivatives). did_full is a sum of ~1e4
#: products (measured <= 2e-15 relative); dfd_full goes through M^-1, which amplifies
#: round-off by cond(M) ~3e3-3e4 on these robots (measured <= 3.1e-12, solo12). 1e-9 (the issue's bar)
#: keeps a margin of ~300 over that and is far below any modelling or convention error
#: (a wrong tangent convention is an O(1) error in the rotation columns).
REL_TOL_DERIVATIVES = 1e-9

#: The reduced model's and the GRF solve's derivatives (dfd_r, dgrf) against central finite
#: differences of the Pinocchio-built reduced reference (and of Pinocchio's GRF SVD solve). The
#: reference is a chain of least-squares solves, SVDs and M_r's solve, accurate to ~1e-11
#: relative, so its differences carry a round-off of ~1e-11 / h; the truncation error is
#: h^2 / 6 |f'''| for second-order differences (measured on the paper robot's four-foot dfd_r: 1.6e-7
#: at h = 1e-3, 8e-8 at 1e-4, 1.2e-6 at 1e-5, 1.6e-5 at 1e-6: round-off wins below 1e-4), but on
#: solo12 (light legs, large accelerations) the walk triple FL+FR+BR's truncation is 2.6e-5 at 1e-4.
#: So the references are fourth-order differences (``checks.finite_differences.central``): there
#: 2.6e-9 at h = 1e-4 (3.2e-9 at 1e-5, round-off). With h = 1e-4 (rad, rad/s, N m, m/s^2) 2e-6
#: relative keeps a margin of ~20 over the paper robot's second-order figures and more over the
#: fourth-order ones, and a wrong term (a missing orientation dependence, a sign) is an O(1e-2 - 1) error.
#: dfd_full's terms go through M's solve, so the model, not the code, bounds their accuracy: a backward-stable solve's
#: relative error is ~cond(M) eps, and da_dq's ~cond(M)^2 eps (dtau/dq is evaluated at a = M^-1 (tau - C - G),
#: then solved with M again). Measured against Pinocchio (the paper robot with the FL shank's inertia x1e7 and x1e9,
#: cond(M) 1e7-2e9, 5 states each): da_dtau <= 0.005 cond eps, da_dv <= 0.062 cond eps, da_dq <= 6.7e-9 cond^2 eps;
#: the built-in robots (cond(M) <= 3.3e4 at 300 random states, solo12; 8.4e3 or less for the others) <= 0.43 cond eps.
#: A term's tolerance is max(REL_TOL_DERIVATIVES, SOLVE_ERR_PER_COND cond eps), da_dq's also
#: SOLVE_ERR_PER_COND2 cond^2 eps (``derivative_tolerance``): a margin of >= 150 over those measurements, and every
#: built-in robot keeps REL_TOL_DERIVATIVES (10 cond eps reaches 1e-9 at cond(M) 4.5e5). An error the code makes
#: (a wrong sign or term) is O(1e-2 - 1) relative and still fails wherever the scaled tolerance is below that.
SOLVE_ERR_PER_COND = 10.0
SOLVE_ERR_PER_COND2 = 1e-6


def derivative_tolerance(name: str, cond_m: float) -> float:
    """The tolerance of derivative term ``name`` at a state where M's condition number is ``cond_m``."""
    scaled = SOLVE_ERR_PER_COND * cond_m * DBL_EPSILON
    if name.endswith("da_dq"):
        scaled = max(scaled, SOLVE_ERR_PER_COND2 * cond_m**2 * DBL_EPSILON)
    return max(REL_TOL_DERIVATIVES, scaled) if name.startswith("dfd_full") else REL_TOL_DERIVATIVES


FD_STEP_DERIVATIVES = 1e-4
REL_TOL_FD_DERIVATIVES = 2e-6

#: The float build's fd_r against the double build, per unit of FLT_EPSILON * cond_1(M_r): a
#: backward-stable LU solve loses ~cond digits, and M_r and C_r + G_r arrive with float rounding
#: of their own. Measured (300 states near standing, docs/embedded.md): at most 0.26 on the paper
#: robot; 1 leaves room for other robots. Stated in the generated header.
FLOAT_FD_R_PER_COND = 1.0
#: A float result with a larger error is not a result (the issue's 1 %). Measured: every float
#: fd_r that returned 0 (not QD_SINGULAR) was within it (at most 1.1e-3 on the paper robot).
FLOAT_USABLE_REL_ERR = 1e-2
#: The float build returns a non-zero code where an error bound it computes exceeds this
#: (QD_FLOAT_MAX_BOUND in the generated C; docs/embedded.md): fd_r QD_SINGULAR where FLT_EPSILON *
#: cond_1 of the matrix it eliminates (M_r with four feet, the folded rest K with a swing leg:
#: docs/formulation.md §6.2) does -- measured at 300 states on the paper robot, the float error is at
#: most 0.94 FLT_EPSILON cond_1(K) --, and every reduced function of two feet QD_DEGENERATE where
#: FLOAT_ERR_PER_REGULARITY * FLT_EPSILON / regularity does. FLOAT_USABLE_REL_ERR over a margin of 4.
FLOAT_MAX_BOUND = FLOAT_USABLE_REL_ERR / 4
#: Two stance feet: the velocity maps are solved by their normal equations (docs/formulation.md §6.2),
#: whose rounding grows as the square of the rigid-motion solve's condition number, i.e. as
#: FLT_EPSILON / regularity (a squared relative singular value: dynamics/stance_regularity.py); the
#: front and back pairs reach regularity ~1e-9 near standing, where a float M_r had no digit left.
#: Measured, float build against double at 200-300 states near standing (docs/embedded.md): the error
#: of M_r, CG_r, G_r, id_r and fd_r of FL+FR and BL+BR is at most 15 FLT_EPSILON / regularity on the paper
#: robot, 8.1 solo12, 2.6 go2, 3.3 anymal_c, 5.7 hyq, 5.8 b1; 20 covers them all (with FLOAT_MAX_BOUND:
#: QD_DEGENERATE below regularity 9.5e-4, FLOAT_REGULARITY_MIN).
FLOAT_ERR_PER_REGULARITY = 20.0
#: The regularity below which the float build of a two-feet stance set returns QD_DEGENERATE.
FLOAT_REGULARITY_MIN = FLOAT_ERR_PER_REGULARITY * FLT_EPSILON / FLOAT_MAX_BOUND

#: The tol_scale of a case in the generated C's reference header (a ratio of condition numbers,
#: printed to 3 significant digits) on two machines: the CPU's round-off moves it by ~1e-15
#: relative, which can flip its third printed digit (up to 1e-2 relative for 1.00 vs 1.01); 2e-2
#: allows that and still catches any change of the state or the conditioning.
REFERENCE_TOL_SCALE_REL_TOL = 2e-2

#: The per-phase interpolant of the plan's reference torques (``experiment.torque_table``),
#: checked at the midpoints between its nodes, relative to each signal's largest magnitude over
#: the phase (joint angles, rates, accelerations, torques, each as a group). Measured on paper,
#: solo12 and go2, trot and walk: degree 64 reaches 3e-15 to 7e-15 and degree 96 or 128 does not
#: go lower -- that floor is the exact IK and id_r's own round-off (a few hundred operations,
#: atan2 / acos), not interpolation error. 1e-14 accepts only an interpolant at that floor, far
#: below DOP853's tolerance (1e-13).
TABLE_REL_TOL = 1e-14

#: Later phases of a run reach a higher floor: on the paper robot's walk, phase 6's
#: id_r differs from its interpolant by 3.8e-14 of its scale at degree 64, 128 and 256 alike, and
#: phase 7's qdd_r by 1.0-1.1e-14: the exact IK and id_r's round-off there, which no interpolant
#: can go below (the exact evaluation the table replaces has that noise itself). Such a floor is
#: accepted up to 1e-13, DOP853's tolerance; a signal that is not smooth within a phase misses
#: it by orders of magnitude (degree 32 on these phases: 1e-11 to 6e-9).
TABLE_NOISE_TOL = 1e-13

#: The native runs (experiment/native_run.py) against the Python path they replace: the same
#: method with the floating-point operations in another order (and, for rigid contacts, M and
#: nle from the generated terms instead of Pinocchio's), so they differ by amplified round-off,
#: which the one-ulp twin run samples once. One sample is not a bound: measured on the paper
#: robot (0.3 s of trot and walk), native vs Python is 0.4-1.5x the twin difference
#: for reduced runs and 1-6.5x for rigid-contact runs. A wrong term (a missing projection, a
#: sign, a stage) moves a run by many orders of magnitude more than 10x that noise.
NATIVE_TWIN_FACTOR = 10.0

#: go2's walk integrated in long double (``NativeRuns(robot, "long double")``, DOP853 at rtol
#: 1e-16) against the exact IK plan, % of each joint signal's largest |value| (q, qd, qdd). Its
#: inputs stay double (the IK plan, id_r's table, the initial state, the footholds), and one
#: ulp of them moves the run by up to 4.9e-7 / 6.8e-7 / 7.9e-6 % (AMD EPYC: the initial
#: state one ulp up, or every table value one ulp off). The table's own noise is larger: the same
#: code, the table evaluated in another order (the grid's exact plan before or after the run),
#: gave 2.1e-7-6.5e-7 / 4.5e-7-8.5e-7 / 8.0e-6-1.3e-5 % (Intel Xeon), and the C with a
#: shared denominator's quotients as reciprocal products (codegen.printer's reciprocals, ~1 ulp per quotient)
#: 2.2e-7-8.0e-7 / 1.8e-7-1.3e-6 / 1.8e-6-2.1e-5 %: the limit is 2.5x the largest of those. The
#: double run at RTOL is at 5e-5 / 8e-5 / 1.2e-3-1.9e-3 % (truncation and its own round-off), so a
#: systematic error of the experiment 25-40x below what double can see fails the check.
EXTENDED_WALK_PCT = {"q": 2e-6, "qd": 3e-6, "qdd": 5e-5}

#: The C pose fit (Horn's quaternion, Jacobi eigenvector) against numpy's SVD (Kabsch) on the
#: same feet, m and rad: both are backward stable, ~100 operations on coordinates of ~0.5 m.
POSE_FIT_TOL = 1e-13

#: qd_dfd_r_lift_columns against qd_dfd_r_lift_dir at its seeds (codegen/emit_derivatives.lift_columns): the same
#: graph with the seeds' zeros and ones substituted, which CasADi simplifies (x * 1, x + 0 * y), so a sum can round
#: once differently (measured on the paper robot: 1.5e-16 of an output's scale with three feet, 0 with four).
#: 16 machine epsilons of the output's largest entry.
LIFT_COLUMNS_REL_TOL = 16 * DBL_EPSILON

#: Two evaluations of the same operations that differ only in their order or grouping: the compiled C against the
#: in-memory CasADi graph (a shared denominator's quotients are products with its reciprocal there,
#: codegen.printer's reciprocals: ~1 ulp each; -O3 without -ffast-math keeps IEEE order), a function leg by leg against the
#: whole-robot graph (codegen/forms/leg_pieces.py: the legs' sums in another grouping). A few hundred operations of ~1 ulp.
REL_TOL_GRAPH = 1e-13
