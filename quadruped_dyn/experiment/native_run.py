"""The experiment's runs in native code: one C call integrates one gait phase.

``simulate.simulate_reduced`` and ``rigid_contact.simulate_rigid`` drive scipy's DOP853 from
Python, and every right-hand-side evaluation (target table, trunk pose from the feet, fd_r
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

Extended precision (``NativeRuns(robot, "long double")``, reduced runs only): the same C with
every real a long double (x87's 64-bit significand here), linked with the robot's generated C
compiled with casadi_real = long double (its elementary-function wrappers then call sinl, cosl,
...: codegen/emit.py). Its inputs stay double: the target table (the exact IK and id_r),
the initial state, the footholds and DOP853's coefficients. It measures what the double
integration's own round-off costs (docs/results.md, the experiment's error budget).

Evaluation counts: the dense output's three extra stages are evaluated only for steps with a
sample inside (the Python path evaluates them after every step), so ``rhs_evaluations`` is
lower for the same trajectory.
"""

from __future__ import annotations

import ctypes
import hashlib
import tempfile
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate._ivp import dop853_coefficients as dop

from quadruped_dyn.codegen.c_file import casadi_c
from quadruped_dyn.codegen.emit import PREFIX, REDUCED_STANCE_SETS, generate, reduced_symbol
from quadruped_dyn.codegen.library import (
    C_FLAGS,
    compile_sources,
    compiled_library,
    compiler_version,
    generation_key,
    work_sizes_of,
)
from quadruped_dyn.dynamics.kinematics import robot_feet
from quadruped_dyn.errors import BuildError, InputError, NumericalError
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

#: The working precisions: the C type and numpy dtype of every real.
PRECISIONS: dict[str, tuple[Any, Any]] = {"double": (ctypes.c_double, np.float64),
                                          "long double": (ctypes.c_longdouble, np.longdouble)}

_int = ctypes.POINTER(ctypes.c_longlong)


@cache
def _structures(real: Any) -> dict[str, Any]:
    """c/qdx_native_run.c's structures with qdx_real = ``real`` (a ctypes type), by C name."""
    ptr = ctypes.POINTER(real)

    class Dop853(ctypes.Structure):
        _fields_ = [(name, ptr) for name in ("A", "B", "C", "E3", "E5", "D")]

    class Table(ctypes.Structure):
        _fields_ = [("m1", ctypes.c_int), ("width", ctypes.c_int), ("nodes", ptr), ("weights", ptr), ("values", ptr)]

    class Law(ctypes.Structure):
        _fields_ = [("scale", real), ("kp", real), ("kd", real), ("roll_applied", ctypes.c_int)]

    class Frame(ctypes.Structure):
        """qdx_frame: the arg, res, iw and w arrays of a call of a generated function."""

        _fields_ = [("arg", ctypes.POINTER(ptr)), ("res", ctypes.POINTER(ptr)), ("iw", _int), ("w", ptr)]

    class Reduced(ctypes.Structure):
        _fields_ = [("table", Table), ("law", Law), ("fd_r", ctypes.c_void_p), ("frame", Frame),
                    ("n", ctypes.c_int), ("k", ctypes.c_int),
                    ("project", ctypes.c_int), ("legs", ctypes.c_int * 4), ("holds", real * 12),
                    ("fallen_closure", real), ("fallen_trunk", real), ("pitch", real),
                    ("evaluations", ctypes.c_longlong), ("out_t", ptr), ("out_y", ptr), ("out_qdd", ptr),
                    ("out_closure", ptr), ("recorded", ctypes.c_int)]

    class Rigid(ctypes.Structure):
        _fields_ = [("table", Table), ("law", Law), ("M_full", ctypes.c_void_p), ("nle_full", ctypes.c_void_p),
                    ("M_rows", _int), ("M_cols", _int), ("M_nnz", ctypes.c_int), ("M_mirror", ctypes.c_int),
                    ("frame", Frame), ("k", ctypes.c_int), ("legs", ctypes.c_int * 4), ("trunk", ptr),
                    ("fallen_trunk", real), ("evaluations", ctypes.c_longlong), ("out_t", ptr),
                    ("out_y", ptr), ("out_a", ptr), ("out_off", ptr), ("recorded", ctypes.c_int)]

    return {"qdx_dop853": Dop853, "qdx_table": Table, "qdx_law": Law, "qdx_frame": Frame, "qdx_reduced": Reduced,
            "qdx_rigid": Rigid}


