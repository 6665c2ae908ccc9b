"""The benchmark's text table (``bench/timing.py``): columns stay apart and aligned whatever the names' lengths."""

from __future__ import annotations

import pytest

from quadruped_dyn.bench.timing import BenchEntry, BenchReport


def test_long_pinocchio_names_do_not_run_into_the_next_column():
    """A dfd_r entry's peer (constraintDynamicsDerivatives with four feet) is longer than the old fixed column: every
    cell is still separated by two spaces or more, and every row's ratio ends where the header's 'ratio' ends."""
    long_name = "constraintDynamicsDerivatives_FL_FR_BL_BR"
    report = BenchReport(robot="paper", entries=[
        BenchEntry("M_full", 201.5, "crba", 1100.0, 0.18, 0.4),
        BenchEntry("dfd_r_FL_FR_BL_BR", 12500.0, long_name, 29000.0, 0.43, 0.5),
    ])
    header, *rows = report.table().splitlines()[:3]
    assert f"{long_name} 29000 ns  " in rows[1]
    end = header.index("ratio") + len("ratio")
    for row, ratio in zip(rows, ("0.18", "0.43")):
        assert row[end - len(ratio):end] == ratio, row
        assert row[end - len(ratio) - 2:end - len(ratio)] == "  ", row


def test_peers_table_columns_stay_apart():
    """adam's table (``peers_table``) sizes its columns the same way: a robot named after a long URDF file stays apart."""
    from quadruped_dyn.bench.peers import PeerEntry, peers_table

    entry = PeerEntry("a_robot_named_after_its_urdf_file", "M_full", "adam_M", 200.0, 3000.0, 0.07, 1200, 9000, 1e-15)
    row = peers_table([entry], native=False).splitlines()[2]
    assert row.startswith("a_robot_named_after_its_urdf_file  "), row


def test_parametric_rows_in_the_table():
    report = BenchReport("paper", parametric={"M_full": {"parametric_ns": 350.0, "fixed_ns": 170.0, "pinocchio_ns": 760.0,
                                                         "vs_pinocchio": 0.46, "vs_fixed": 2.06}})
    row = next(line for line in report.table().splitlines() if line.startswith("M_full"))
    assert row.split() == ["M_full", "350", "170", "760", "0.46", "2.06"]


@pytest.mark.slow
def test_bench_json_has_the_parametric_section():
    """``bench --parametric --json``: per term of parametric_timing.PAIRS the three times, finite and positive."""
    import json
    import math

    from click.testing import CliRunner

    from quadruped_dyn.bench.parametric_timing import PAIRS
    from quadruped_dyn.cli import main

    run = CliRunner().invoke(main, ["bench", "--robot", "paper", "--parametric", "--json", "--calls", "200", "--reps", "1",
                                    "--peers", "none", "--no-call-cost"])
    assert run.exit_code == 0, run.output
    section = json.loads(run.stdout[run.stdout.index("["):])[0]["parametric"]
    assert set(section) == {fixed for _, fixed, _ in PAIRS}
    for times in section.values():
        assert all(math.isfinite(times[k]) and times[k] > 0 for k in ("parametric_ns", "fixed_ns", "pinocchio_ns")), times
