"""One validation pass over a URDF before anything is built from it (docs/reliability.md §2).

Pinocchio's parser accepts numbers that make every later answer wrong (a zero joint axis,
NaN or 1e300 masses, lower > upper limits, inertias no body can have) and ignores ``mimic``.
``validate_urdf`` reads the XML itself and rejects, with an ``InputError`` naming the element
and the value:

- XML that is not a URDF ``<robot>``, or that declares entities (URDF parsers do not expand them);
  joints that do not make a tree (a link the child of two
  joints, a loop), or a tree deeper than ``MAX_URDF_DEPTH`` (Pinocchio's parser recurses per level
  and overflows the stack);
- numbers that are not numbers, not finite, or absurd (beyond ``MAX_LENGTH_M``, ``MAX_MASS_KG``,
  ``MAX_ANGLE_RAD``) in any origin, axis, limit, mass or inertia;
- a zero joint axis; a joint with lower > upper limits;
- ``mimic`` joints (a leg needs three independent joints); ``floating`` or ``planar`` joints
  (a leg hangs from the trunk by revolute joints);
- a negative mass; an inertia that is not positive semi-definite or breaks the triangle
  inequality of its principal moments (A + B >= C): rejected for a link a joint moves (a leg
  link), returned as a warning for a link attached by a fixed joint (a camera on the trunk, a
  dummy foot): Pinocchio merges it into its parent's body, and ``robot.load_robot`` checks
  the merged bodies of the trunk and the legs.

``continuous`` joints are legal: their limits are not read.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from xml.parsers import expat

import numpy as np

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable
from quadruped_dyn.tolerances import INERTIA_REL_TOL

#: Larger than any legged robot by two orders of magnitude: a length, mass or angle beyond
#: these is a units or typing mistake, and squares of such numbers lose all precision.
MAX_LENGTH_M = 100.0
MAX_MASS_KG = 1e5
MAX_ANGLE_RAD = 100.0
MAX_INERTIA_KG_M2 = MAX_MASS_KG * MAX_LENGTH_M**2

#: An axis shorter than this is no direction anyone wrote; Pinocchio would normalise noise.
MIN_AXIS_NORM = 1e-6

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")


def _numbers(where: str, attribute: str, text: str | None, count: int, bound: float, default: str | None = None) -> np.ndarray:
    """``count`` finite numbers of magnitude <= bound from an attribute's text, or an InputError."""
    text = default if text is None else text
    if text is None:
        raise InputError(f"{where} has no {attribute}; expected {count} number(s)")
    try:
        values = np.array([float(x) for x in text.split()])
    except ValueError as e:
        raise InputError(f'{where} has {attribute}="{text}"; expected {count} number(s)') from e
    if values.size != count:
        raise InputError(f'{where} has {attribute}="{text}"; expected {count} number(s)')
    if not np.all(np.isfinite(values)):
        raise InputError(f'{where} has {attribute}="{text}"; expected finite numbers')
    if np.any(np.abs(values) > bound):
        raise InputError(f'{where} has {attribute}="{text}"; expected magnitudes <= {bound:g}')
    return values


def _origin(where: str, element: ET.Element | None) -> None:
    origin = None if element is None else element.find("origin")
    if origin is not None:
        _numbers(f"{where} <origin>", "xyz", origin.get("xyz"), 3, MAX_LENGTH_M, default="0 0 0")
        _numbers(f"{where} <origin>", "rpy", origin.get("rpy"), 3, MAX_ANGLE_RAD, default="0 0 0")


