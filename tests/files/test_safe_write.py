"""files.safe_write's sets: the files of one result appear together or not at all."""

from __future__ import annotations

import signal

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


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_an_interrupt_while_the_set_is_renamed_comes_after_every_file(tmp_path, monkeypatch, signum):
    """A signal between two renames left the first file new and the second old (a mix of two results). It is
    sent here during the first rename: every file is put in place, then the interrupt is raised, and the
    handlers are the ones from before."""
    from quadruped_dyn.cli.entry import Terminated, _terminate
    from quadruped_dyn.files import safe_write

    files = [tmp_path / f"{k}.txt" for k in range(3)]
    for path in files:
        path.write_text("old")
    rename = safe_write._rename
    sent = []

    def rename_and_signal(tmp, path):
        if not sent:
            sent.append(signum)
            signal.raise_signal(signum)  # its handler runs at once unless deferred
        rename(tmp, path)

    monkeypatch.setattr(safe_write, "_rename", rename_and_signal)
    previous = signal.signal(signal.SIGTERM, _terminate)  # as cli.entry sets it
    try:
        with pytest.raises(Terminated if signum == signal.SIGTERM else KeyboardInterrupt), output_set():
            for path in files:
                write_text(path, "new")
        assert [path.read_text() for path in files] == ["new"] * 3
        assert signal.getsignal(signal.SIGTERM) is _terminate
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_an_interrupt_as_the_handlers_are_put_back_leaves_none_of_the_sets(tmp_path, monkeypatch):
    """Ctrl-C just after SIGINT's handler is put back raised out of the loop before SIGTERM's was: SIGTERM kept
    the set's deferring handler for good, and every later SIGTERM was swallowed."""
    from quadruped_dyn.cli.entry import _terminate

    real = signal.signal

    def signal_then_ctrl_c(signum, handler):
        old = real(signum, handler)
        if signum == signal.SIGINT and handler is signal.default_int_handler:
            signal.raise_signal(signal.SIGINT)  # the Ctrl-C, as soon as its handler is back
        return old

    previous = real(signal.SIGTERM, _terminate)
    monkeypatch.setattr(signal, "signal", signal_then_ctrl_c)
    try:
        with pytest.raises(KeyboardInterrupt), output_set():
            write_text(tmp_path / "a.txt", "new")
        assert (tmp_path / "a.txt").read_text() == "new"
        assert signal.getsignal(signal.SIGTERM) is _terminate
    finally:
        real(signal.SIGTERM, previous)
