"""``python -m quadruped_dyn.cli``."""

from quadruped_dyn.cli import main

main()