def _joint(joint: ET.Element) -> None:
    name = joint.get("name")
    kind = joint.get("type")
    where = f"joint '{name}'"
    if kind not in JOINT_TYPES:
        raise InputError(f"{where} has type '{kind}'; expected revolute or continuous joints in the legs, fixed elsewhere")
    _origin(where, joint)
    if kind == "fixed":
        return
    if joint.find("mimic") is not None:
        raise InputError(f"{where} has a <mimic> element (it copies joint '{joint.find('mimic').get('joint')}'); "  # type: ignore[union-attr]
                         "expected a leg of 3 independent joints")
    axis_element = joint.find("axis")
    axis = _numbers(f"{where} <axis>", "xyz", None if axis_element is None else axis_element.get("xyz"), 3, MAX_LENGTH_M,
                    default="1 0 0")
    if not np.linalg.norm(axis) >= MIN_AXIS_NORM:
        raise InputError(f'{where} has <axis xyz="{axis_element.get("xyz")}">; expected a nonzero direction')  # type: ignore[union-attr]
    limit = joint.find("limit")
    if kind != "continuous" and limit is not None:
        bound = MAX_ANGLE_RAD if kind == "revolute" else MAX_LENGTH_M
        lower = _numbers(f"{where} <limit>", "lower", limit.get("lower"), 1, bound, default="0")[0]
        upper = _numbers(f"{where} <limit>", "upper", limit.get("upper"), 1, bound, default="0")[0]
        if lower > upper:
            raise InputError(f'{where} has <limit lower="{limit.get("lower")}" upper="{limit.get("upper")}">; '
                             "expected lower <= upper")


def inertia_problem(moments: np.ndarray) -> str | None:
    """What makes principal moments (ascending, kg m^2) unphysical, or None."""
    slack = INERTIA_REL_TOL * max(float(np.abs(moments).max()), math.ulp(0.0))
    if moments[0] < -slack:
        return "is not positive semi-definite"
    if moments[0] + moments[1] < moments[2] - slack:
        return "breaks the triangle inequality A + B >= C"
    return None


def _inertial(link: str, inertial: ET.Element, moved: bool, warnings: list[str]) -> None:
    where = f"link '{link}' <inertial>"
    _origin(where, inertial)
    mass_element = inertial.find("mass")
    if mass_element is None:
        raise InputError(f"{where} has no <mass>; expected <mass value=...> in kg")
    (mass,) = _numbers(f"{where} <mass>", "value", mass_element.get("value"), 1, MAX_MASS_KG)
    if mass < 0.0:
        raise InputError(f'{where} has <mass value="{mass_element.get("value")}">; expected a mass >= 0 kg')
    element = inertial.find("inertia")
    if element is None:
        return
    names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    xx, xy, xz, yy, yz, zz = (
        _numbers(f"{where} <inertia>", n, element.get(n), 1, MAX_INERTIA_KG_M2, default="0")[0] for n in names
    )
    moments = np.linalg.eigvalsh(np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]))
    problem = inertia_problem(moments)
    if problem is None:
        return
    message = (f"{where} <inertia> {problem}: principal moments {np.array2string(moments, precision=3)} kg m^2; "
               "expected a physical rigid body")
    if moved:
        raise InputError(message)
    warnings.append(message + " (a fixed link: warned; the body it is merged into is checked)")


#: Far beyond any legged robot's URDF (example-robot-data's largest is ~0.2 MB with ~100 links;
#: meshes live in separate files): Pinocchio's parse grows roughly quadratically with the number of
#: links (a 52 MB file with 377k links does not finish in minutes), so larger files are refused
#: before any parsing.
MAX_URDF_BYTES = 10_000_000
MAX_URDF_LINKS = 5_000


def check_urdf_size(path: Path, data: bytes | None, size: int | None = None) -> None:
    """InputError if the URDF's bytes (``size`` of them; ``data`` when read) exceed MAX_URDF_BYTES
    or it declares more than MAX_URDF_LINKS links or joints (counted in the raw bytes, before
    parsing)."""
    size = len(data) if size is None and data is not None else size
    if size is not None and size > MAX_URDF_BYTES:
        raise InputError(f"'{printable(path.name)}' is {size / 1e6:.1f} MB; expected a URDF of at most "
                         f"{MAX_URDF_BYTES / 1e6:g} MB (a legged robot's is well under 1 MB)")
    for tag in (b"<link", b"<joint"):
        count = data.count(tag) if data is not None else 0
        if count > MAX_URDF_LINKS:
            raise InputError(f"'{printable(path.name)}' has {count} {tag.decode()}> elements; expected at most "
                             f"{MAX_URDF_LINKS} (a quadruped has a few dozen)")


