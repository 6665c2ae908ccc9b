"""The paper's robot: its DH table (Table 1), the physical parameters we chose, and the
generator of its URDF from them: ``quadruped_dyn/urdf/paper_quadruped.urdf`` (package data,
so an installed package has it) and the same bytes at ``urdf/paper_quadruped.urdf`` in a
source checkout (``URDF_COPIES``: ``make-urdf`` writes both, ``make-urdf --check`` compares both).

DH convention: Craig's *modified* DH, ``T_{i-1,i} = RotX(alpha_{i-1}) TransX(a_{i-1})
RotZ(theta_i) TransZ(d_i)``. Because RotZ and TransZ commute, each row compiles to a fixed
placement ``RotX(alpha) TransX(a) TransZ(d)`` followed by a rotation about the joint's z.

Frame 0 of every leg sits at its hip with x0 = y_b, y0 = x_b, z0 = -z_b. The paper writes
"x, y, z of frame 0 correspond to y, x, z of the body", which is a reflection (det = -1);
flipping z0 makes it a proper rotation. All four legs use this same assignment, so
theta = (0, 0, 0) points every leg sideways (+y_b) and theta = STANDING_Q
= (90, 45, -90) deg is the standing posture of the paper's Fig. 1d.

The paper gives no masses or inertias. ``PARAMS`` holds plausible values for a ~10 kg
robot, each with its reason; this module is the only place they are stated.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.math.rigid import LinkInertia, Placement
from quadruped_dyn.model.leg import JOINT_ROLES, LEG_LABELS, Leg, LegJoint


@dataclass(frozen=True)
class DHRow:
    """One row of a modified-DH table: alpha_{i-1} (rad), a_{i-1} (m), d_i (m)."""

    alpha: float
    a: float
    d: float

    def placement(self) -> Placement:
        """Fixed part RotX(alpha) TransX(a) TransZ(d) of T_{i-1,i}; the joint turns about z."""
        ca, sa = np.cos(self.alpha), np.sin(self.alpha)
        R = np.array([[1.0, 0.0, 0.0], [0.0, ca, -sa], [0.0, sa, ca]])
        return Placement(R, np.array([self.a, 0.0, 0.0]) + R @ np.array([0.0, 0.0, self.d]))


@dataclass(frozen=True)
class PaperRobotParams:
    # Link lengths: the paper leaves them symbolic (l2, l3); 0.2 m each is the size class
    # of Unitree A1 / Go1 (0.2 / 0.213 m), giving a 0.28 m standing height at STANDING_Q.
    l2: float = 0.20  # thigh, m
    l3: float = 0.20  # shank, m
    # Hip (frame 0) positions: a 0.38 m x 0.14 m hip rectangle, as on A1-class trunks.
    hip_x: float = 0.19  # m, +front / -back
    hip_y: float = 0.07  # m, +left / -right
    # Masses: 10.0 kg in total; the trunk carries ~54 % (battery, electronics), as on A1.
    trunk_mass: float = 5.4  # kg
    trunk_size: tuple[float, float, float] = (0.38, 0.16, 0.10)  # solid box, m
    hip_mass: float = 0.45  # HAA link: holds the HFE motor, kg
    hip_radius: float = 0.04  # solid sphere centred on the hip, m
    thigh_mass: float = 0.55  # HFE link: holds the knee motor, kg
    shank_mass: float = 0.15  # KFE link: light carbon tube, kg
    link_radius: float = 0.015  # thigh and shank are solid cylinders along their DH x axis, m
    # Joint limits (rad): a band around STANDING_Q that keeps the knee bent one way
    # (KFE < 0 never reaches the straight-leg singularity) and the hip away from the trunk.
    haa_limits: tuple[float, float] = (np.pi / 2 - 0.6, np.pi / 2 + 0.6)
    hfe_limits: tuple[float, float] = (-0.5, 2.0)
    kfe_limits: tuple[float, float] = (-2.6, -0.3)
    effort: float = 20.0  # N m, URDF requires one; not used by the dynamics
    velocity: float = 20.0  # rad/s, idem


PARAMS = PaperRobotParams()

#: Table 1 of the paper: rows 1-3 are HAA, HFE, KFE; row 4 places the foot (theta_4 = 0).
def dh_table(params: PaperRobotParams = PARAMS) -> tuple[DHRow, DHRow, DHRow, DHRow]:
    return (
        DHRow(alpha=np.pi / 2, a=0.0, d=0.0),
        DHRow(alpha=-np.pi / 2, a=0.0, d=0.0),
        DHRow(alpha=0.0, a=params.l2, d=0.0),
        DHRow(alpha=0.0, a=params.l3, d=0.0),
    )


#: Frame 0 in the trunk frame: columns x0 = y_b, y0 = x_b, z0 = -z_b (a proper rotation).
R_B0 = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])

#: The standing posture of the paper's Fig. 1d, rad (HAA, HFE, KFE), the same for all legs.
STANDING_Q = np.radians([90.0, 45.0, -90.0])


def hip_position(label: str, params: PaperRobotParams = PARAMS) -> np.ndarray:
    sx = 1.0 if label[0] == "F" else -1.0
    sy = 1.0 if label[1] == "L" else -1.0
    return np.array([sx * params.hip_x, sy * params.hip_y, 0.0])


def _cylinder_x(mass: float, radius: float, length: float) -> np.ndarray:
    """Solid cylinder along x about its centre, kg m^2."""
    axial = mass * radius**2 / 2.0
    transverse = mass * (3.0 * radius**2 + length**2) / 12.0
    return np.diag([axial, transverse, transverse])


def link_inertias(params: PaperRobotParams = PARAMS) -> tuple[LinkInertia, LinkInertia, LinkInertia]:
    """Hip, thigh, shank inertias in their DH frames (1, 2, 3)."""
    p = params
    hip = LinkInertia(p.hip_mass, np.zeros(3), np.eye(3) * 0.4 * p.hip_mass * p.hip_radius**2)
    thigh = LinkInertia(p.thigh_mass, np.array([p.l2 / 2, 0.0, 0.0]), _cylinder_x(p.thigh_mass, p.link_radius, p.l2))
    shank = LinkInertia(p.shank_mass, np.array([p.l3 / 2, 0.0, 0.0]), _cylinder_x(p.shank_mass, p.link_radius, p.l3))
    return hip, thigh, shank


def trunk_inertia(params: PaperRobotParams = PARAMS) -> LinkInertia:
    sx, sy, sz = params.trunk_size
    m = params.trunk_mass
    return LinkInertia(m, np.zeros(3), np.diag([m * (sy**2 + sz**2), m * (sx**2 + sz**2), m * (sx**2 + sy**2)]) / 12.0)


def dh_leg(label: str, params: PaperRobotParams = PARAMS) -> Leg:
    """Compile the DH table of one leg to the project's leg structure."""
    rows = dh_table(params)
    frame0 = Placement(R_B0, hip_position(label, params))
    limits = (params.haa_limits, params.hfe_limits, params.kfe_limits)
    joints = tuple(
        LegJoint(
            name=f"{label}_{role}",
            placement=(frame0 @ row.placement()) if i == 0 else row.placement(),
            axis=np.array([0.0, 0.0, 1.0]),
            lower=lim[0],
            upper=lim[1],
        )
        for i, (role, row, lim) in enumerate(zip(JOINT_ROLES, rows, limits))
    )
    return Leg(label, joints, link_inertias(params), rows[3].placement(), f"{label}_foot")  # type: ignore[arg-type]