def layout_checks_c(structures: dict[str, Any]) -> str:
    """C, to follow c/qdx_native_run.c in its translation unit, that fails to compile (an array of size -1 named by the
    structure and field) where a structure of ``structures`` (``_structures``: C name -> ctypes structure) is not laid
    out as C lays it out: every structure's size and every field's offset, so the two sides cannot disagree."""
    lines = ["#include <stddef.h>", "/* the ctypes structures' layout (experiment/native_run.py, layout_checks_c) */"]
    for name, struct in structures.items():
        checks = [("size", f"sizeof({name})", ctypes.sizeof(struct))]
        checks += [(field, f"offsetof({name}, {field})", getattr(struct, field).offset) for field, *_ in struct._fields_]
        lines += [f"typedef char qdx_layout_{name}_{what}[{expr} == {value} ? 1 : -1];" for what, expr, value in checks]
    return "\n".join(lines) + "\n"


Buffers = tuple[np.ndarray, ...]


def _integrate(segments: list[tuple[float, float, Stance, np.ndarray]], tables: list[Any],
               phase: Callable[[float, float, Stance, np.ndarray, Any], tuple[Buffers, int]],
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


_C_TYPES = {np.dtype(np.int64): ctypes.c_longlong, np.dtype(np.float64): ctypes.c_double,
            np.dtype(np.longdouble): ctypes.c_longdouble}


def _ptr(a: np.ndarray) -> ctypes._Pointer:  # type: ignore[type-arg]
    return a.ctypes.data_as(ctypes.POINTER(_C_TYPES[a.dtype]))


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


#: The flags of a long-double build: c/qdx_native_run.c's qdx_real, the generated C's casadi_real,
#: and tgmath.h for the elementary functions CasADi's C calls directly (the feet).
LONG_DOUBLE_FLAGS = (*C_FLAGS, "-DQDX_LONG_DOUBLE", "-Dcasadi_real=long double", "-include", "tgmath.h")

def native_library(robot: Robot, cc: str = "gcc", precision: str = "double") -> Path:
    """The robot's compiled native-run library (c/qdx_native_run.c + its generated feet; in long
    double also the robot's generated C), cached under the hash of the
    sources (the generated C by its generation key), the flags and the compiler."""
    if precision not in PRECISIONS:
        raise InputError(f"precision '{precision}' is not supported; expected one of {', '.join(PRECISIONS)}")
    flags = C_FLAGS if precision == "double" else LONG_DOUBLE_FLAGS
    with tempfile.TemporaryDirectory() as tmp:
        feet = feet_source(robot, Path(tmp))
        unit = Path(tmp) / SOURCE.name  # the source and the check of its structures against the ctypes side
        unit.write_text(SOURCE.read_text() + layout_checks_c(_structures(PRECISIONS[precision][0])))
        h = hashlib.sha256(unit.read_bytes() + feet.read_bytes())
        h.update(f"{' '.join(flags)} {compiler_version(cc)}".encode())
        if precision != "double":
            h.update(generation_key(robot, precision, flags, cc).encode())

        def build(building: Path) -> None:
            generated = generate(robot, Path(tmp), "double").c_sources if precision != "double" else []
            compile_sources([unit, feet, *generated], flags, building, cc)

        suffix = "" if precision == "double" else "_" + precision.replace(" ", "_")
        return cached_build(h.hexdigest()[:16], f"libqdx_native{suffix}_{robot.name}.so", build)


class NativeRuns:
    """The robot's native runs: ``reduced`` and ``rigid`` (one gait phase per C call), in double
    or (reduced runs only) long double (the module docstring)."""

    def __init__(self, robot: Robot, precision: str = "double") -> None:
        self.robot = robot
        self._lib = ctypes.CDLL(str(native_library(robot, precision=precision)))
        self.precision = precision
        self._real, self._dtype = PRECISIONS[precision]
        self._s = _structures(self._real)
        real, ptr = self._real, ctypes.POINTER(self._real)
        for name, n_arg, n_res in (("qdx_feet", 1, 2), ("qdx_feet_rates", 2, 3)):
            if any(x > limit for x, limit in zip(work_sizes_of(self._lib, name), (n_arg, n_res, 0, 0))):
                raise BuildError(f"{name} asks for more than its own {n_arg} inputs and {n_res} outputs; "
                                 "c/qdx_native_run.c's feet_of passes no more")
        for name, kind in (("qdx_reduced_phase", "qdx_reduced"), ("qdx_rigid_phase", "qdx_rigid")):
            getattr(self._lib, name).argtypes = [ctypes.POINTER(self._s["qdx_dop853"]), ctypes.POINTER(self._s[kind]),
                                                 real, real, real, ptr, ptr, ctypes.c_int]
        # scipy's coefficients, also in long double (its 30-digit literals measured no different)
        self._coef = [np.ascontiguousarray(a, dtype=self._dtype) for a in
                      (dop.A, dop.B, dop.C, dop.E3, dop.E5, dop.D)]
        if self._coef[0].shape != (16, 16) or self._coef[5].shape != (4, 16) or self._coef[3].size != 13:
            raise BuildError("scipy's DOP853 coefficients do not have the shapes c/qdx_native_run.c expects")
        self._dop = self._s["qdx_dop853"](*[_ptr(a) for a in self._coef])
        self._interpolants: dict[tuple[int, Stance], tuple[np.ndarray, ...]] = {}
        called = [PREFIX + reduced_symbol("fd_r", s) for s in REDUCED_STANCE_SETS]
        if precision == "double":
            self._main = ctypes.CDLL(str(compiled_library(robot).path))
            graph = ca.external(PREFIX + "M_full", str(compiled_library(robot).path))
            rows, cols = (np.ascontiguousarray(x, dtype=np.int64) for x in graph.sparsity_out(0).get_triplet())
            pairs = set(zip(rows.tolist(), cols.tolist()))
            self._M = (rows, cols, int(any((c, r) not in pairs for r, c in pairs)))
            called += [PREFIX + "M_full", PREFIX + "nle_full"]
        else:
            self._main = self._lib  # the generated C is linked in
        sizes = [work_sizes_of(self._main, name) for name in called] + [work_sizes_of(self._lib, "qdx_feet_rates")]
        n_arg, n_res, n_iw, n_w = (max(1, *column) for column in zip(*sizes))
        self._work = (np.zeros(n_iw, dtype=np.int64), np.zeros(n_w, dtype=self._dtype))  # kept alive with the frame
        self._frame = self._s["qdx_frame"]((ptr * n_arg)(), (ptr * n_res)(), _ptr(self._work[0]), _ptr(self._work[1]))

    def pose(self, r_b: np.ndarray, P_w: np.ndarray, roll: float | None = None,
             pitch_hint: float = 0.0) -> tuple[np.ndarray, np.ndarray, float]:
        """The C pose fit (same arguments and result as ``trunk_pose.pose_from_feet``)."""
        rb, P = (np.ascontiguousarray(x, dtype=self._dtype).reshape(-1, 3) for x in (r_b, P_w))
        R, p, closure = np.zeros((3, 3), dtype=self._dtype), np.zeros(3, dtype=self._dtype), self._real()
        code = self._lib.qdx_pose(rb.shape[0], _ptr(rb), _ptr(P), self._real(roll or 0.0),
                                  self._real(pitch_hint), _ptr(R), _ptr(p), ctypes.byref(closure))
        if code:
            raise NumericalError(f"the C pose fit failed for {rb.shape[0]} feet (code {code})")
        return R, p, closure.value

    def _address(self, symbol: str) -> int:
        return ctypes.cast(getattr(self._main, PREFIX + symbol), ctypes.c_void_p).value or 0

    def _tables(self, table: IkTorqueTable, plan: Plan,
                segments: list[tuple[float, float, Stance, np.ndarray]]) -> list[Any] | None:
        """Every phase's interpolant, or None if one of them falls back to the exact evaluation."""
        tables = [self._table(table, plan, t0, stance) for t0, _, stance, _ in segments]
        return [tb for tb in tables if tb is not None] if all(tb is not None for tb in tables) else None

    def _table(self, table: IkTorqueTable, plan: Plan, t0: float, stance: Stance) -> Any:
        """The phase's interpolant (nodes, weights, values | the plan's trunk position), kept alive here."""
        k = int(np.floor(t0 / plan.gait.phase_duration + 1e-12))
        key = (k, stance)
        if key not in self._interpolants:
            phase = table.phase(k, stance)
            if phase is None:
                return None
            trunk = np.array([plan.trunk(float(t))[0] for t in phase.nodes])
            self._interpolants[key] = tuple(np.ascontiguousarray(a, dtype=self._dtype) for a in
                                      (phase.nodes, phase.weights, np.hstack([phase.values, trunk])))
        nodes, weights, values = self._interpolants[key]
        return self._s["qdx_table"](nodes.size, values.shape[1], _ptr(nodes), _ptr(weights), _ptr(values))

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
        y = np.ascontiguousarray(y, dtype=self._dtype)
        cfg = self._s["qdx_reduced"](law=self._s["qdx_law"](law.scale, law.kp, law.kd, int(law.roll_applied)),
                                     frame=self._frame, n=n, project=int(project), fallen_closure=FALLEN_CLOSURE_M,
                                     fallen_trunk=FALLEN_TRUNK_M, pitch=0.0, evaluations=0)
        current = [gait.stance(0.0)]

        def phase(t0: float, t1: float, stance: Stance, inside: np.ndarray, tb: Any) -> tuple[Buffers, int]:
            if t0 > 0:  # the landing in double (so, in long double, are the footholds)
                before = current[0]
                y_d = y.astype(float)
                feet = np.asarray(robot_feet(robot)(y_d[:12])[0]).T[list(before)]
                roll = float(y_d[12]) if len(before) == 2 else None
                R, p, _ = pose_from_feet(feet, np.array([footholds[i] for i in before]), roll=roll,
                                         pitch_hint=cfg.pitch)
                cfg.pitch = float(np.arctan2(-R[2, 0], np.hypot(R[2, 1], R[2, 2])))
                land(robot, footholds, before, stance, y_d, R, p)
                current[0] = stance
            m = len(inside)
            bufs = tuple(np.zeros(shape, dtype=self._dtype) for shape in (m, (m, 2 * n), (m, n), m))
            cfg.table, cfg.k, cfg.fd_r = tb, len(stance), self._address(reduced_symbol("fd_r", StanceSet(stance)))
            cfg.legs[:] = [*stance, *[0] * (4 - len(stance))]
            cfg.holds[:] = [*np.concatenate([footholds[i] for i in stance]), *[0.0] * (12 - 3 * len(stance))]
            cfg.out_t, cfg.out_y, cfg.out_qdd, cfg.out_closure = (_ptr(b) for b in bufs)
            code = self._lib.qdx_reduced_phase(ctypes.byref(self._dop), ctypes.byref(cfg), t0, t1, rtol, _ptr(y),
                                               _ptr(np.ascontiguousarray(inside, dtype=self._dtype)), m)
            return tuple(b[: cfg.recorded] for b in bufs), code

        (t, Y, qdd, closure), stopped_at = _integrate(segments, tables, phase, progress, [(), (2 * n,), (n,), ()])
        return Run(t, Y[:, :n], Y[:, n:], qdd, closure, stopped_at, int(cfg.evaluations))

    def rigid(self, plan: Plan, table: IkTorqueTable, law: TorqueLaw, horizon: float, dt: float,
              rtol: float = RTOL, progress: Progress | None = None,
              initial: tuple[np.ndarray, np.ndarray] | None = None,
              trunk: Callable[[float], np.ndarray] | None = None) -> Run | None:
        """``rigid_contact.simulate_rigid`` with DOP853 (same arguments and result), or None
        when a phase has no table."""
        if self.precision != "double":
            raise InputError(f"the rigid-contact runs are in double only, not {self.precision}")
        ref = PinocchioReference(plan.robot)
        segments = phase_segments(plan, horizon, dt)
        tables = self._tables(table, plan, segments)
        if tables is None:
            return None
        y = np.ascontiguousarray(initial_state(plan, table, ref, initial))
        trunk_at = trunk if trunk is not None else (lambda t: plan.trunk(t)[0])
        rows, cols, mirror = self._M
        cfg = self._s["qdx_rigid"](law=self._s["qdx_law"](law.scale, law.kp, law.kd, 0),
                                   M_full=self._address("M_full"), nle_full=self._address("nle_full"),
                                   M_rows=_ptr(rows), M_cols=_ptr(cols), M_nnz=rows.size, M_mirror=mirror,
                                   frame=self._frame, fallen_trunk=FALLEN_TRUNK_M, evaluations=0)
        state = [y]

        def phase(t0: float, t1: float, stance: Stance, inside: np.ndarray, tb: Any) -> tuple[Buffers, int]:
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
