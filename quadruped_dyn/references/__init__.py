"""Other libraries as references, behind one interface in the project's conventions: Pinocchio
(the ground truth, and as its users load a URDF), MuJoCo, iDynTree, Drake and adam. Nothing in
``dynamics`` imports them."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "adam": ("AdamRefusal", "load_kin_dyn", "AdamReference"),
    "drake": ("DrakeRefusal", "load_plant", "DrakeReference"),
    "idyntree": ("IDynTreeRefusal", "load_model", "IDynTreeReference"),
    "interface": ("TERMS", "Dynamics", "computed_terms", "terms_at", "max_rel_errors", "PinocchioTerms", "pinocchio_of",
                  "ModelChange", "Prepared"),
    "mujoco": ("MuJoCoRefusal", "MuJoCoOptions", "compile_model", "MuJoCoReference"),
    "pinocchio": ("LWA", "GrfReference", "PinocchioReference", "roll_rate_row", "roll_rates", "PinocchioDerivatives"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
