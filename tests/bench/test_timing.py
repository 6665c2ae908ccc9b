"""The benchmark's text table (``bench/timing.py``): columns stay apart and aligned whatever the names' lengths."""

from __future__ import annotations

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