#: Two placements are "the same" when every entry agrees to this (m or unitless): the URDF
#: writer prints shortest round-trip doubles and the loader snaps entries within 1e-12.
DH_MATCH_TOL = 1e-9


def dh_form(leg: Leg) -> PaperRobotParams | None:
    """The DH parameters (hip, l2, l3) if ``leg`` has the paper's DH form (Table 1 with frame
    0 as R_B0 at a hip in the trunk plane), else None: decided by what the leg is -- its joint
    placements, axes and foot -- not by which file it came from."""
    hip = leg.hip
    params = PaperRobotParams(l2=float(leg.joints[2].placement.p[0]), l3=float(leg.foot.p[0]),
                              hip_x=abs(float(hip[0])), hip_y=abs(float(hip[1])))
    if params.l2 <= 0 or params.l3 <= 0:
        return None
    dh = dh_leg(leg.label, params)
    pairs = [(a.placement, b.placement) for a, b in zip(leg.joints, dh.joints)] + [(leg.foot, dh.foot)]
    same = all(np.allclose(a.R, b.R, rtol=0, atol=DH_MATCH_TOL) and np.allclose(a.p, b.p, rtol=0, atol=DH_MATCH_TOL)
               for a, b in pairs)
    axes = all(np.allclose(j.axis, [0.0, 0.0, 1.0], rtol=0, atol=DH_MATCH_TOL) for j in leg.joints)
    return params if same and axes else None


# ----------------------------------------------------------------------------- URDF writer


