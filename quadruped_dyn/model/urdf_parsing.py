"""A URDF's bytes read, validated and parsed by Pinocchio into a free-flyer model, without armature, placements
snapped (``SNAP_TOL``)."""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from quadruped_dyn.errors import InputError, UrdfWarning
from quadruped_dyn.files.names import printable
from quadruped_dyn.model.stderr_capture import StderrCapture
from quadruped_dyn.model.urdf_edit import strip_geometry, to_text
from quadruped_dyn.model.urdf_rules import check_urdf_size, validate_urdf

#: Placement entries within this of 0 or +-1 are snapped exactly. URDF text carries rotations
#: as rpy angles, so cos(pi/2) arrives as ~6e-17 instead of 0, or as 4.9e-12 where pi/2 is
#: written with ten digits (hyq, anymal_c: 1.5707963268); snapping keeps structural zeros zero
#: (smaller symbolic graphs, smaller C: with the 4.9e-12 kept, every joint axis of hyq is tilted
#: and its generated M costs 2.7x) and moves nothing by more than 1e-9 m/rad.
SNAP_TOL = 1e-9


def _snap(M: pin.SE3) -> pin.SE3:
    def snap(x: np.ndarray) -> np.ndarray:
        x = np.array(x)
        for target in (0.0, 1.0, -1.0):
            x[np.abs(x - target) < SNAP_TOL] = target
        return x

    return pin.SE3(snap(M.rotation), snap(M.translation))


def parse_urdf(path: Path, data: bytes) -> pin.Model:
    """Pinocchio's free-flyer model of the URDF whose bytes are ``data``, validated first. Pinocchio parses
    the XML the validation read (any encoding, as Unicode), without the geometry and
    materials (the dynamics never read them). Its parser (urdfdom) drops an element it cannot read, e.g. a whole
    ``<inertial>`` for ``<mass value="2.0 ">``, says so on stderr and returns the model anyway: that is an
    InputError too, not a model without the mass."""
    for message in validate_urdf(path, data):
        warnings.warn(f"{printable(path.name)}: {message}", UrdfWarning, stacklevel=2)
    root = ET.fromstring(data)  # well-formed: validate_urdf parsed it
    strip_geometry(root)
    for material in root.findall("material"):  # the visuals' colours: urdfdom's complaints about one are harmless
        root.remove(material)
    capture = StderrCapture()
    try:
        with capture:
            model = pin.buildModelFromXML(to_text(root), pin.JointModelFreeFlyer())
    except Exception as e:  # Pinocchio raises plain ValueError/RuntimeError with the parser's text
        said = [line.strip() for line in capture.text.splitlines() if line.strip()]
        first = (said[:1] or str(e).strip().splitlines()[:1] or ["no reason given"])[0]
        reason = first.removeprefix("Error:").strip().rstrip(".")  # our sentence goes on after it
        raise InputError(f"Pinocchio cannot parse '{printable(path)}': {printable(reason)}; expected one tree of links "
                         "joined by joints: a trunk with four legs of three revolute joints each") from e
    errors = [line.strip() for line in capture.text.splitlines() if line.strip().startswith("Error:")]
    if errors:
        reasons = "; then ".join(e.removeprefix("Error:").strip().rstrip(".") for e in errors[:2])
        raise InputError(f"Pinocchio's parser skipped part of '{printable(path)}': {printable(reasons)}; expected every "
                         "element readable (numbers without stray characters or spaces inside the quotes)")
    return model


def read_urdf(path: Path) -> bytes:
    """The URDF's bytes, its size checked before it is read."""
    try:
        check_urdf_size(path, None, path.stat().st_size)  # before reading a huge file
        data = path.read_bytes()
    except OSError as e:
        raise InputError(f"cannot read '{printable(path)}' ({e.strerror}); expected a readable URDF file") from e
    return data


def prepared_model(path: Path, data: bytes) -> pin.Model:
    """Pinocchio's free-flyer model of the validated URDF (its bytes ``data``), without armature,
    placements snapped."""
    model = parse_urdf(path, data)
    model.armature[:] = 0.0
    for j in range(1, model.njoints):
        model.jointPlacements[j] = _snap(model.jointPlacements[j])
    for frame in model.frames:
        frame.placement = _snap(frame.placement)
    return model
