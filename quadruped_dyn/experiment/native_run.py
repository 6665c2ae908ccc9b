"""The experiment's runs in native code: one C call integrates one gait phase.

``simulate.simulate_reduced`` and ``rigid_contact.simulate_rigid`` drive scipy's DOP853 from
Python, and every right-hand-side evaluation (reference table, trunk pose from the feet, fd_r
or the rigid-contact KKT system, projection onto the stance closure) went through the
interpreter. ``NativeRuns`` does the same runs with c/qdx_native_run.c: scipy's DOP853 step
control, dense output and coefficients (read from scipy, not copied), the same projection and
stop rules; per phase Python only passes the table, the footholds and the law, and handles the
stance switch (footholds of landing feet, the rigid run's impact), as the Python path does.
What differs is the order of floating-point operations (and the pose fit of three or four
feet: Horn's quaternion instead of the SVD, the same optimal rotation): results agree with
the Python path to round-off, which the tests check against the one-ulp twin spread.

The reduced runs need a table for every phase (``IkTorqueTable.phase``); where one falls back
to the exact evaluation the Python path runs instead (``simulate_reduced_native`` returns None).
The rigid-contact runs take M and nle from the robot's generated full-coordinate terms
(``M_full``, ``nle_full``; checked against Pinocchio's crba and nonLinearEffects by ``check``)
and the feet, their Jacobians and J'qd' from ``qdx_feet_rates`` (generated here from
``kinematics.robot_feet``); the contact rows are in the trunk frame.

Evaluation counts: the dense output's three extra stages are evaluated only for steps with a
sample inside (the Python path evaluates them after every step), so ``rhs_evaluations`` is
lower for the same trajectory.
"""

from __future__ import annotations

import ctypes
import hashlib
import tempfile
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop

from quadruped_dyn.codegen.casadi_source import casadi_c
from quadruped_dyn.codegen.emit import PREFIX, REDUCED_STANCE_SETS, reduced_symbol
from quadruped_dyn.codegen.library import C_FLAGS, compile_sources, compiled_library, compiler_version, work_sizes_of
from quadruped_dyn.dynamics.kinematics import robot_feet
from quadruped_dyn.errors import BuildError, NumericalError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.experiment.rigid_contact import initial_state, touch_down
from quadruped_dyn.experiment.simulate import (
    FALLEN_CLOSURE_M,
    FALLEN_TRUNK_M,
    RTOL,
    Progress,
    Run,
    Stance,
    TorqueLaw,
    land,
    phase_segments,
)
from quadruped_dyn.experiment.torque_table import IkTorqueTable
from quadruped_dyn.experiment.trunk_pose import pose_from_feet
from quadruped_dyn.files.cache import cached_build
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.references.pinocchio import PinocchioReference

SOURCE = Path(__file__).parent / "c" / "qdx_native_run.c"

#: Stop codes of c/qdx_native_run.c.
FALLEN, SINGULAR, STEP_FAILED = 1, 2, 3

_dbl = ctypes.POINTER(ctypes.c_double)
_int = ctypes.POINTER(ctypes.c_longlong)


class _Dop853(ctypes.Structure):
    _fields_ = [(name, _dbl) for name in ("A", "B", "C", "E3", "E5", "D")]


class _Table(ctypes.Structure):
    _fields_ = [("m1", ctypes.c_int), ("width", ctypes.c_int), ("nodes", _dbl), ("weights", _dbl), ("values", _dbl)]


class _Law(ctypes.Structure):
    _fields_ = [("scale", ctypes.c_double), ("kp", ctypes.c_double), ("kd", ctypes.c_double),
                ("roll_applied", ctypes.c_int)]


class _Frame(ctypes.Structure):
    """c/qdx_native_run.c's qdx_frame: the arg, res, iw and w arrays of a call of a generated function."""

    _fields_ = [("arg", ctypes.POINTER(_dbl)), ("res", ctypes.POINTER(_dbl)), ("iw", _int), ("w", _dbl)]


