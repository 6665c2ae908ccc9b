"""Output files: directories proven writable before work starts, strict JSON, names derived from
input made safe, writes that stay under the output directory and never follow a link, the record of
which URDF a robot's outputs came from, and the verified cache of built artefacts (compiled
libraries, harnesses, stored symbolic models)."""

from quadruped_dyn.exports import lazy_exports

_MODULES: dict[str, tuple[str, ...]] = {
    "cache": ("HASH_SUFFIX", "PARTIAL_MARK", "cache_dir", "writable_cache", "file_sha256", "verified", "cached_build"),
    "json": ("json_safe", "write_json"),
    "names": ("MAX_NAME_CHARS", "is_safe_name", "safe_name", "printable"),
    "paths": ("writable_dir",),
    "provenance": ("check_source", "record_source"),
    "safe_write": ("output_path", "output_dir", "output_set", "remove", "publish", "replaceable", "write_bytes",
                   "write_text", "text_writer", "save_figure"),
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _MODULES)