def _num(x: float) -> str:
    """Shortest text that reads back as the same double (so the URDF loses nothing)."""
    s = repr(float(x))
    s = s[:-2] if s.endswith(".0") else s
    return "0" if s in ("-0", "0") else s


def _vec(v: np.ndarray) -> str:
    return " ".join(_num(x) for x in v)


def _rpy(R: np.ndarray) -> np.ndarray:
    """URDF roll-pitch-yaw with R = Rz(yaw) Ry(pitch) Rx(roll); rounded to 1e-15 so round-off noise prints as 0."""
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    roll = np.arctan2(R[2, 1], R[2, 2])
    yaw = np.arctan2(R[1, 0], R[0, 0])
    return np.round(np.array([roll, pitch, yaw]), 15)


def _origin(T: Placement) -> str:
    return f'<origin xyz="{_vec(T.p)}" rpy="{_vec(_rpy(T.R))}"/>'


def _link(name: str, inertia: LinkInertia | None) -> list[str]:
    if inertia is None:
        return [f"  <link name={quoteattr(name)}/>"]
    I = inertia.inertia
    return [
        f"  <link name={quoteattr(name)}>",
        "    <inertial>",
        f'      <origin xyz="{_vec(inertia.com)}" rpy="0 0 0"/>',
        f'      <mass value="{_num(inertia.mass)}"/>',
        f'      <inertia ixx="{_num(I[0, 0])}" ixy="{_num(I[0, 1])}" ixz="{_num(I[0, 2])}"'
        f' iyy="{_num(I[1, 1])}" iyz="{_num(I[1, 2])}" izz="{_num(I[2, 2])}"/>',
        "    </inertial>",
        "  </link>",
    ]


LINK_NAMES = ("hip", "thigh", "shank")


def urdf_text(params: PaperRobotParams = PARAMS) -> str:
    """The URDF of the paper's robot, deterministic for given parameters."""
    lines = [
        '<?xml version="1.0"?>',
        "<!-- Generated by quadruped_dyn.model.paper_robot from the paper's DH table (Table 1).",
        "     Do not edit: run `quadruped-dyn make-urdf` instead. -->",
        '<robot name="paper_quadruped">',
        *_link("trunk", trunk_inertia(params)),
    ]
    for label in LEG_LABELS:
        leg = dh_leg(label, params)
        parent = "trunk"
        for joint, link_name, inertia in zip(leg.joints, LINK_NAMES, leg.links):
            child = f"{label}_{link_name}"
            lines += _link(child, inertia)
            lines += [
                f'  <joint name={quoteattr(joint.name)} type="revolute">',
                f"    {_origin(joint.placement)}",
                f"    <parent link={quoteattr(parent)}/>",
                f"    <child link={quoteattr(child)}/>",
                f'    <axis xyz="{_vec(joint.axis)}"/>',
                f'    <limit lower="{_num(joint.lower)}" upper="{_num(joint.upper)}"'
                f' effort="{_num(params.effort)}" velocity="{_num(params.velocity)}"/>',
                "  </joint>",
            ]
            parent = child
        lines += _link(leg.foot_frame, None)
        lines += [
            f'  <joint name="{label}_foot_fixed" type="fixed">',
            f"    {_origin(leg.foot)}",
            f"    <parent link={quoteattr(parent)}/>",
            f"    <child link={quoteattr(leg.foot_frame)}/>",
            "  </joint>",
        ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


#: The paper robot's URDF the toolkit loads: package data.
URDF_PATH = Path(__file__).resolve().parents[1] / "urdf" / "paper_quadruped.urdf"
_CHECKOUT = Path(__file__).resolve().parents[2]
#: Every copy of it: the package's, and in a source checkout (pyproject.toml beside the
#: package) the top-level urdf/ one, for readers of the repository.
URDF_COPIES = (URDF_PATH, *([_CHECKOUT / "urdf" / URDF_PATH.name] if (_CHECKOUT / "pyproject.toml").is_file() else []))


def write_urdf(params: PaperRobotParams = PARAMS) -> list[Path]:
    """Write every copy of the URDF (``URDF_COPIES``); InputError if one cannot be written."""
    text = urdf_text(params)
    for path in URDF_COPIES:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
        except OSError as e:
            raise InputError(f"cannot write '{path}' ({e.strerror}); expected a writable file") from e
    return list(URDF_COPIES)


def stale_urdf_copies(params: PaperRobotParams = PARAMS) -> list[Path]:
    """The copies of the URDF that are missing or differ from a fresh generation."""
    text = urdf_text(params)
    return [p for p in URDF_COPIES if not (p.is_file() and p.read_text() == text)]
