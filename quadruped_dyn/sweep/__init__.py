"""Sweeps: checks, generated C, the paper's experiment and closed loops over many robots, variants and
plant perturbations, run on Dask distributed, each finished task a row of a Parquet dataset
(docs/sweeps.md): the sweep file (``spec``, ``options``), its robots (``robots``), the perturbation
samples (``sampling``), the tasks (``tasks``) and their rows (``rows``), the engine (``engine``), the
dataset (``dataset``), the summary (``summary``) and its page (``page``); the scaling benchmark (``scaling``).
Needs the ``sweep`` extra (distributed, pyarrow, pandas)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "spec": ("SweepSpec", "Variants", "read_spec"),
    "options": ("DEFAULTS", "installed_libraries", "checked_options"),
    "robots": ("RobotRef", "sweep_robots", "materialise"),
    "sampling": ("BOUNDS", "sample"),
    "tasks": ("KINDS", "Task", "sweep_tasks", "compute"),
    "rows": ("execute", "error_row"),
    "engine": ("CONNECT_TIMEOUT_S", "Cluster", "connect", "run"),
    "dataset": ("Dataset",),
    "summary": ("wilson", "newcombe", "summarise"),
    "page": ("page",),
    "scaling": ("measure", "cpu_model"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
