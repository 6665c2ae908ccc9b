"""Output files: directories proven writable before work starts, and strict JSON."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "json": ("json_safe", "write_json"),
    "paths": ("writable_dir",),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
