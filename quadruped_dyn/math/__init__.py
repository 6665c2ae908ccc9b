"""Mathematics with no robot in it: rigid placements, rotations and cross-product matrices (for
numbers and symbols), spatial algebra and linear algebra on CasADi SX, and the one place where
numbers are compared (``compare``)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "compare": ("max_abs_error", "scale_of", "relative_error", "within"),
    "linalg": ("householder_qr", "least_squares", "min_norm"),
    "rigid": ("Placement", "LinkInertia", "skew", "axis_rotation"),
    "spatial": ("quat_to_rotation", "dm", "placement_rt", "motion_cross", "force_cross", "force_cross_bar", "spatial_inertia"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
