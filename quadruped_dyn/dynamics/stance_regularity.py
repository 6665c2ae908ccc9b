"""How far a stance set's reduced model is from its degenerate configurations: one scale-free
number per state, the same expression in Python (``ReducedModel``) and in the generated C
(docs/formulation.md §6.3, docs/reliability.md §7).

The reduced model divides by two kinds of determinants (``reduced_projection``):
* the GRF system of the paper's model: for three or four feet, the support polygon's
  fz system B = [1; y_i; -x_i] (trunk-frame xy of the stance feet) and, for three feet, the
  fy system whose pivot is 2 x_same - x_opp = 3 (x_same - xbar); for two feet, d = r_1 - r_2;
* the rigid-motion solve (K + e_phi e_phi^T with two feet): singular for 3-D collinear feet
  (implied by collinear xy) and, with two feet, for e_phi . d = 0 (the roll cannot fix the
  rotation about the foot-to-foot line: the front or back pair with zero pitch or roll).

``regularity`` (dimensionless, in [0, 1], 0 exactly at those configurations) multiplies one
factor per determinant, each the square of a relative singular value:
* 3 or 4 feet: 4 det(S) / tr(S)^2 of the feet's centred xy scatter S = sum rho_i rho_i^T, with
  det(S) = sum_{i<j} (rho_i x rho_j)^2 (Cauchy-Binet: accurate to round-off even when tiny),
  ~ 4 (sigma_2 / sigma_1)^2 of the centred xy positions;
* 3 feet also 3/2 rho_same,x^2 / tr(S): the fy system's pivot relative to the spread;
* 2 feet: (e_phi . d)^2 / (2 |e_phi|^2 (|r_1|^2 + |r_2|^2)): zero for coincident feet and for
  a roll axis perpendicular to the support line; and zero where the trunk is pitched to within
  arccos(TRUNK_PITCH_COS_MIN) (2 deg) of +-90 deg, cos(pitch)^2 = 1 / |e_phi|^2: there e_phi's
  tan(pitch) costs the generated forms more digits than REL_TOL_TERMS allows (``tolerances``).
A state is regular where regularity > REGULARITY_MIN (``tolerances``: RANK_RTOL squared, the
GRF rank test's relative singular value). NaN (e.g. the trunk pitched 90 deg: e_phi has
tan(pitch)) is never regular.
"""

from __future__ import annotations

import casadi as ca

from quadruped_dyn.model.leg import LEG_LABELS
from quadruped_dyn.model.stance import StanceSet
from quadruped_dyn.tolerances import TRUNK_PITCH_COS_MIN


def regularity(stance: StanceSet, r: list[ca.SX], e_phi: ca.SX | None) -> ca.SX:
    """The measure (module docstring) for stance-foot positions ``r`` (trunk frame, in the
    order of ``stance.feet``) and, for two feet, the roll-rate row ``e_phi`` (3,)."""
    if len(r) == 2:
        if e_phi is None:
            raise ValueError("two stance feet: regularity needs the roll-rate row e_phi")
        d, e2 = r[0] - r[1], ca.dot(e_phi, e_phi)
        layout = ca.dot(e_phi, d) ** 2 / (2 * e2 * (ca.dot(r[0], r[0]) + ca.dot(r[1], r[1])))
        # (cos(pitch)^2 = 1 / |e_phi|^2) > TRUNK_PITCH_COS_MIN^2: 1 or 0, times layout, so NaN stays NaN (an if_else
        # would make it 0: a zero quaternion would read as degenerate instead of non-finite)
        return layout * (e2 * TRUNK_PITCH_COS_MIN**2 < 1)
    xy = [ri[:2] for ri in r]
    centre = sum(xy[1:], xy[0]) / len(xy)
    rho = [p - centre for p in xy]
    spread = sum((ca.dot(p, p) for p in rho[1:]), ca.dot(rho[0], rho[0]))
    area2 = sum(((rho[i][0] * rho[j][1] - rho[i][1] * rho[j][0]) ** 2 for i in range(len(rho)) for j in range(i)),
                ca.SX(0))
    measure = 4 * area2 / spread**2
    if len(r) == 3:
        side = LEG_LABELS[stance.lifted[0]][1]
        (same,) = [j for j, i in enumerate(stance.feet) if LEG_LABELS[i][1] == side]
        measure = measure * (1.5 * rho[same][0] ** 2 / spread)
    return measure

