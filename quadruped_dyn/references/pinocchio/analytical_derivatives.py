"""Pinocchio's analytical derivatives of RNEA and ABA in the project's order."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from quadruped_dyn.references.pinocchio.coordinates import PinocchioCoordinates


class PinocchioDerivatives:
    """Pinocchio's analytical derivatives (Carpentier & Mansard 2018) in the project's order.

    d/dq is along ``pinocchio.integrate(model, q, dq)`` (a body-frame increment of the free
    flyer, dq (18,)); rows and columns are permuted from Pinocchio's ``idx_v`` order to the
    project's (6 trunk + FL, FR, BL, BR x HAA, HFE, KFE). Symmetric matrices (M, M^-1), of
    which Pinocchio fills the upper triangle, are returned symmetrised."""

    def __init__(self, reference: PinocchioCoordinates) -> None:
        self.ref = reference
        self.model = reference.model
        self.data = self.model.createData()

    def _m(self, X: np.ndarray) -> np.ndarray:
        return self.ref.project_matrix(np.array(X))

    @staticmethod
    def _sym(X: np.ndarray) -> np.ndarray:
        U = np.triu(X)
        return U + np.triu(X, 1).T

    def rnea_derivatives(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(dtau_dq, dtau_dv, M) of rnea(q, v, a) by ``computeRNEADerivatives``."""
        r = self.ref
        dq, dv, da = pin.computeRNEADerivatives(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(a, "a"))
        return self._m(dq), self._m(dv), self._m(self._sym(np.array(da)))

    def aba_derivatives(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(da_dq, da_dv, M^-1) of aba(q, v, tau) by ``computeABADerivatives``; tau (18,) = (trunk
        wrench, body frame; joint torques)."""
        r = self.ref
        dq, dv, dtau = pin.computeABADerivatives(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(tau, "tau"))
        return self._m(dq), self._m(dv), self._m(self._sym(np.array(dtau)))

    def aba(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        r = self.ref
        return r.project_v(pin.aba(self.model, self.data, r.pin_q(q), r.pin_v(v), r.pin_v(tau, "tau")))

    def integrate(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """``pinocchio.integrate(model, q, dq)`` in the project's coordinates (dq in project order)."""
        r = self.ref
        return r.project_q(pin.integrate(self.model, r.pin_q(q), r.pin_v(dq, "dq")))
