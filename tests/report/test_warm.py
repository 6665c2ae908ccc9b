"""The report's compile-ahead process: a failure there is one line handed back, never a crash
(the step that needs the artefact builds it and reports), and no process outlives the pool."""

from __future__ import annotations

import pytest

from quadruped_dyn.report import warm


def test_a_failed_warm_build_is_one_line(tmp_path):
    message = warm.warm_caches(str(tmp_path / "missing.urdf"), with_benchmark=True)
    assert message.startswith("InputError: ") and "\n" not in message


def test_the_warm_process_ends_with_its_pool(tmp_path):
    pool, future, _ = warm.start(tmp_path / "missing.urdf", with_benchmark=False)
    pool.shutdown(wait=True)
    assert future.done() and future.result().startswith("InputError: ")
    assert not [p for p in (pool._processes or {}).values() if p.is_alive()]


@pytest.mark.slow  # a spawned process and a Jupyter kernel: ~20 s on the loaded 2-core machine
def test_notebooks_run_in_the_warm_process_after_it(tmp_path):
    """A notebook handed to ``start`` is executed and rendered there, after the warm builds (here
    failing at once), and comes back as the notebooks step shows it."""
    import nbformat

    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("print(6 * 7)"),
                                         nbformat.v4.new_code_cell("1 / 0")])
    path = tmp_path / "probe.ipynb"
    nbformat.write(nb, path)
    pool, warmed, notebooks = warm.start(tmp_path / "missing.urdf", with_benchmark=False, notebooks=[path])
    try:
        page = notebooks[0].result(timeout=120)
    finally:
        pool.shutdown(wait=True)
    assert warmed.result().startswith("InputError: ")
    assert page["name"] == "probe.ipynb" and page["errors"] == 1
    assert "42" in page["html"] and "ZeroDivisionError" in page["html"]


def test_the_warm_build_loads_the_reports_feet():
    """The warm process loads the robot on the report's foot frames (the caches key on them: on the default feet it
    would build another library): a foot frame the URDF does not have is its one-line error."""
    message = warm.warm_caches("paper", with_benchmark=False, foot_frames=("FL_nowhere", "FR_foot", "BL_foot", "BR_foot"))
    assert message.startswith("InputError: ") and "'FL_nowhere' of leg FL is not a frame" in message, message


def test_the_warm_process_writes_nothing_to_the_reports_stderr(tmp_path, capfd):
    """What the warm process prints is not the report's output (its errors come back as one line through the
    futures): nbclient's cleanup when ``stop(now=True)`` ends it during a kernel's start printed asyncio's 'Task
    exception was never retrieved' traceback under the report's ``error: terminated``."""
    import os

    pool, _, _ = warm.start(tmp_path / "missing.urdf", with_benchmark=False)
    try:
        assert pool.submit(os.write, 2, b"Traceback (most recent call last):\n").result(timeout=120) > 0
    finally:
        warm.stop(pool)
    assert "Traceback" not in capfd.readouterr().err


def test_a_second_interrupt_while_the_warm_process_is_stopped_still_ends_it(tmp_path, monkeypatch):
    """Ctrl-C (or SIGTERM) again while ``stop(now=True)`` ends the warm process (the first one's cleanup) takes
    effect once it has ended: it cut the stop short, the pool stayed up and the exit hung joining its worker."""
    import multiprocessing.process
    import os
    import signal

    pool, warmed, _ = warm.start(tmp_path / "missing.urdf", with_benchmark=False)
    warmed.result(timeout=120)
    workers = list((pool._processes or {}).values())
    terminate = multiprocessing.process.BaseProcess.terminate

    def interrupted_terminate(self):
        os.kill(os.getpid(), signal.SIGINT)  # the second Ctrl-C, as the first is being handled
        terminate(self)

    monkeypatch.setattr(multiprocessing.process.BaseProcess, "terminate", interrupted_terminate)
    try:
        with pytest.raises(KeyboardInterrupt):
            warm.stop(pool, now=True)
        assert workers and not [p for p in workers if p.is_alive()]
    finally:
        for p in workers:
            p.kill()
        pool.shutdown(wait=True)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_an_interrupt_while_the_warm_process_spawns_waits_for_the_spawn_then_stops_it(tmp_path, monkeypatch, capfd):
    """Ctrl-C (or SIGTERM) while the first submit spawns the worker: the spawn completes, the worker is ended and the
    interrupt raised from ``start``. Before, the parent's pipe closed mid-spawn and the worker printed multiprocessing's
    'EOFError: Ran out of input' traceback under the report's ``error: terminated`` (and the caller, with no pool in
    hand, could not stop it)."""
    import multiprocessing.popen_spawn_posix
    import os
    import signal

    spawned = []
    launch = multiprocessing.popen_spawn_posix.Popen._launch

    def interrupted_launch(self, process_obj):
        os.kill(os.getpid(), signal.SIGINT)  # arrives while the worker's preparation data is being written
        launch(self, process_obj)
        spawned.append(self.pid)

    monkeypatch.setattr(multiprocessing.popen_spawn_posix.Popen, "_launch", interrupted_launch)
    with pytest.raises(KeyboardInterrupt):
        warm.start(tmp_path / "missing.urdf", with_benchmark=False)
    assert spawned and not [pid for pid in spawned if os.path.exists(f"/proc/{pid}") and
                            "Z" not in open(f"/proc/{pid}/stat").read().split()[2]]
    assert "Traceback" not in capfd.readouterr().err
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
