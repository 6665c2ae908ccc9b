"""``python -m quadruped_dyn.cli``."""

from quadruped_dyn.cli.entry import main

main()
