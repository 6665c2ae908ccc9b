"""Pinocchio's whole-body terms in the project's coordinates: RNEA, M, C + G, G and C."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.references.pinocchio.coordinates import PinocchioCoordinates


class PinocchioWholeBody(PinocchioCoordinates):
    """Full-coordinate dynamics terms (18 rows: body wrench in the body frame, then joints)."""

    def rnea(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """Generalised forces (18,): body wrench (force, moment; body frame) and joint torques."""
        return self.project_v(pin.rnea(self.model, self.data, self.pin_q(q), self.pin_v(v), self.pin_v(a, "a")))

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M (18, 18) from crba; the Python binding returns it symmetrised."""
        return self.project_matrix(pin.crba(self.model, self.data, self.pin_q(q)))

    def nonlinear_effects(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, v) + G(q) (18,)."""
        return self.project_v(pin.nonLinearEffects(self.model, self.data, self.pin_q(q), self.pin_v(v)))

    def gravity(self, q: np.ndarray) -> np.ndarray:
        """G(q) (18,)."""
        return self.project_v(pin.computeGeneralizedGravity(self.model, self.data, self.pin_q(q)))

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Pinocchio's Coriolis matrix C(q, v) (18, 18): C v = nle - G, Mdot - 2C skew."""
        return self.project_matrix(pin.computeCoriolisMatrix(self.model, self.data, self.pin_q(q), self.pin_v(v)))
