"""What C++ code writes to file descriptor 2, captured: urdfdom prints its own ``Error:`` lines before Pinocchio
raises, and the one-line error says them instead."""

from __future__ import annotations

import os
import sys
import tempfile


class StderrCapture:
    """Within ``with``, file descriptor 2 goes to a temporary file; ``text`` is what was written there."""

    def __enter__(self) -> StderrCapture:
        self._file = tempfile.TemporaryFile()
        try:
            sys.stderr.flush()
        except (OSError, ValueError):
            pass
        self._saved = os.dup(2)
        os.dup2(self._file.fileno(), 2)
        return self

    def __exit__(self, *exc: object) -> None:
        os.dup2(self._saved, 2)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode("utf-8", "replace")
        self._file.close()
