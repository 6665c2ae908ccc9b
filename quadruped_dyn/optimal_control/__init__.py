"""Trajectory optimisation on the symbolic reduced model: a periodic gait cycle by CasADi + IPOPT (docs/optimal_control.md)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "hermite": ("BASIS", "weights", "interpolate"),
    "trajectory_files": ("COORDINATES", "SAMPLES_PER_CYCLE", "output_paths", "coordinate_names", "per_node_residuals",
                         "plan_effort", "walk_feasibility", "report", "write_csv", "plot", "write_outputs"),
    "replay": ("REPLAY_DT", "OptimizedTrajectory", "Replay", "replay_rigid", "node_count"),
    "node": ("N_X", "ROLL", "NodeFunctions", "node_functions", "euler_rotation", "euler_quaternion", "com_position",
             "trunk_quaternion"),
    "solve": ("MAX_CONSTRAINT_VIOLATION", "IPOPT_OPTIONS", "HESSIANS", "Solution", "constraint_violation", "solve"),
    "blocks": ("derivative_functions",),
    "transcription": ("MU", "FZ_MIN_FRACTION", "MIN_COM_MARGIN_M", "CLEARANCE_FRACTION", "FOOTHOLD_BOUND_M",
                      "TRUNK_ANGLE_RAD", "TRUNK_HEIGHT_M", "W_EFFORT", "W_PLAN", "W_SMOOTH", "MIN_NODES_PER_PHASE",
                      "NODES_PER_PHASE", "MAX_STEP_FRACTION", "P_SCALE_M", "Options", "leg_length", "Piece",
                      "Transcription", "plan_coordinates", "transcribe", "stance_name"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
