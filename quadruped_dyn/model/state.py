"""The project's full-coordinate state and its conventions (docs/conventions.md §1-§3).

Frames: world w (z up, gravity ``GRAVITY_W``), trunk/body b with pose (R, p), R maps b -> w.

Full coordinates (18 velocities = 6 body + 12 joints), project joint order
FL, FR, BL, BR x (HAA, HFE, KFE):

* ``q`` (19,) = (p [m, world], quaternion (x, y, z, w) of R, 12 joint angles [rad])
* ``v`` (18,) = (v_b, omega_b, qd): body twist in the body frame, v_b = R^T pdot [m/s],
  omega_b [rad/s]; joint rates [rad/s]
* ``a`` (18,) = vdot, the time derivative of v. For the body this is the **spatial**
  acceleration vdot_b = a_b - omega_b x v_b, where a_b = R^T pddot is the **classical**
  acceleration the paper's Newton-Euler uses. ``spatial_from_classical`` and
  ``classical_from_spatial`` convert. With this choice M, C, G are the usual
  Lagrangian terms M(q) vdot + C(q, v) + G(q) = tau, identical to Pinocchio's.

The quaternion order (x, y, z, w) is Pinocchio's; it need not be normalised on input to the
symbolic functions but ``full_q`` always writes a unit one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError
from quadruped_dyn.math.compare import max_abs_error, within
from quadruped_dyn.tolerances import ORTHONORMAL_TOL

GRAVITY_W = np.array([0.0, 0.0, -9.81])  # m/s^2, world frame
NQ_FULL = 19
JOINT_ANGLES = range(7, NQ_FULL)  # q's 12 joint angles [rad], in the project joint order
NV_FULL = 18


def full_q(R: np.ndarray, p: np.ndarray, q_joints: np.ndarray) -> np.ndarray:
    """Pack (R, p, 12 joint angles) into the project's q (19,)."""
    R = check_array("R", R, (3, 3))
    with np.errstate(over="ignore"):  # a huge R's R^T R is inf: not within, refused below
        orthonormal = within(max_abs_error(R.T @ R, np.eye(3)), ORTHONORMAL_TOL)
    if not orthonormal or np.linalg.det(R) < 0:
        raise InputError("R is not a rotation matrix; expected R^T R = I and det R = +1")
    quat = pin.Quaternion(R).coeffs()  # (x, y, z, w)
    return np.concatenate([check_array("p", p, (3,)), quat, check_array("q_joints", q_joints, (12,))])


def rotation(q: np.ndarray) -> np.ndarray:
    """R (b -> w) from the project's q (checked: InputError on a wrong shape, NaN/inf or a zero
    quaternion); the quaternion is normalised first."""
    quat = check_array("q", q, (NQ_FULL,))[3:7]
    check_quaternion("q", quat)
    return quaternion_rotation(quat)


def quaternion_rotation(quat: np.ndarray) -> np.ndarray:
    """R (b -> w) of a non-zero quaternion (x, y, z, w), normalised first. Unchecked: for states the
    toolkit itself produced (an integrator's, MuJoCo's), where ``rotation``'s checks would cost more
    than the conversion."""
    return pin.Quaternion(quat / np.linalg.norm(quat)).toRotationMatrix()


def spatial_from_classical(omega_b: np.ndarray, v_b: np.ndarray, a_b: np.ndarray) -> np.ndarray:
    """vdot_b = a_b - omega_b x v_b (body frame; each (3,), checked)."""
    omega_b, v_b, a_b = (check_array(n, x, (3,)) for n, x in (("omega_b", omega_b), ("v_b", v_b), ("a_b", a_b)))
    return a_b - np.cross(omega_b, v_b)


def classical_from_spatial(omega_b: np.ndarray, v_b: np.ndarray, vdot_b: np.ndarray) -> np.ndarray:
    """a_b = vdot_b + omega_b x v_b (body frame; each (3,), checked)."""
    omega_b, v_b, vdot_b = (check_array(n, x, (3,)) for n, x in (("omega_b", omega_b), ("v_b", v_b), ("vdot_b", vdot_b)))
    return vdot_b + np.cross(omega_b, v_b)


