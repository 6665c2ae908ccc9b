"""The plant of the closed loop: a MuJoCo model of the robot, built from the same URDF.

How the URDF becomes the plant (``build_plant``):

* MuJoCo's URDF loading as in ``references.mujoco`` (welded links fused into their parents;
  inertias the compiler refuses merged into the links they are welded to, else balanced --
  ``accepted_urdf``; every change is listed in ``Plant.changes``). The URDF's joint limits
  (MuJoCo enforces them as soft limits) and ``<dynamics damping friction>`` are kept: they are
  the robot. The controllers' model knows neither.
* The trunk on a free joint; per joint (project order FL, FR, BL, BR x HAA, HFE, KFE) the
  low-level command of a legged robot's motor drivers (as Unitree's (q, dq, Kp, Kd, tau)):
  tau_ff + Kp (q_des - q) + Kd (qd_des - qd), the PD evaluated by the drivers at every plant
  step (MuJoCo position and velocity actuators; ``implicitfast`` treats the damping
  implicitly), the feedforward held over the control tick; the sum clamped at the URDF's
  effort limit (``actfrcrange`` of the joint). Robots like solo12 have links of ~1e-4 kg m^2:
  a joint damping of a few 0.1 N m s/rad applied explicitly once per 1 ms tick is unstable
  (Kd dt / I > 2), which is why real drivers run the PD at 10-40 kHz.
* A ground plane and one contact sphere per foot, centred at the foot frame's origin (the
  paper's contact point), radius the foot link's collision sphere if the URDF has one there,
  else ``DEFAULT_FOOT_RADIUS``. The sphere touches the ground ``radius`` below the contact
  point of the controllers' model: the floor is placed so that the plan's feet are exactly
  ``radius`` above it, so world coordinates are the plan's (the planned trunk origin is at z = 0).
  A ground step (``PlantOptions.ground_step`` = (x, h)): from world x on, across the whole width, the
  ground is h higher (h < 0: lower), the edge a box's; ``floor_z`` stays the start's ground.
  Feet are the only collision geometry: legs and trunk pass through the floor (a fall is
  detected from the trunk, ``measures``). Friction mu (default 0.8) on the feet and the floor,
  ``condim`` 3 (point contact with sliding friction), MuJoCo's default soft-contact parameters
  (``solref`` 0.02 s, ``solimp`` 0.9-0.95): a compliant, frictional, unilateral contact.
* Time step ``timestep`` (default 0.5 ms) and integrator ``implicitfast`` (MuJoCo's
  recommended one: implicit in the joint damping and velocity terms, explicit otherwise).
* Visual only (no mass, no contact): capsules along the links and a box for the trunk, for
  the animation.

Conventions at the boundary: MuJoCo's qpos = (p, quat w x y z, joints in MuJoCo's order),
qvel = (linear velocity in the **world** frame, angular velocity in the **body** frame,
joint rates); ``Plant`` converts to the project's (p, quat x y z w, joints) and
(v_b, omega_b, qd) in project order.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import mujoco
import numpy as np

from quadruped_dyn.arguments import real_number
from quadruped_dyn.control.ground import GROUND_HALF_SIZE_M, MAX_GROUND_STEP_M
from quadruped_dyn.dynamics.grf import MAX_FRICTION_COEFFICIENT
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import Plan
from quadruped_dyn.model.actuator_limits import actuator_limits
from quadruped_dyn.model.robot import Robot
from quadruped_dyn.model.state import GRAVITY_W
from quadruped_dyn.model.urdf_edit import strip_geometry, to_text
from quadruped_dyn.references.mujoco import accepted_urdf

#: Contact sphere radius (m) when the URDF has no collision sphere at the foot frame: the
#: size of the rubber feet of 10-15 kg quadrupeds (go1, a1: 0.02 m).
DEFAULT_FOOT_RADIUS = 0.02

#: A collision sphere of the foot link counts as the foot if its centre is this close to the
#: foot frame's origin (m).
FOOT_SPHERE_OFFSET_TOL = 1e-3

#: A push's impulse is spread evenly over this time as a force on the trunk (s): short against a gait phase
#: (0.1-0.3 s), long against the plant's step (0.5 ms), so the impulse is what matters.
PUSH_DURATION_S = 0.01

INTEGRATORS = {"implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST, "euler": mujoco.mjtIntegrator.mjINT_EULER,
               "rk4": mujoco.mjtIntegrator.mjINT_RK4, "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT}


@dataclass(frozen=True)
class PlantOptions:
    timestep: float = 0.0005  # s
    integrator: str = "implicitfast"
    mu: float = 0.8  # Coulomb friction of feet and floor
    foot_radius: float | None = None  # m; None: from the URDF (see the module docstring)
    ground_step: tuple[float, float] | None = None  # (x m, height m), world frame; None: one flat floor

    def validate(self) -> None:
        for name in ("timestep", "mu") + (("foot_radius",) if self.foot_radius is not None else ()):
            real_number(f"plant {name}", getattr(self, name))
        if self.ground_step is not None:
            step = self.ground_step
            if not (isinstance(step, tuple | list) and len(step) == 2
                    and all(math.isfinite(real_number("ground step", v)) for v in step)):
                raise InputError(f"ground step {step!r}; expected two finite numbers: x (m) and height (m)")
            if not (abs(step[0]) <= GROUND_HALF_SIZE_M and abs(step[1]) <= MAX_GROUND_STEP_M):
                raise InputError(f"ground step at x = {step[0]:g} m of {step[1]:g} m; expected |x| <= "
                                 f"{GROUND_HALF_SIZE_M:g} m and |height| <= {MAX_GROUND_STEP_M:g} m")
        if not (math.isfinite(self.timestep) and 0 < self.timestep <= 0.01):
            raise InputError(f"plant timestep {self.timestep} s; expected 0 < timestep <= 0.01 s")
        if self.integrator not in INTEGRATORS:
            raise InputError(f"unknown integrator '{self.integrator}'; expected one of {', '.join(INTEGRATORS)}")
        if not (math.isfinite(self.mu) and 0 <= self.mu <= MAX_FRICTION_COEFFICIENT):
            raise InputError(f"friction mu = {self.mu}; expected a number from 0 to {MAX_FRICTION_COEFFICIENT:g}")
        if self.foot_radius is not None and not (math.isfinite(self.foot_radius) and 0 < self.foot_radius < 0.2):
            raise InputError(f"foot radius {self.foot_radius} m; expected 0 < radius < 0.2 m")


@dataclass(frozen=True)
class Command:
    """One control tick's command per joint (12,): feedforward torque (N m), PD target and gains
    (one gain for every joint, or one per joint)."""

    tau: np.ndarray
    q_des: np.ndarray | None = None
    qd_des: np.ndarray | None = None
    kp: float | np.ndarray = 0.0  # N m / rad
    kd: float | np.ndarray = 0.0  # N m s / rad


@dataclass(frozen=True)
class Measurement:
    """What a robot measures: encoders and an IMU (exact here: no noise, no delay)."""

    q: np.ndarray  # (12,) joint angles, rad, project order
    qd: np.ndarray  # (12,) joint rates, rad/s
    quat: np.ndarray  # (4,) trunk orientation x y z w (trunk -> world)
    omega_b: np.ndarray  # (3,) trunk angular velocity, trunk frame, rad/s
    touching: np.ndarray  # (4,) foot contact switches (MuJoCo's contacts of the last step)


@dataclass
class Plant:
    robot: Robot
    model: mujoco.MjModel
    data: mujoco.MjData
    options: PlantOptions
    floor_z: float  # m, world
    foot_radius: float  # m
    foot_radius_source: str
    effort: np.ndarray  # (12,) N m, project order
    changes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        m, names = self.model, self.robot.joint_names
        self.qpos_idx = np.array([m.joint(n).qposadr[0] for n in names])
        self.dof_idx = np.array([m.joint(n).dofadr[0] for n in names])
        self.foot_geoms = np.array([m.geom(f"quadruped_dyn_foot_{leg.label}").id for leg in self.robot.legs])
        self.foot_sites = [m.site(f"quadruped_dyn_foot_{leg.label}").id for leg in self.robot.legs]
        self.floor_geom = m.geom("quadruped_dyn_floor").id
        self._gains: tuple[object, object] = (None, None)  # the gains last set (identity: they are set again if new)
        self._warnings = 0

    # -------------------------------------------------------------------- state
    def measure(self) -> Measurement:
        d = self.data
        w, x, y, z = d.qpos[3:7]
        return Measurement(d.qpos[self.qpos_idx].copy(), d.qvel[self.dof_idx].copy(), np.array([x, y, z, w]),
                           d.qvel[3:6].copy(), self.contact_forces()[1])

    def full_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The true state in the project's full coordinates: q (19,), v (18,)."""
        d = self.data
        w, x, y, z = d.qpos[3:7]
        R = self.rotation()
        q = np.concatenate([d.qpos[:3], [x, y, z, w], d.qpos[self.qpos_idx]])
        v = np.concatenate([R.T @ d.qvel[:3], d.qvel[3:6], d.qvel[self.dof_idx]])
        return q, v

    def acceleration(self) -> np.ndarray:
        """vdot (18,) in the project's convention (spatial trunk part: R^T pddot - omega x v_b) of
        the last step's forward dynamics (``data.qacc``, at the state before that step)."""
        d = self.data
        R = self.rotation()
        v_b = R.T @ d.qvel[:3]
        return np.concatenate([R.T @ d.qacc[:3] - np.cross(d.qvel[3:6], v_b), d.qacc[3:6], d.qacc[self.dof_idx]])

    def set_state(self, q: np.ndarray, v: np.ndarray) -> None:
        """Set the state from the project's q (19,), v (18,) and run the position stage."""
        d = self.data
        quat = np.asarray(q[3:7], dtype=float) / np.linalg.norm(q[3:7])
        d.qpos[:3] = q[:3]
        d.qpos[3:7] = [quat[3], quat[0], quat[1], quat[2]]
        d.qpos[self.qpos_idx] = q[7:]
        mujoco.mj_kinematics(self.model, d)
        d.qvel[:3] = self.rotation() @ v[:3]
        d.qvel[3:6] = v[3:6]
        d.qvel[self.dof_idx] = v[6:]
        mujoco.mj_forward(self.model, d)

    def rotation(self) -> np.ndarray:
        return self.data.xmat[self.model.jnt_bodyid[0]].reshape(3, 3).copy()

    def trunk_position(self) -> np.ndarray:
        return self.data.qpos[:3].copy()

    def step(self, command: Command, substeps: int) -> None:
        """Apply the command for ``substeps`` plant steps (the drivers' PD at every step; the sum
        clamped at the effort limits)."""
        m, d = self.model, self.data
        d.ctrl[:12] = command.tau
        d.ctrl[12:24] = command.q_des if command.q_des is not None else 0.0
        d.ctrl[24:36] = command.qd_des if command.qd_des is not None else 0.0
        if command.kp is not self._gains[0] or command.kd is not self._gains[1]:
            m.actuator_gainprm[12:24, 0], m.actuator_biasprm[12:24, 1] = command.kp, np.negative(command.kp)
            m.actuator_gainprm[24:36, 0], m.actuator_biasprm[24:36, 2] = command.kd, np.negative(command.kd)
            self._gains = (command.kp, command.kd)
        mujoco.mj_step(m, d, substeps)

    def push(self, impulse_N_s: np.ndarray | tuple[float, ...], at_s: float, t_s: float) -> None:
        """Set the force of a push of ``impulse_N_s`` (world frame, N s) at the trunk's centre of mass for the
        next steps, at time ``t_s`` (s): impulse / PUSH_DURATION_S from ``at_s`` for PUSH_DURATION_S, else none."""
        pushing = at_s <= t_s + 1e-9 < at_s + PUSH_DURATION_S
        self.data.xfrc_applied[self.model.jnt_bodyid[0], :3] = np.asarray(impulse_N_s) / PUSH_DURATION_S if pushing else 0.0

    def unstable(self) -> bool:
        """MuJoCo found non-finite or huge accelerations or controls (and reset the state): the
        warning counters grew since the last call."""
        w = self.data.warning
        count = sum(int(w[k].number) for k in (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADCTRL,
                                                mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL))
        grew, self._warnings = count > self._warnings, count
        return grew

    def joint_torques(self) -> np.ndarray:
        """(12,) the drivers' total torque of the last step before the effort clamp, N m."""
        f = self.data.actuator_force
        return f[:12] + f[12:24] + f[24:36]

    # -------------------------------------------------------------------- contacts
    def foot_positions(self) -> np.ndarray:
        """(4, 3) world positions of the foot frames' origins (the sphere centres), m."""
        return np.array([self.data.site_xpos[s] for s in self.foot_sites])

    def contact_forces(self) -> tuple[np.ndarray, np.ndarray]:
        """(4, 3) ground force on each foot (world frame, N) and (4,) in-contact flags, from the
        contacts of the last step (``mj_contactForce``)."""
        d = self.data
        forces, touching = np.zeros((4, 3)), np.zeros(4, dtype=bool)
        buf = np.zeros(6)
        for i in range(d.ncon):
            c = d.contact[i]
            for sign, geom in ((1.0, c.geom2), (-1.0, c.geom1)):  # the normal points from geom1 to geom2
                hit = np.nonzero(self.foot_geoms == geom)[0]
                if hit.size:
                    mujoco.mj_contactForce(self.model, d, i, buf)
                    forces[hit[0]] += sign * (c.frame.reshape(3, 3).T @ buf[:3])
                    touching[hit[0]] = True
        return forces, touching


