"""Every term compared with a reference: the term checks against Pinocchio, the cross-library
comparison, and the reference values of the generated C's check program."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "check_program_values": (
        "REFERENCE_DIGITS", "reference_state", "reduced_inputs", "pinocchio_outputs", "tolerance_scale", "reference_header",
        "reference_header_name", "checked_files", "generate_checked", "differing_files", "ReferenceHeader",
        "parse_reference_header", "reference_differences", "GenerationDiff", "compare_generation",
    ),
    "cross_library": (
        "LIBRARIES", "EXACT_CHANGES", "INSTALL_HINT", "parse_libraries", "ToolkitDynamics", "CrossLibraryResult",
        "CrossLibraryReport", "run_cross_library",
    ),
    "sample_counts": ("MAX_SAMPLES", "CHECK_SAMPLES", "check_samples"),
    "finite_differences": ("central", "rotated", "ReducedFiniteDifferences", "grf_derivatives_by_differences",
                           "grf_wrench_by_differences"),
    "terms": ("TermResult", "CheckReport", "GrfResult", "REDUCED_STANCES", "run_check"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
