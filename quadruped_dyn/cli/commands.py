"""The ``quadruped-dyn`` group with every command added (light: each command imports its work, CasADi, Pinocchio,
scipy, when it runs; tests/test_layout.py holds it so)."""

from quadruped_dyn.cli.app import main
from quadruped_dyn.cli.bench_command import bench
from quadruped_dyn.cli.check_command import check
from quadruped_dyn.cli.codegen_command import codegen
from quadruped_dyn.cli.control_command import control
from quadruped_dyn.cli.optimize_command import optimize
from quadruped_dyn.cli.report_command import report
from quadruped_dyn.cli.robot_commands import info, make_urdf, robots
from quadruped_dyn.cli.sweep_command import sweep
from quadruped_dyn.cli.validate_command import validate

for _command in (robots, info, check, codegen, bench, validate, report, make_urdf):
    main.add_command(_command)
main.add_command(optimize)
main.add_command(control)
main.add_command(sweep)

__all__ = ["main"]