def check_quaternion(name: str, quat: np.ndarray) -> None:
    """InputError unless |quat|^2 is a normal positive double (R = f(quat / |quat|) is then finite)."""
    with np.errstate(over="ignore", under="ignore"):
        norm2 = float(np.dot(quat, quat))
    if not np.finfo(float).tiny <= norm2 < np.inf:
        kind = "a zero quaternion" if norm2 < np.finfo(float).tiny else "a quaternion too large to normalise"
        raise InputError(f"{name} has {kind} {np.array2string(quat, precision=3)} (|q|^2 = {norm2:.1e} in double "
                         "precision); expected (x, y, z, w) of a rotation")


def check_array(name: str, x: object, shape: tuple[int, ...]) -> np.ndarray:
    """A float64 array of the given shape with finite entries, or a clear InputError. Every computation is in
    double precision: integer, float32 and float64 entries convert exactly, wider floats (long double) are
    rounded to the nearest double; float16 (3 significant digits), booleans and masked arrays (their mask would
    be ignored and the hidden values used) are refused."""
    if isinstance(x, (str, bytes)):
        raise InputError(f"{name} is a string; expected a numeric array of shape {shape}")
    if np.ma.isMaskedArray(x) or (isinstance(x, (list, tuple)) and any(np.ma.isMaskedArray(e) for e in x)):
        raise InputError(f"{name} is a masked array; expected a plain array of shape {shape} (the mask would be "
                         "ignored and the hidden values used: fill them, e.g. x.filled(...))")
    try:
        raw = np.asarray(x)  # an object's own __array__ may raise anything: that is bad input too
        if np.iscomplexobj(raw):
            raise InputError(f"{name} is complex; expected a real array of shape {shape} (the imaginary part would be lost)")
        if raw.dtype.kind == "b":
            raise InputError(f"{name} is a boolean array; expected numbers of shape {shape} (True and False would "
                             "be taken as 1 and 0)")
        if raw.dtype == np.float16:
            raise InputError(f"{name} is float16 (3 significant digits); expected float32 or float64 of shape "
                             f"{shape}: every computation is in double precision")
        if raw.dtype.kind not in "iuf":
            raise InputError(f"{name} has entries of type {raw.dtype}; expected a real numeric array of shape {shape}")
        arr = np.asarray(raw, dtype=float)
    except InputError:
        raise
    except Exception as e:
        raise InputError(f"{name} is not numeric ({type(e).__name__}: {str(e)[:80]}); expected an array of shape "
                         f"{shape}") from e
    if arr.shape != shape:
        raise InputError(f"{name} has shape {arr.shape}; expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} contains NaN or inf; expected finite values")
    return arr


@dataclass(frozen=True)
class FullState:
    """A sampled full-coordinate state: q (19,), v (18,), a = vdot (18,), foot forces (4, 3)."""

    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    f: np.ndarray  # ground force on each foot, body frame, N, project leg order


def random_state(lower: np.ndarray, upper: np.ndarray, rng: np.random.Generator) -> FullState:
    """Random orientation and position, joints uniform inside [lower, upper] (12 joint limits each,
    finite, lower <= upper: ``Robot.lower``, ``Robot.upper``), unit-scale rates."""
    lower, upper = check_array("lower", lower, (12,)), check_array("upper", upper, (12,))
    with np.errstate(over="ignore"):
        bad = np.flatnonzero(~(np.isfinite(upper - lower) & (lower <= upper)))
    if bad.size:
        raise InputError(f"joint limits [lower, upper] at joints {bad.tolist()} are not a finite range; expected "
                         "lower <= upper with a finite difference")
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng is {type(rng).__name__}; expected a numpy.random.Generator (np.random.default_rng(seed))")
    quat = rng.normal(size=4)
    R = quaternion_rotation(quat)
    q = full_q(R, rng.uniform(-1.0, 1.0, 3), rng.uniform(lower, upper))
    return FullState(q, rng.normal(size=NV_FULL), rng.normal(size=NV_FULL), rng.normal(scale=20.0, size=(4, 3)))
