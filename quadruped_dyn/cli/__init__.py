"""The ``quadruped-dyn`` command line: ``main`` and its commands, one module per command.
Exit codes: 0 success, 1 a check or a computation failed, 2 bad input (one line on stderr, no traceback), 130 interrupted."""

from quadruped_dyn.cli.app import EXIT_BAD_INPUT, EXIT_CHECK_FAILED, main
from quadruped_dyn.cli.bench_command import bench
from quadruped_dyn.cli.check_command import check
from quadruped_dyn.cli.codegen_command import codegen
from quadruped_dyn.cli.control_command import control
from quadruped_dyn.cli.optimize_command import optimize
from quadruped_dyn.cli.report_command import report
from quadruped_dyn.cli.robot_commands import info, make_urdf, robots
from quadruped_dyn.cli.validate_command import validate

for _command in (robots, info, check, codegen, bench, validate, report, make_urdf):
    main.add_command(_command)
main.add_command(optimize)
main.add_command(control)

__all__ = ["EXIT_BAD_INPUT", "EXIT_CHECK_FAILED", "main"]
