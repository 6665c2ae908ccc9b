"""Copies of a URDF that another library accepts, and the inertia checks that decide them.

Other libraries read a URDF differently from Pinocchio (``cross_library``). To compare like
with like, the toolkit writes edited copies of the URDF text:

* ``strip_geometry``: drop ``<visual>`` (and ``<collision>``) elements; dynamics never use
  them, and their meshes (``package://`` paths, .dae files) are not loadable everywhere.
* ``merge_inertial``: move a link's ``<inertial>`` into the link it is welded to by a
  ``fixed`` joint. Pinocchio merges welded links anyway, so the dynamics are unchanged
  (to round-off); a library that checks each link's inertia separately then accepts a
  physically impossible part (a 1e-6 dummy, a camera breaking A + B >= C) whose sum is fine.
* ``balance_inertia``: MuJoCo's ``balanceinertia`` rule (principal moments that break
  A + B >= C are all set to their mean), written into the copy, so Pinocchio can evaluate
  the model MuJoCo actually uses.

Inertias are in each link's frame: ``<inertial><origin xyz rpy>`` places the CoM and the
axes of ``<inertia>``; the merged inertial is written with rpy = 0 (link axes), 17 digits.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError

_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")


def parse_urdf_text(text: str) -> ET.Element:
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise InputError(f"URDF is not well-formed XML ({e}); expected a URDF file") from e
    return root


def _floats(element: ET.Element | None, attr: str, default: str) -> np.ndarray:
    text = default if element is None else element.get(attr, default)
    return np.array([float(x) for x in text.split()])


def _pose(origin: ET.Element | None) -> pin.SE3:
    """The SE3 of an ``<origin xyz rpy>`` (identity when absent)."""
    rpy = _floats(origin, "rpy", "0 0 0")
    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), _floats(origin, "xyz", "0 0 0"))


def link_inertia(link: ET.Element) -> pin.Inertia | None:
    """The link's spatial inertia in its own frame, or None when it has no ``<inertial>``."""
    inertial = link.find("inertial")
    if inertial is None:
        return None
    mass_el, inertia_el = inertial.find("mass"), inertial.find("inertia")
    mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
    ixx, ixy, ixz, iyy, iyz, izz = (float(inertia_el.get(k, "0")) if inertia_el is not None else 0.0 for k in _INERTIA_KEYS)
    I_axes = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    pose = _pose(inertial.find("origin"))
    return pin.Inertia(mass, pose.translation, pose.rotation @ I_axes @ pose.rotation.T)


def _write_inertial(link: ET.Element, Y: pin.Inertia) -> None:
    old = link.find("inertial")
    if old is not None:
        link.remove(old)
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=" ".join(repr(float(x)) for x in Y.lever), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(Y.mass)))
    I = np.array(Y.inertia)
    ET.SubElement(inertial, "inertia", {k: repr(float(I[i, j])) for k, (i, j) in
                                        zip(_INERTIA_KEYS, [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)])})


NOT_POSITIVE_DEFINITE = "not positive definite"
BREAKS_TRIANGLE = "breaks A + B >= C"


@dataclass(frozen=True)
class InertiaProblem:
    link: str
    kind: str  # NOT_POSITIVE_DEFINITE or BREAKS_TRIANGLE
    values: str  # the principal moments, kg m^2

    def __str__(self) -> str:
        return f"'{self.link}' {self.kind} (principal moments {self.values} kg m^2)"


def inertia_problems(root: ET.Element) -> list[InertiaProblem]:
    """Links whose own ``<inertial>`` is not physical: inertia not positive definite, or
    principal moments breaking A + B >= C (MuJoCo refuses both). Links without one, or with a
    zero inertia matrix (a massless link), are fine."""
    problems = []
    for link in root.findall("link"):
        Y = link_inertia(link)
        if Y is None or not np.any(np.array(Y.inertia)):
            continue
        eig = np.linalg.eigvalsh(np.array(Y.inertia))  # ascending
        values = np.array2string(eig, precision=3)
        if not eig[0] > 0.0:
            problems.append(InertiaProblem(link.get("name", "?"), NOT_POSITIVE_DEFINITE, values))
        elif eig[0] + eig[1] < eig[2]:
            problems.append(InertiaProblem(link.get("name", "?"), BREAKS_TRIANGLE, values))
    return problems


def strip_geometry(root: ET.Element, keep_primitive_collisions: bool = False) -> int:
    """Remove ``<visual>`` and ``<collision>`` elements in place (with ``keep_primitive_collisions``,
    collisions of boxes, cylinders and spheres stay). Returns how many mesh collisions were removed."""
    removed_meshes = 0
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
        for collision in link.findall("collision"):
            is_mesh = collision.find("geometry/mesh") is not None
            removed_meshes += int(is_mesh)
            if not keep_primitive_collisions or is_mesh:
                link.remove(collision)
    return removed_meshes


