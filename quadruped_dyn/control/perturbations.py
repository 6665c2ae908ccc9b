"""The plant made unlike the controllers' model: a heavier trunk, a payload off centre, a noisy and
late IMU (friction, foot radius and a ground step are ``PlantOptions``; a push is the run's,
``LoopOptions.push``, timed on the run's clock). The controllers keep the nominal robot's generated
C; only MuJoCo's model changes.

* ``trunk_mass_scale`` / ``link_mass_scale``: the trunk's (every leg body's) mass and rotational
  inertia times the factor (MuJoCo ``body_mass``, ``body_inertia``), centres of mass unchanged.
* ``payload_kg`` at ``payload_offset_m`` (trunk frame, from the trunk frame's origin): a point mass
  rigidly added to the trunk (its mass, centre of mass and inertia about the new centre, parallel
  axes).
* ``imu_noise_rad_s``: Gaussian noise (standard deviation, rad/s) on each axis of the measured angular
  rate, and ``imu_noise_rad`` on the measured orientation (a rotation about a random axis, trunk
  frame); ``imu_delay_ticks``: the IMU reading is that of this many measurements before (the control
  loop measures once per tick: ticks of the control rate). The encoders stay exact and on time.
  The noise is drawn from ``seed``: MuJoCo is deterministic, so the sample decides the run.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, fields

import mujoco
import numpy as np
import pinocchio as pin

from quadruped_dyn.arguments import real_number, whole_number
from quadruped_dyn.control.plant import Measurement, Plant
from quadruped_dyn.errors import InputError

#: Largest accepted mass scale of a body: beyond x10 the drivers' effort limits, not the model, decide.
MAX_MASS_SCALE = 10.0


@dataclass(frozen=True)
class Perturbation:
    trunk_mass_scale: float = 1.0
    link_mass_scale: float = 1.0
    payload_kg: float = 0.0
    payload_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)  # trunk frame
    imu_noise_rad_s: float = 0.0
    imu_noise_rad: float = 0.0
    imu_delay_ticks: int = 0
    seed: int = 0

    def validate(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            items = value if isinstance(value, tuple) else (value,)
            if f.name in ("imu_delay_ticks", "seed"):
                if whole_number(f"perturbation {f.name}", value) < 0:
                    raise InputError(f"perturbation {f.name} = {value}; expected a whole number >= 0")
                continue
            if isinstance(value, tuple) and len(value) != 3:
                raise InputError(f"perturbation {f.name} = {value!r}; expected three numbers (x, y, z)")
            for x in items:
                if not math.isfinite(real_number(f"perturbation {f.name}", x)):
                    raise InputError(f"perturbation {f.name} = {value!r}; expected finite numbers")
        for name in ("trunk_mass_scale", "link_mass_scale"):
            if not 0 < getattr(self, name) <= MAX_MASS_SCALE:
                raise InputError(f"perturbation {name} = {getattr(self, name)}; expected 0 < scale <= {MAX_MASS_SCALE:g}")
        for name in ("payload_kg", "imu_noise_rad_s", "imu_noise_rad"):
            if getattr(self, name) < 0:
                raise InputError(f"perturbation {name} = {getattr(self, name)}; expected a number >= 0")


def _payload(model: mujoco.MjModel, body: int, m: float, r: np.ndarray) -> None:
    """Add a point mass m (kg) at r (body frame, m) to ``body``: mass, centre of mass, and the
    principal inertia and its axes about the new centre (in place)."""
    M, c = float(model.body_mass[body]), model.body_ipos[body].copy()
    flat = np.zeros(9)
    mujoco.mju_quat2Mat(flat, model.body_iquat[body])
    R = flat.reshape(3, 3)
    total = M + m
    c_new = (M * c + m * r) / total

    def shift(d: np.ndarray) -> np.ndarray:
        return float(d @ d) * np.eye(3) - np.outer(d, d)

    I = R @ np.diag(model.body_inertia[body]) @ R.T + M * shift(c - c_new) + m * shift(r - c_new)
    eig, axes = np.linalg.eigh(I)
    if np.linalg.det(axes) < 0:
        axes[:, 0] = -axes[:, 0]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, axes.ravel())
    model.body_mass[body], model.body_ipos[body], model.body_inertia[body], model.body_iquat[body] = total, c_new, eig, quat


@dataclass
class PerturbedPlant(Plant):
    """A ``Plant`` with a ``Perturbation`` applied (``perturbed``)."""

    perturbation: Perturbation = field(default_factory=Perturbation)

    def __post_init__(self) -> None:
        super().__post_init__()
        p, m = self.perturbation, self.model
        trunk = int(m.jnt_bodyid[0])
        for body in range(1, m.nbody):
            scale = p.trunk_mass_scale if body == trunk else p.link_mass_scale
            m.body_mass[body] *= scale
            m.body_inertia[body] *= scale
        if p.payload_kg > 0:
            _payload(m, trunk, p.payload_kg, np.asarray(p.payload_offset_m, dtype=float))
        mujoco.mj_setConst(m, self.data)
        self._rng = np.random.default_rng(p.seed)
        self._imu: deque[tuple[np.ndarray, np.ndarray]] = deque(maxlen=p.imu_delay_ticks + 1)

    def set_state(self, q: np.ndarray, v: np.ndarray) -> None:
        super().set_state(q, v)
        self._imu.clear()

    def measure(self) -> Measurement:
        meas = super().measure()
        p = self.perturbation
        quat, omega = meas.quat, meas.omega_b
        if p.imu_noise_rad > 0:
            axis = self._rng.normal(size=3)
            tilt = pin.exp3(axis / np.linalg.norm(axis) * self._rng.normal(scale=p.imu_noise_rad))
            quat = pin.Quaternion(pin.Quaternion(quat).toRotationMatrix() @ tilt).coeffs()  # x y z w
        if p.imu_noise_rad_s > 0:
            omega = omega + self._rng.normal(scale=p.imu_noise_rad_s, size=3)
        self._imu.append((np.asarray(quat, dtype=float), omega))
        quat, omega = self._imu[0]
        return Measurement(meas.q, meas.qd, quat, omega, meas.touching)


def perturbed(plant: Plant, perturbation: Perturbation) -> PerturbedPlant:
    """A copy of ``plant`` (its MuJoCo model copied: ``plant`` is left as it was) with ``perturbation``."""
    perturbation.validate()
    model = plant.model.__copy__()
    return PerturbedPlant(plant.robot, model, mujoco.MjData(model), plant.options, plant.floor_z, plant.foot_radius,
                          plant.foot_radius_source, plant.effort, list(plant.changes), perturbation)