class _Reduced(ctypes.Structure):
    _fields_ = [("table", _Table), ("law", _Law), ("fd_r", ctypes.c_void_p), ("frame", _Frame),
                ("n", ctypes.c_int), ("k", ctypes.c_int),
                ("project", ctypes.c_int), ("legs", ctypes.c_int * 4), ("holds", ctypes.c_double * 12),
                ("fallen_closure", ctypes.c_double), ("fallen_trunk", ctypes.c_double), ("pitch", ctypes.c_double),
                ("evaluations", ctypes.c_longlong), ("out_t", _dbl), ("out_y", _dbl), ("out_qdd", _dbl),
                ("out_closure", _dbl), ("recorded", ctypes.c_int)]


class _Rigid(ctypes.Structure):
    _fields_ = [("table", _Table), ("law", _Law), ("M_full", ctypes.c_void_p), ("nle_full", ctypes.c_void_p),
                ("M_rows", _int), ("M_cols", _int), ("M_nnz", ctypes.c_int), ("M_mirror", ctypes.c_int),
                ("frame", _Frame), ("k", ctypes.c_int), ("legs", ctypes.c_int * 4), ("trunk", _dbl),
                ("fallen_trunk", ctypes.c_double), ("evaluations", ctypes.c_longlong), ("out_t", _dbl),
                ("out_y", _dbl), ("out_a", _dbl), ("out_off", _dbl), ("recorded", ctypes.c_int)]


Buffers = tuple[np.ndarray, ...]


def _integrate(segments: list[tuple[float, float, Stance, np.ndarray]], tables: list[_Table],
               phase: Callable[[float, float, Stance, np.ndarray, _Table], tuple[Buffers, int]],
               progress: Progress | None, widths: list[tuple[int, ...]]) -> tuple[list[np.ndarray], float | None]:
    """``phase`` on every gait phase until one returns a stop code: the samples it recorded,
    concatenated (arrays of the given row shapes), and where the run stopped (its last sample;
    None: the full horizon)."""
    out: list[Buffers] = [tuple(np.zeros((0, *w)) for w in widths)]
    for (t0, t1, stance, inside), tb in zip(segments, tables):
        bufs, code = phase(t0, t1, stance, np.ascontiguousarray(inside, dtype=float), tb)
        out.append(bufs)
        if code:
            t = np.concatenate([o[0] for o in out])
            return [np.concatenate(parts) for parts in zip(*out)], float(t[-1]) if t.size else 0.0
        if progress:
            progress(t1)
    return [np.concatenate(parts) for parts in zip(*out)], None


def _ptr(a: np.ndarray) -> ctypes._Pointer:  # type: ignore[type-arg]
    return a.ctypes.data_as(_int if a.dtype == np.int64 else _dbl)


def feet_source(robot: Robot, directory: Path) -> Path:
    """Generate qdx_feet (q (12,) -> r (3, 4), J (3, 12): ``kinematics.robot_feet``) and
    qdx_feet_rates (q, qd (12,) -> r, J, J'qd' (3, 4)), dense, trunk frame, into one C file."""
    feet = robot_feet(robot)
    q, qd = ca.SX.sym("q", 12), ca.SX.sym("qd", 12)
    r, J = feet(q)
    jdqd = ca.horzcat(*[ca.jtimes(J[:, 3 * i : 3 * i + 3] @ qd[3 * i : 3 * i + 3], q, qd) for i in range(4)])
    source, _ = casadi_c("qdx_feet", [
        ca.Function("qdx_feet", [q], [ca.densify(r), ca.densify(J)], {"cse": True}),
        ca.Function("qdx_feet_rates", [q, qd], [ca.densify(r), ca.densify(J), ca.densify(jdqd)], {"cse": True}),
    ], "double")
    path = directory / "qdx_feet.c"
    path.write_text(source)
    return path


