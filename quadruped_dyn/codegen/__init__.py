"""Standalone C from the CasADi graphs: emission, the compiled libraries loaded back into Python,
and the C templates (``c/``); they are cached in the verified build cache (``files/cache.py``)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "print_settings": ("PREFIX", "EVALUATION", "UNGUARDED", "static_c"),
    "printer": ("PrintOptions", "Printed", "print_function"),
    "c_file": ("Entry", "FileOptions", "c_file", "casadi_c"),
    "file_names": ("REDUCED_STANCE_SETS", "SHARED_FILES", "GeneratedFiles", "file_layout", "robot_stem", "robot_file",
                   "feet_suffix", "reference_header_name", "robots_in", "check_no_collision"),
    "emit": (
        "CODEGEN_FUNCTIONS", "ALIASES", "REDUCED_NAMES", "reduced_symbol", "reduced_functions",
        "SIGNAL_DOCS", "codegen_function", "codegen_functions", "reduced_parts", "header_doc", "generate",
    ),
    "emit_derivatives": ("DERIVATIVE_NAMES", "GRF_DERIVATIVE_NAMES", "GRF_DERIVATIVE_STANCE_SETS", "REDUCED_DERIVATIVE_NAMES",
                         "derivative_functions", "derivative_source", "grf_derivative_functions",
                         "reduced_derivative_functions"),
    "library": (
        "C_FLAGS", "COMPILE_JOBS", "run_tool", "compiler_version", "CompiledLibrary", "cached_object", "compile_sources",
        "PACKAGE",
        "generator_sources", "generation_key", "compiled_library", "load_external", "RETURN_CODES", "CompiledFunction",
        "work_sizes_of",
    ),
    "reduced_library": ("CompiledReducedDynamics",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
