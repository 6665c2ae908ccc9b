"""files.safe_write's sets: the files of one result appear together or not at all."""

from __future__ import annotations

import pytest

from quadruped_dyn.files.safe_write import output_set, write_text


def test_a_set_inside_a_set_joins_it(tmp_path):
    """A writer's set inside a command's (which adds the provenance record) is renamed when the outer set ends, and
    an error after the inner block leaves the previous files as they were, with no temporary file."""
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a")
    with output_set():
        with output_set():
            write_text(a, "new a")
        assert a.read_text() == "old a"  # the inner set waits for the outer
        write_text(b, "b")
    assert a.read_text() == "new a" and b.read_text() == "b"
    with pytest.raises(RuntimeError), output_set():
        with output_set():
            write_text(a, "newer a")
        raise RuntimeError("after the writer's set")
    assert a.read_text() == "new a" and sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.txt"]