def native_library(robot: Robot, cc: str = "gcc") -> Path:
    """The robot's compiled native-run library (c/qdx_native_run.c + its generated feet),
    cached under the hash of both sources, the flags and the compiler."""
    with tempfile.TemporaryDirectory() as tmp:
        feet = feet_source(robot, Path(tmp))
        h = hashlib.sha256(SOURCE.read_bytes() + feet.read_bytes())
        h.update(f"{' '.join(C_FLAGS)} {compiler_version(cc)}".encode())

        def build(building: Path) -> None:
            compile_sources([SOURCE, feet], C_FLAGS, building, cc)

        return cached_build(h.hexdigest()[:16], f"libqdx_native_{robot.name}.so", build)


class NativeRuns:
    """The robot's native runs: ``reduced`` and ``rigid`` (one gait phase per C call)."""

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self._lib = ctypes.CDLL(str(native_library(robot)))
        for name, n_arg, n_res in (("qdx_feet", 1, 2), ("qdx_feet_rates", 2, 3)):
            if any(x > limit for x, limit in zip(work_sizes_of(self._lib, name), (n_arg, n_res, 0, 0))):
                raise BuildError(f"{name} asks for more than its own {n_arg} inputs and {n_res} outputs; "
                                 "c/qdx_native_run.c's feet_of passes no more")
        self._lib.qdx_reduced_phase.argtypes = [ctypes.POINTER(_Dop853), ctypes.POINTER(_Reduced), ctypes.c_double,
                                                ctypes.c_double, ctypes.c_double, _dbl, _dbl, ctypes.c_int]
        self._lib.qdx_rigid_phase.argtypes = [ctypes.POINTER(_Dop853), ctypes.POINTER(_Rigid), ctypes.c_double,
                                              ctypes.c_double, ctypes.c_double, _dbl, _dbl, ctypes.c_int]
        self._coef = [np.ascontiguousarray(a, dtype=float) for a in
                      (dop.A, dop.B, dop.C, dop.E3, dop.E5, dop.D)]
        if self._coef[0].shape != (16, 16) or self._coef[5].shape != (4, 16) or self._coef[3].size != 13:
            raise BuildError("scipy's DOP853 coefficients do not have the shapes c/qdx_native_run.c expects")
        self._dop = _Dop853(*[_ptr(a) for a in self._coef])
        self._main = ctypes.CDLL(str(compiled_library(robot).path))
        self._interpolants: dict[tuple[int, Stance], tuple[np.ndarray, ...]] = {}
        graph = ca.external(PREFIX + "M_full", str(compiled_library(robot).path))
        rows, cols = (np.ascontiguousarray(x, dtype=np.int64) for x in graph.sparsity_out(0).get_triplet())
        pairs = set(zip(rows.tolist(), cols.tolist()))
        self._M = (rows, cols, int(any((c, r) not in pairs for r, c in pairs)))
        called = [PREFIX + reduced_symbol("fd_r", s) for s in REDUCED_STANCE_SETS] + [PREFIX + "M_full", PREFIX + "nle_full"]
        sizes = [work_sizes_of(self._main, name) for name in called] + [work_sizes_of(self._lib, "qdx_feet_rates")]
        n_arg, n_res, n_iw, n_w = (max(1, *column) for column in zip(*sizes))
        self._work = (np.zeros(n_iw, dtype=np.int64), np.zeros(n_w))  # kept alive with the frame
        self._frame = _Frame((_dbl * n_arg)(), (_dbl * n_res)(), _ptr(self._work[0]), _ptr(self._work[1]))

    def pose(self, r_b: np.ndarray, P_w: np.ndarray, roll: float | None = None,
             pitch_hint: float = 0.0) -> tuple[np.ndarray, np.ndarray, float]:
        """The C pose fit (same arguments and result as ``trunk_pose.pose_from_feet``)."""
        rb, P = (np.ascontiguousarray(x, dtype=float).reshape(-1, 3) for x in (r_b, P_w))
        R, p, closure = np.zeros((3, 3)), np.zeros(3), ctypes.c_double()
        code = self._lib.qdx_pose(rb.shape[0], _ptr(rb), _ptr(P), ctypes.c_double(roll or 0.0),
                                  ctypes.c_double(pitch_hint), _ptr(R), _ptr(p), ctypes.byref(closure))
        if code:
            raise NumericalError(f"the C pose fit failed for {rb.shape[0]} feet (code {code})")
        return R, p, closure.value

    def _address(self, symbol: str) -> int:
        return ctypes.cast(getattr(self._main, PREFIX + symbol), ctypes.c_void_p).value or 0

    def _tables(self, table: IkTorqueTable, plan: Plan,
                segments: list[tuple[float, float, Stance, np.ndarray]]) -> list[_Table] | None:
        """Every phase's interpolant, or None if one of them falls back to the exact evaluation."""
        tables = [self._table(table, plan, t0, stance) for t0, _, stance, _ in segments]
        return [tb for tb in tables if tb is not None] if all(tb is not None for tb in tables) else None

    def _table(self, table: IkTorqueTable, plan: Plan, t0: float, stance: Stance) -> _Table | None:
        """The phase's interpolant (nodes, weights, values | the plan's trunk position), kept alive here."""
        k = int(np.floor(t0 / plan.gait.phase_duration + 1e-12))
        key = (k, stance)
        if key not in self._interpolants:
            phase = table.phase(k, stance)
            if phase is None:
                return None
            trunk = np.array([plan.trunk(float(t))[0] for t in phase.nodes])
            self._interpolants[key] = tuple(np.ascontiguousarray(a, dtype=float) for a in
                                      (phase.nodes, phase.weights, np.hstack([phase.values, trunk])))
        nodes, weights, values = self._interpolants[key]
        return _Table(nodes.size, values.shape[1], _ptr(nodes), _ptr(weights), _ptr(values))

    def reduced(self, plan: Plan, table: IkTorqueTable, law: TorqueLaw, horizon: float, dt: float,
                rtol: float = RTOL, initial_ulps: int = 0, progress: Progress | None = None,
                project: bool = True) -> Run | None:
        """``simulate.simulate_reduced`` with DOP853 (same arguments and result), or None when a
        phase has no table."""
        robot, gait = plan.robot, plan.gait
        n = gait.n_coords
        segments = phase_segments(plan, horizon, dt)
        tables = self._tables(table, plan, segments)
        if tables is None:
            return None
        footholds = {i: plan.foot(i, 0.0)[0] for i in range(4)}
        ref0, _ = table(0.0, gait.stance(0.0))
        y = np.concatenate([ref0.q_r, ref0.qd_r])
        for _ in range(initial_ulps):
            y = np.nextafter(y, np.inf)
        y = np.ascontiguousarray(y)
        cfg = _Reduced(law=_Law(law.scale, law.kp, law.kd, int(law.roll_applied)), frame=self._frame, n=n, project=int(project),
                       fallen_closure=FALLEN_CLOSURE_M, fallen_trunk=FALLEN_TRUNK_M, pitch=0.0, evaluations=0)
        current = [gait.stance(0.0)]

        def phase(t0: float, t1: float, stance: Stance, inside: np.ndarray, tb: _Table) -> tuple[Buffers, int]:
            if t0 > 0:
                before = current[0]
                feet = np.asarray(robot_feet(robot)(y[:12])[0]).T[list(before)]
                roll = float(y[12]) if len(before) == 2 else None
                R, p, _ = pose_from_feet(feet, np.array([footholds[i] for i in before]), roll=roll,
                                         pitch_hint=cfg.pitch)
                cfg.pitch = float(np.arctan2(-R[2, 0], np.hypot(R[2, 1], R[2, 2])))
                land(robot, footholds, before, stance, y, R, p)
                current[0] = stance
            m = len(inside)
            bufs = (np.zeros(m), np.zeros((m, 2 * n)), np.zeros((m, n)), np.zeros(m))
            cfg.table, cfg.k, cfg.fd_r = tb, len(stance), self._address(reduced_symbol("fd_r", StanceSet(stance)))
            cfg.legs[:] = [*stance, *[0] * (4 - len(stance))]
            cfg.holds[:] = [*np.concatenate([footholds[i] for i in stance]), *[0.0] * (12 - 3 * len(stance))]
            cfg.out_t, cfg.out_y, cfg.out_qdd, cfg.out_closure = (_ptr(b) for b in bufs)
            code = self._lib.qdx_reduced_phase(ctypes.byref(self._dop), ctypes.byref(cfg), t0, t1, rtol, _ptr(y),
                                               _ptr(inside), m)
            return tuple(b[: cfg.recorded] for b in bufs), code

        (t, Y, qdd, closure), stopped_at = _integrate(segments, tables, phase, progress, [(), (2 * n,), (n,), ()])
        return Run(t, Y[:, :n], Y[:, n:], qdd, closure, stopped_at, int(cfg.evaluations))

    def rigid(self, plan: Plan, table: IkTorqueTable, law: TorqueLaw, horizon: float, dt: float,
              rtol: float = RTOL, progress: Progress | None = None,
              initial: tuple[np.ndarray, np.ndarray] | None = None,
              trunk: Callable[[float], np.ndarray] | None = None) -> Run | None:
        """``rigid_contact.simulate_rigid`` with DOP853 (same arguments and result), or None
        when a phase has no table."""
        ref = PinocchioReference(plan.robot)
        segments = phase_segments(plan, horizon, dt)
        tables = self._tables(table, plan, segments)
        if tables is None:
            return None
        y = np.ascontiguousarray(initial_state(plan, table, ref, initial))
        trunk_at = trunk if trunk is not None else (lambda t: plan.trunk(t)[0])
        rows, cols, mirror = self._M
        cfg = _Rigid(law=_Law(law.scale, law.kp, law.kd, 0), M_full=self._address("M_full"),
                     nle_full=self._address("nle_full"), M_rows=_ptr(rows), M_cols=_ptr(cols), M_nnz=rows.size,
                     M_mirror=mirror, frame=self._frame, fallen_trunk=FALLEN_TRUNK_M, evaluations=0)
        state = [y]

        def phase(t0: float, t1: float, stance: Stance, inside: np.ndarray, tb: _Table) -> tuple[Buffers, int]:
            m = len(inside)
            bufs = (np.zeros(m), np.zeros((m, 37)), np.zeros((m, 18)), np.zeros(m))
            if t0 > 0:
                try:
                    state[0] = np.ascontiguousarray(touch_down(ref, stance, state[0]))
                except np.linalg.LinAlgError:  # as the Python path: a run that falls apart stops
                    return tuple(b[:0] for b in bufs), SINGULAR
            trunk_s = np.ascontiguousarray([trunk_at(float(t)) for t in inside], dtype=float).reshape(m, 3)
            cfg.table, cfg.k, cfg.trunk = tb, len(stance), _ptr(trunk_s)
            cfg.legs[:] = [*stance, *[0] * (4 - len(stance))]
            cfg.out_t, cfg.out_y, cfg.out_a, cfg.out_off = (_ptr(b) for b in bufs)
            code = self._lib.qdx_rigid_phase(ctypes.byref(self._dop), ctypes.byref(cfg), t0, t1, rtol, _ptr(state[0]),
                                             _ptr(inside), m)
            return tuple(b[: cfg.recorded] for b in bufs), code

        (t, Y, A, off), stopped_at = _integrate(segments, tables, phase, progress, [(), (37,), (18,), ()])
        return Run(t, Y[:, 7:19], Y[:, 25:], A[:, 6:], off, stopped_at, int(cfg.evaluations))
