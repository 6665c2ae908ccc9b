"""Closed loop: the generated C controls a quadruped simulated by MuJoCo (docs/closed_loop.md):
the plant, the plan, the controllers (the whole-body QP and its MPC among them), the loop, its
measures, its files, one study of a robot and gait.

MuJoCo picks its OpenGL backend when it is first imported: offscreen rendering (the animation)
works headless with EGL (Debian ``libegl1``), so that is the default unless MUJOCO_GL is set.
Everything here needs MuJoCo (the ``xlib`` extra).
"""

import os

from quadruped_dyn.exports import lazy_exports

os.environ.setdefault("MUJOCO_GL", "egl")

_MODULES: dict[str, tuple[str, ...]] = {
    "ground": ("MAX_GROUND_STEP_M", "GROUND_HALF_SIZE_M"),
    "plant": ("DEFAULT_FOOT_RADIUS", "PUSH_DURATION_S", "PlantOptions", "Command", "Measurement", "Plant", "build_plant"),
    "plan": ("TARGET_KNOT_S", "Target", "joint_inertia", "target_cycle"),
    "controllers": ("KP_PER_KG", "KD_PER_KG", "CT_OMEGA_STANCE", "CT_OMEGA_SWING", "CT_ZETA", "LANDING_DROP_M",
                    "Gains", "GeneratedC",
                    "CONTROLLERS", "parse_controllers", "make_controller", "levelled", "model_stance", "measured_state"),
    "wbc": ("WholeBodyQp", "QpInfeasible", "leg_odometry", "friction_rows"),
    "mpc": ("MpcWbc", "rigid_body", "continuous_model"),
    "run": ("FALL_HEIGHT_FRACTION", "FALL_TILT_RAD", "LoopOptions", "Trace", "settled_state", "run_controller"),
    "measures": ("tracking", "trunk_drift", "foot_slip", "grf_comparison", "saturation", "compute_time", "summary"),
    "study_files": ("output_paths", "write_all", "best_controller", "rendering_available", "animate"),
    "closed_loop": ("ClosedLoop", "parse_gait", "prepare", "run_all"),
    "perturbations": ("Perturbation", "PerturbedPlant", "perturbed"),
    "thresholds": ("PERSIST_S", "UNLOADED_FRACTION", "SLIP_SPEED_M_S", "TILT_RAD", "SIGNS", "first_crossings"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