def fixed_neighbour(root: ET.Element, link_name: str) -> tuple[str, pin.SE3] | None:
    """A link welded to ``link_name`` by a fixed joint (its parent first, else its first child),
    with the placement of ``link_name``'s frame in that link's frame; None if there is none."""
    fixed = [j for j in root.findall("joint") if j.get("type") == "fixed"]
    for j in fixed:
        parent, child = j.find("parent"), j.find("child")
        if child is not None and parent is not None and child.get("link") == link_name:
            return parent.get("link", ""), _pose(j.find("origin"))
    for j in fixed:
        parent, child = j.find("parent"), j.find("child")
        if parent is not None and child is not None and parent.get("link") == link_name:
            return child.get("link", ""), _pose(j.find("origin")).inverse()
    return None


def merge_inertial(root: ET.Element, link_name: str) -> str | None:
    """Move ``link_name``'s inertial into its fixed neighbour (in place); returns the
    neighbour's name, or None (nothing changed) when the link is not welded to another."""
    found = fixed_neighbour(root, link_name)
    links = {link.get("name"): link for link in root.findall("link")}
    if found is None or found[0] not in links:
        return None
    neighbour, placement = found
    Y = link_inertia(links[link_name])
    if Y is None:
        return neighbour
    Y_other = link_inertia(links[neighbour])
    merged = placement.act(Y) if Y_other is None else Y_other + placement.act(Y)
    _write_inertial(links[neighbour], merged)
    drop_inertial(root, link_name)
    return neighbour


def set_inertial(root: ET.Element, link_name: str, Y: pin.Inertia) -> None:
    """Replace the link's ``<inertial>`` by ``Y`` (in the link's frame; in place)."""
    _write_inertial(next(x for x in root.findall("link") if x.get("name") == link_name), Y)


def drop_inertial(root: ET.Element, link_name: str) -> None:
    """Remove the link's ``<inertial>`` (in place)."""
    link = next(x for x in root.findall("link") if x.get("name") == link_name)
    inertial = link.find("inertial")
    if inertial is not None:
        link.remove(inertial)


def balance_inertia(root: ET.Element, link_name: str) -> None:
    """MuJoCo's ``balanceinertia``: the link's principal moments all become their mean, i.e. its
    inertia about the CoM becomes (trace / 3) * identity (in place)."""
    link = next(x for x in root.findall("link") if x.get("name") == link_name)
    Y = link_inertia(link)
    if Y is None:
        return
    _write_inertial(link, pin.Inertia(Y.mass, Y.lever, np.trace(Y.inertia) / 3.0 * np.eye(3)))


def to_text(root: ET.Element) -> str:
    return ET.tostring(root, encoding="unicode")


def scale_urdf(root: ET.Element, mass: float = 1.0, length: float = 1.0, inertia: float = 1.0) -> None:
    """A design variant, in place: every link's mass times ``mass``; every length times ``length``
    (joint, inertial, visual and collision origins, sphere and cylinder radii and lengths, box
    sizes), so each rotational inertia times ``mass * length**2`` (a body scaled geometrically);
    then each rotational inertia times ``inertia`` as well. Joint limits and efforts stay as
    written. InputError unless each factor is a finite number > 0."""
    for what, factor in (("mass", mass), ("length", length), ("inertia", inertia)):
        if not (isinstance(factor, (int, float)) and not isinstance(factor, bool) and np.isfinite(factor) and factor > 0):
            raise InputError(f"{what} scale {factor!r}; expected a finite number > 0")
    for origin in root.iter("origin"):
        if "xyz" in origin.attrib:
            origin.set("xyz", " ".join(repr(float(x) * length) for x in origin.get("xyz", "").split()))
    for tag, attrs in (("sphere", ("radius",)), ("cylinder", ("radius", "length")), ("capsule", ("radius", "length"))):
        for shape in root.iter(tag):
            for attr in attrs:
                if attr in shape.attrib:
                    shape.set(attr, repr(float(shape.get(attr, "0")) * length))
    for box in root.iter("box"):
        if "size" in box.attrib:
            box.set("size", " ".join(repr(float(x) * length) for x in box.get("size", "").split()))
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            continue
        mass_el, inertia_el = inertial.find("mass"), inertial.find("inertia")
        if mass_el is not None:
            mass_el.set("value", repr(float(mass_el.get("value", "0")) * mass))
        if inertia_el is not None:
            for key in _INERTIA_KEYS:
                inertia_el.set(key, repr(float(inertia_el.get(key, "0")) * mass * length**2 * inertia))
