"""The paper's experiment: the gait plan, inverse kinematics along it, the reduced forward
dynamics, the rigid-contact physics check, and the comparison with the plan and its files."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "gait": (
        "CROUCH", "ZMP_WEIGHT", "gait_posture", "gait_feet", "Gait", "TROT", "WALK", "GAITS", "support_margin", "deepest_point",
        "Plan", "gait_plan",
    ),
    "ik": ("analytic_ik", "IK_POSITION_TOL", "numeric_ik", "gauss_newton"),
    "linearised_growth": ("PROJECTION_FD_STEP", "STEP", "linearised_departure", "linearised_growth_rate"),
    "validation_files": ("output_paths", "write_csv", "plot_br_hfe", "plot_physics_check", "summary_text"),
    "paper_experiment": (
        "ZERO_SIGNAL", "PD_KP_PER_KG", "PD_KD_PER_KG", "STABILITY_DT", "DEPARTURE_PCT", "SIGNALS", "Experiment", "joint_names",
        "percent_errors", "departure", "growth_rate", "static_stability", "pd_gains", "run_experiment", "report",
        "physics_check",
    ),
    "plan_ik": ("POLISH_STEPS", "IkTarget", "feet_ik", "ik_target", "ik_targets"),
    "rigid_contact": ("simulate_rigid",),
    "simulate": (
        "FALLEN_CLOSURE_M", "FALLEN_TRUNK_M", "RTOL", "TRUNCATION_RTOL_FACTOR", "IDENTITY_QUAT", "ReducedDynamics",
        "CasadiReducedDynamics", "BACKENDS",
        "reduced_dynamics", "IkTorques", "TorqueLaw", "Run", "simulate_reduced", "integrate_phases", "project_on_stance",
    ),
    "trunk_pose": ("pose_from_feet",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