#: Pinocchio's URDF parser recurses once per link from the root down, with ~2 kB of stack a level: a chain of
#: 4,000 links (fixed joints, within MAX_URDF_LINKS) overflowed the 8 MB main-thread stack, SIGSEGV (measured
#: with Pinocchio 4.1; 3,500 passed). A quadruped's tree is a few links deep (trunk, 3 leg links, foot, sensors).
MAX_URDF_DEPTH = 500


def tree_depth(joints: list[ET.Element]) -> int:
    """The number of joints on the longest path from a root link down the joints' parent -> child
    tree (iterative: the tree may be deep). InputError if the joints do not make a tree: a link the
    child of two joints, or a loop (urdfdom's own messages for these name a symptom, e.g. '0 joint chains')."""
    parent: dict[str | None, str | None] = {}
    via: dict[str | None, str | None] = {}
    for joint in joints:
        p, c = joint.find("parent"), joint.find("child")
        if p is not None and c is not None:
            child = c.get("link")
            if child in parent:
                raise InputError(f"link '{printable(str(child))}' is the child of joints '{printable(str(via[child]))}' and "
                                 f"'{printable(str(joint.get('name')))}'; expected a tree: each link the child of one joint")
            parent[child], via[child] = p.get("link"), joint.get("name")
    depth: dict[str | None, int] = {}
    for start in parent:
        path: list[str | None] = []
        on_path: set[str | None] = set()
        node = start
        while node in parent and node not in depth and node not in on_path:
            path.append(node)
            on_path.add(node)
            node = parent[node]
        if node in on_path:
            raise InputError(f"the joints make a loop through link '{printable(str(node))}'; expected a tree of links "
                             "hanging from one root link")
        below = depth.get(node, 0)
        for k, link in enumerate(reversed(path), start=1):
            depth[link] = below + k
    return max(depth.values(), default=0)


def declared_entities(data: bytes) -> list[str]:
    """The names of the entities a well-formed XML document declares in its DTD (``<!ENTITY m "2.0">``)."""
    names: list[str] = []
    parser = expat.ParserCreate()
    parser.EntityDeclHandler = lambda name, *rest: names.append(name)
    parser.Parse(data, True)
    return names


def validate_urdf(path: Path, data: bytes | None = None) -> list[str]:
    """Validate the URDF at ``path`` (whose bytes are ``data`` when given: what will be parsed);
    returns warnings (one line each), raises InputError."""
    data = Path(path).read_bytes() if data is None else data
    check_urdf_size(Path(path), data)
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        raise InputError(f"'{path}' is not well-formed XML ({e}); expected a URDF file") from e
    if root.tag != "robot":
        raise InputError(f"'{path}' has root element <{root.tag}>; expected a URDF <robot>")
    entities = declared_entities(data)
    if entities:  # Python's parser expands them; Pinocchio's, MuJoCo's and iDynTree's read the file's text as written
        raise InputError(f"'{printable(Path(path).name)}' declares the XML entity '{printable(entities[0])}'; expected a URDF "
                         "without <!ENTITY> declarations (URDF parsers do not expand them: each library would read "
                         "another robot)")
    joints = root.findall("joint")
    depth = tree_depth(joints)
    if depth > MAX_URDF_DEPTH:
        raise InputError(f"'{printable(Path(path).name)}' has a chain of {depth} joints from its root link; expected at most "
                         f"{MAX_URDF_DEPTH} (a quadruped's is a few links deep)")
    for joint in joints:
        _joint(joint)
    moved = {c.get("link") for j in joints if j.get("type") != "fixed" for c in j.findall("child")}
    warnings: list[str] = []
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is not None:
            name = link.get("name", "?")
            _inertial(name, inertial, name in moved, warnings)
    return warnings
