"""Pinocchio ground truth, in the project's coordinates (see ``state`` for conventions).

Every function takes the project's q (19,), v (18,), a = vdot (18,) and returns results in
project order (6 body + 12 joints in FL, FR, BL, BR x HAA, HFE, KFE order), converting to
and from Pinocchio's own order (``Robot.idx_q`` / ``idx_v``) explicitly. Nothing here calls
the project's CasADi code: it is an independent implementation of the same quantities.

One concept per module: ``coordinates`` (the conversions), ``whole_body`` (RNEA, M, C + G),
``foot_terms`` (foot kinematics, rigid contacts), ``force_distribution`` (the GRF solve),
``reduced_coordinates`` (the reduced model), ``analytical_derivatives``. ``PinocchioReference``
is all of them on one robot.
"""

from __future__ import annotations

from quadruped_dyn.references.pinocchio.analytical_derivatives import PinocchioDerivatives
from quadruped_dyn.references.pinocchio.coordinates import LWA
from quadruped_dyn.references.pinocchio.force_distribution import GrfReference, min_norm_solution
from quadruped_dyn.references.pinocchio.reduced_coordinates import PinocchioReducedCoordinates, roll_rate_row, roll_rates

__all__ = ["LWA", "GrfReference", "PinocchioDerivatives", "PinocchioReference", "min_norm_solution", "roll_rate_row",
           "roll_rates"]


class PinocchioReference(PinocchioReducedCoordinates):
    """Pinocchio's terms of one robot in the project's coordinates: conversions, whole-body
    dynamics, feet and contacts, the GRF solve and the reduced model."""