def _foot_sphere(root: ET.Element, link: str) -> float | None:
    """Radius of a collision sphere of ``link`` centred at its origin, if the URDF has one."""
    for x in root.findall("link"):
        if x.get("name") != link:
            continue
        for col in x.findall("collision"):
            sphere = col.find("geometry/sphere")
            origin = col.find("origin")
            xyz = np.array([float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()])
            if sphere is not None and np.linalg.norm(xyz) < FOOT_SPHERE_OFFSET_TOL:
                return float(sphere.get("radius", "nan"))
    return None


def _compile(spec: mujoco.MjSpec) -> mujoco.MjModel:
    try:
        return spec.compile()
    except ValueError as e:
        raise InputError(f"MuJoCo cannot compile the plant: {' '.join(str(e).replace('Error: ', '').split())}") from e


def _spec(text: str, robot: Robot, options: PlantOptions, floor_z: float, radius: float,
          effort: np.ndarray) -> mujoco.MjSpec:
    try:
        spec = mujoco.MjSpec.from_string(text)
    except ValueError as e:
        raise InputError(f"MuJoCo cannot read the URDF {robot.urdf}: {' '.join(str(e).split())}") from e
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.option.gravity = GRAVITY_W
    spec.option.timestep = options.timestep
    spec.option.integrator = INTEGRATORS[options.integrator]
    trunk = spec.worldbody.first_body()
    if trunk is None:
        raise InputError(f"MuJoCo finds no body in {robot.urdf}; expected a quadruped URDF")
    trunk.add_freejoint()
    spec.worldbody.add_light(pos=[0, 0, 3], dir=[0, 0, -1])
    x0, h = options.ground_step or (0.0, 0.0)
    friction = [options.mu, 0.005, 0.0001]
    spec.worldbody.add_geom(name="quadruped_dyn_floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                            pos=[0, 0, floor_z + min(0.0, h)], friction=friction, rgba=[0.55, 0.6, 0.65, 1])
    if h:  # the higher side (x >= x0 for a step up, x < x0 for one down) a box standing on the plane
        side = 1.0 if h > 0 else -1.0
        spec.worldbody.add_geom(name="quadruped_dyn_step", type=mujoco.mjtGeom.mjGEOM_BOX,
                                size=[GROUND_HALF_SIZE_M, GROUND_HALF_SIZE_M, abs(h) / 2],
                                pos=[x0 + side * GROUND_HALF_SIZE_M, 0, floor_z + min(0.0, h) + abs(h) / 2],
                                friction=friction, rgba=[0.5, 0.55, 0.6, 1])
    for leg in robot.legs:
        foot = spec.body(leg.foot_frame)
        if foot is None:
            raise InputError(f"MuJoCo has no body for the foot link '{leg.foot_frame}' of {robot.name}")
        foot.add_site(name=f"quadruped_dyn_foot_{leg.label}", pos=[0.0, 0.0, 0.0])
        foot.add_geom(name=f"quadruped_dyn_foot_{leg.label}", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[radius, 0, 0],
                      friction=friction, condim=3, rgba=[0.1, 0.1, 0.1, 1])
    for name, limit in zip(robot.joint_names, effort):
        joint = spec.joint(name)
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.actfrcrange = [-limit, limit]
    for kind in ("tau", "kp", "kd"):  # actuators 0-11 feedforward, 12-23 position, 24-35 velocity
        for name in robot.joint_names:
            act = spec.add_actuator(name=f"quadruped_dyn_{kind}_{name}", target=name)
            act.trntype = mujoco.mjtTrn.mjTRN_JOINT
            act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
            if kind == "kp":
                act.set_to_position(kp=0.0)
            elif kind == "kd":
                act.set_to_velocity(kv=0.0)
    return spec


def _add_visuals(spec: mujoco.MjSpec, model: mujoco.MjModel, robot: Robot) -> None:
    """Capsules from each leg body's origin to the next joint's (or the foot's), a trunk box."""
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    visual = {"contype": 0, "conaffinity": 0, "group": 1}
    hips = []
    for leg in robot.legs:
        bodies = [model.jnt_bodyid[model.joint(j.name).id] for j in leg.joints]
        foot_site = model.site(f"quadruped_dyn_foot_{leg.label}").id
        ends = [data.xpos[b] for b in bodies[1:]] + [data.site_xpos[foot_site]]
        hips.append(model.body_pos[bodies[0]] if model.body_parentid[bodies[0]] == 1 else data.xpos[bodies[0]])
        for b, end in zip(bodies, ends):
            rel = data.xmat[b].reshape(3, 3).T @ (end - data.xpos[b])
            if np.linalg.norm(rel) > 1e-3:
                spec.body(model.body(b).name).add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, fromto=[0, 0, 0, *rel],
                                                       size=[0.012, 0, 0], rgba=[0.85, 0.45, 0.1, 1], **visual)
    h = np.abs(np.array(hips))
    spec.worldbody.first_body().add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[max(h[:, 0].max(), 0.05),
                                         max(h[:, 1].max(), 0.03), 0.03], rgba=[0.2, 0.35, 0.6, 1], **visual)


