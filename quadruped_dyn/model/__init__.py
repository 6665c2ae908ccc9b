"""The robot as data: legs, the URDF loader and its rules, the state conventions, stance sets,
the paper's DH robot."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "leg": ("LEG_LABELS", "JOINT_ROLES", "BR_HFE", "LegJoint", "Leg"),
    "leg_frames": ("axis_aligned",),
    "paper_robot": (
        "DHRow", "PaperRobotParams", "PARAMS", "dh_table", "R_B0", "STANDING_Q", "hip_position", "link_inertias",
        "trunk_inertia", "dh_leg", "DH_MATCH_TOL", "dh_form", "LINK_NAMES", "urdf_text", "URDF_PATH", "URDF_COPIES",
        "write_urdf", "stale_urdf_copies",
    ),
    "actuator_limits": ("ACTUATOR_LIMITS", "actuator_limit"),
    "foot_frames": ("FOOT_WORDS", "NOT_FOOT_WORDS", "foot_frame", "foot_frame_names"),
    "registry": ("ROBOT_NAMES", "example_robot_data_dir", "robot_path"),
    "robot": ("Robot", "check_robot", "load_robot"),
    "robot_identity": ("builtin_name", "UrdfSource", "urdf_source"),
    "urdf_parsing": ("SNAP_TOL",),
    "robot_summary": ("robot_info",),
    "stance": ("GRF_MODELS", "StanceSet", "STANCE_SETS", "stance_set"),
    "state": (
        "GRAVITY_W", "NQ_FULL", "NV_FULL", "full_q", "rotation", "spatial_from_classical", "classical_from_spatial",
        "check_array", "FullState", "random_state",
    ),
    "urdf_edit": (
        "parse_urdf_text", "link_inertia", "NOT_POSITIVE_DEFINITE", "BREAKS_TRIANGLE", "InertiaProblem", "inertia_problems",
        "strip_geometry", "fixed_neighbour", "merge_inertial", "drop_inertial", "balance_inertia", "to_text",
    ),
    "urdf_rules": (
        "MAX_LENGTH_M", "MAX_MASS_KG", "MAX_ANGLE_RAD", "MAX_INERTIA_KG_M2", "MIN_AXIS_NORM", "JOINT_TYPES", "inertia_problem",
        "validate_urdf",
    ),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
