"""The HTML report: numbers gathered from the public APIs, sections rendered from plain data."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "build": ("Progress", "prepare", "ReportResult", "build_report"),
    "figures": ("stick_figure", "footprint_figure", "sparsity_figure"),
    "gather": (
        "FRICTION_MU", "EXPERIMENT_DT", "LIBRARIES", "load_with_warnings", "robot_data", "leg_points",
        "grf_posture", "reduced_rows", "experiment", "generate_c_directory", "generated_c", "symbolic_data", "versions",
    ),
    "html": (
        "VERDICTS", "Section", "esc", "num", "grade", "cell", "table", "badge", "png_image", "figure", "not_available", "page",
    ),
    "notebooks": ("NOTEBOOK_DIR", "CELL_TIMEOUT_S", "notebook_paths", "execute", "render", "error_count"),
    "sections": (
        "generic_table", "data_html", "robot_section", "terms_section", "grf_section", "reduced_section", "experiment_section",
        "generated_c_section", "symbolic_section", "notebooks_section", "versions_section",
    ),
    "warm": ("warm_caches",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
