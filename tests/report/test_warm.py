"""The report's compile-ahead process: a failure there is one line handed back, never a crash
(the step that needs the artefact builds it and reports), and no process outlives the pool."""

from __future__ import annotations

from quadruped_dyn.report import warm


def test_a_failed_warm_build_is_one_line(tmp_path):
    message = warm.warm_caches(str(tmp_path / "missing.urdf"), with_benchmark=True)
    assert message.startswith("InputError: ") and "\n" not in message


def test_the_warm_process_ends_with_its_pool(tmp_path):
    pool, future = warm.start(tmp_path / "missing.urdf", with_benchmark=False)
    pool.shutdown(wait=True)
    assert future.done() and future.result().startswith("InputError: ")
    assert not [p for p in (pool._processes or {}).values() if p.is_alive()]
