"""Closed loop: the generated C controls a quadruped simulated by MuJoCo (docs/closed_loop.md).

MuJoCo picks its OpenGL backend when it is first imported: offscreen rendering (the animation)
works headless with EGL (Debian ``libegl1``), so that is the default unless MUJOCO_GL is set.
"""

import os

os.environ.setdefault("MUJOCO_GL", "egl")
