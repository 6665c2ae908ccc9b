"""The results of a sweep: a Parquet dataset, one file per finished task, ``<out>/rows/<key>.parquet``.

Each file is written under a temporary name in the same folder, flushed to disk and renamed into
place (atomic), so the folder only ever holds whole rows: an interrupted or killed sweep leaves every
finished row readable and at most a temporary file (``.partial-`` in its name; never read, removed
by the next run). A key is written once: a task that reran (its worker died) replaces its row by the
same row's content. ``keys()`` is what ``--resume`` skips.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from quadruped_dyn.errors import InputError
from quadruped_dyn.files.names import printable

ROWS = "rows"
SUFFIX = ".parquet"
PARTIAL = ".partial-"


class Dataset:
    def __init__(self, out: Path) -> None:
        self.folder = out / ROWS

    def prepare(self) -> None:
        """Create the rows folder and remove temporary files an interrupted run left."""
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise InputError(f"cannot create '{printable(self.folder)}' ({e.strerror}); expected a writable --out") from e
        for stray in self.folder.glob(f"*{PARTIAL}*"):
            stray.unlink(missing_ok=True)

    def keys(self) -> set[str]:
        if not self.folder.is_dir():
            return set()
        return {p.name[: -len(SUFFIX)] for p in self.folder.iterdir() if p.name.endswith(SUFFIX) and PARTIAL not in p.name}

    def write(self, row: dict[str, Any]) -> Path:
        """Write ``row`` (scalars and strings) as ``rows/<key>.parquet``, atomically."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        path = self.folder / f"{row['key']}{SUFFIX}"
        partial = self.folder / f".{row['key']}{PARTIAL}{os.getpid()}"
        try:
            with open(partial, "wb") as f:
                pq.write_table(pa.Table.from_pylist([row]), f)
                f.flush()
                os.fsync(f.fileno())
            os.replace(partial, path)
        finally:
            partial.unlink(missing_ok=True)
        return path

    def rows(self) -> list[dict[str, Any]]:
        """Every row, in key order."""
        import pyarrow.parquet as pq

        return [pq.read_table(self.folder / f"{key}{SUFFIX}").to_pylist()[0] for key in sorted(self.keys())]

    def frame(self) -> Any:
        """Every row as a pandas DataFrame (columns a row lacks are null)."""
        import pandas as pd

        return pd.DataFrame(self.rows())
