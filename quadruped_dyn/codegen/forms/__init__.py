"""The forms the generated C evaluates for speed, each equal to a ``dynamics`` algorithm (tested): one symbolic leg for
the legs that share its joint axes up to sign (``leg_template``), id_full, M's blocks and the feet leg by leg
(``leg_pieces``), did_full leg by leg (``did_full_pieces``), a stance's maps from its feet's positions
(``stance_maps``)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "leg_template": ("LegTemplate", "leg_templates", "LegPieces", "leg_signs", "template_of"),
    "leg_pieces": ("FOOT_PARTS", "TRUNK_MASS_BLOCKS", "LEG_MASS_BLOCKS", "mass_blocks", "trunk_head", "id_full_pieces",
                   "mass_matrix_pieces", "foot_kinematics", "foot_pieces"),
    "did_full_pieces": ("did_full_pieces", "did_full_by_leg"),
    "stance_maps": ("stance_maps",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