def build_plant(robot: Robot, plan: Plan, options: PlantOptions = PlantOptions()) -> Plant:
    """The MuJoCo plant of ``robot`` for ``plan`` (see the module docstring). InputError if MuJoCo
    cannot compile it."""
    options.validate()
    original = ET.parse(robot.urdf).getroot()
    root, changes = accepted_urdf(original)
    if options.foot_radius is not None:
        radius, source = options.foot_radius, "given"
    else:
        found = {_foot_sphere(root, leg.foot_frame) for leg in robot.legs}
        value = next(iter(found)) if len(found) == 1 else None
        if value is not None and math.isfinite(value) and value > 0:
            radius, source = value, "the URDF's foot collision sphere"
        else:
            radius, source = DEFAULT_FOOT_RADIUS, f"default {DEFAULT_FOOT_RADIUS} m (no collision sphere at the foot frames)"
    strip_geometry(root)
    effort = actuator_limits(robot)["effort"]  # the rates too: optimize's rule (a joint that cannot move is refused)
    floor_z = float(np.mean([plan.foot(i, 0.0)[0][2] for i in range(4)])) - radius
    text = to_text(root)
    model = _compile(_spec(text, robot, options, floor_z, radius, effort))
    if model.nv != 18 or model.jnt_type[0] != mujoco.mjtJoint.mjJNT_FREE:
        raise InputError(f"MuJoCo's plant of {robot.name} has nv = {model.nv}; expected a free joint and 12 hinges")
    spec = _spec(text, robot, options, floor_z, radius, effort)
    spec.compiler.discardvisual = False  # MuJoCo's URDF default drops geoms that do not collide
    _add_visuals(spec, model, robot)
    model = _compile(spec)
    fused = len(original.findall("link")) - (model.nbody - 1)
    changes.insert(0, f"{fused} welded links fused into their parents (MuJoCo's fusestatic)")
    return Plant(robot, model, mujoco.MjData(model), options, floor_z, radius, source, effort, changes)
