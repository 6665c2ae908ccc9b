"""The paper's dynamics as CasADi graphs: leg kinematics, Newton-Euler, composite rigid bodies,
the GRF solve, the reduced model, the derivatives, and guarded numeric calls."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "crba": ("MASS_PARTS", "mass_matrix_crba", "leg_mass_parts", "assembled_mass_matrix", "generalized_gravity"),
    "derivatives": (
        "quaternion_tangent", "configuration_tangent", "tangent_jacobian", "cholesky_solve",
        "FullDerivatives", "full_derivatives", "rotation_jacobian", "ReducedDerivatives", "reduced_derivatives",
        "grf_derivatives",
    ),
    "formulas": (
        "DISPLAY_DIGITS", "to_sympy", "rounded", "Formula", "paper_formulas", "TermSize", "sparsity_pattern", "term_functions",
        "term_sizes", "shapes",
    ),
    "grf": (
        "contact_map", "min_norm_solve", "solve_lambda", "GrfSolution", "GrfSolve", "GrfExpressions", "grf_expressions",
        "grf_solves", "grf_solve", "friction_cone", "check_friction_coefficient",
    ),
    "guarded": ("check_quaternion", "check_inputs", "check_outputs", "guarded_call", "GuardedFunction", "guard_fields"),
    "kinematics": ("joint_frames", "foot_position", "LegKinematics", "leg_kinematics", "robot_kinematics"),
    "newton_euler": (
        "LegForces", "leg_newton_euler", "hip_reaction_split", "gravity_in_trunk", "trunk_acceleration",
        "inverse_dynamics", "coriolis_matrix", "FullDynamics",
        "full_dynamics",
    ),
    "reduced": (
        "REDUCED_KINDS", "MAX_COND_M_R", "roll_rate_row", "roll_rate_row_dot", "reduced_inverse_dynamics", "ReducedModel",
        "solve_forward_dynamics", "reduced_model",
    ),
    "reduced_projection": ("rigid_motion", "ReducedProjection"),
    "rnea_derivatives": ("LEG_PARTS", "leg_rows", "rows_to_derivatives", "rnea_tangent_derivatives"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
