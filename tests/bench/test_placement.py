"""The benchmark's rounds run fresh copies of each harness and of the libraries it times (bench/placement.py)."""

from __future__ import annotations

import stat
from pathlib import Path

import pytest

from quadruped_dyn.bench.placement import TimedProgram, median_over_rounds

# A harness stand-in: reports where it runs from, whether the library copy beside it comes first on the library
# path, and a time that changes from round to round (10, 40, 20 ns: median 20, max / min 4).
SCRIPT = """#!/bin/sh
here=$(cd "$(dirname "$0")" && pwd)
first=${LD_LIBRARY_PATH%%:*}
n=$(cat "$1"); echo $((n + 1)) > "$1"
case $n in 0) t=10;; 1) t=40;; *) t=20;; esac
[ "$first" = "$here" ] && [ -f "$here/libtimed.so" ] && [ "$here" != "$2" ] && echo "t $t" && echo "dir_$n 1"
"""


def test_every_round_runs_a_fresh_copy_and_takes_the_median(tmp_path: Path) -> None:
    original = tmp_path / "harness"
    original.write_text(SCRIPT)
    original.chmod(original.stat().st_mode | stat.S_IXUSR)
    library, counter = tmp_path / "libtimed.so", tmp_path / "counter"
    library.write_bytes(b"code")
    counter.write_text("0")
    program = TimedProgram([str(original), str(counter), str(tmp_path)], (library,))
    median, spread = median_over_rounds({"side": program}, 3)
    # the copy ran (not the original: its directory differs, the library beside it and first on LD_LIBRARY_PATH)
    assert set(median["side"]) == {"t", "dir_0", "dir_1", "dir_2"}
    assert median["side"]["t"] == 20.0 and spread["side"]["t"] == pytest.approx(4.0)
    assert counter.read_text().strip() == "3"
