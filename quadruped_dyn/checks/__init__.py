"""Every term compared with a reference: the term checks against Pinocchio, the cross-library
comparison, and the reference values of the generated C's check program."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "c_reference": (
        "REFERENCE_DIGITS", "reference_state", "reduced_inputs", "pinocchio_outputs", "tolerance_scale", "reference_header",
        "reference_header_name", "checked_files", "generate_checked", "differing_files", "ReferenceHeader",
        "parse_reference_header", "reference_differences", "GenerationDiff", "compare_generation",
    ),
    "cross_library": (
        "LIBRARIES", "EXACT_CHANGES", "INSTALL_HINT", "parse_libraries", "ToolkitDynamics", "CrossLibraryResult",
        "CrossLibraryReport", "run_cross_library",
    ),
    "limits": ("MAX_SAMPLES", "CHECK_SAMPLES", "check_samples"),
    "derivative_reference": ("central", "rotated", "ReducedReference", "grf_derivatives_reference", "grf_wrench_reference"),
    "terms": ("TermResult", "CheckReport", "GrfResult", "REDUCED_STANCES", "run_check"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
