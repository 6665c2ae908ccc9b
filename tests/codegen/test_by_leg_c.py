"""The feet's C leg by leg (codegen/by_leg.py ``foot_c``, the library's qd_foot_trig), compiled with the library's flags
for a robot whose legs need two templates and a sign (``turned_robot``), against each leg's own kinematics
(``kinematics.foot_position`` and its derivatives: no templates), with rates and at rest (qd_l null)."""

from __future__ import annotations

import ctypes
import subprocess

import casadi as ca
import numpy as np

from quadruped_dyn.codegen.by_leg import foot_c
from quadruped_dyn.codegen.forms.leg_pieces import FOOT_PARTS, foot_kinematics, foot_pieces
from quadruped_dyn.codegen.library import C_FLAGS
from quadruped_dyn.dynamics.kinematics import foot_position
from quadruped_dyn.tolerances import REL_TOL_GRAPH
from tests.codegen.forms.test_leg_template import turned_robot
from tests.conftest import assert_close

_PRELUDE = "#include <math.h>\n#define casadi_real double\n#define casadi_int long long int\n"


def test_feet_of_two_leg_templates_and_a_turned_hip_compiled(tmp_path):
    robot = turned_robot()
    pieces = foot_pieces(robot)
    assert pieces.template_of == (0, 1, 0, 0) and [pieces.leg_signs(k)[0] for k in (0, 2, 3)] == [1.0, -1.0, -1.0]
    source, library = tmp_path / "feet.c", tmp_path / "libfeet.so"
    source.write_text(_PRELUDE + foot_c("qd_foot_trig", pieces, frozenset()))
    subprocess.run(["gcc", *C_FLAGS, "-shared", str(source), "-o", str(library), "-lm"], check=True)
    c_foot = ctypes.CDLL(str(library)).qd_foot_trig
    c_foot.restype = ctypes.c_int
    reals = ctypes.POINTER(ctypes.c_double)
    n_y = sum(rows * cols for _, rows, cols in FOOT_PARTS)
    q_l, qd_l = ca.SX.sym("q_l", 3), ca.SX.sym("qd_l", 3)
    rng = np.random.default_rng(4)
    for k in range(4):
        whole = ca.Function("foot", [q_l, qd_l], [foot_kinematics(foot_position(robot.legs[k], q_l), q_l, qd_l)])
        q, qd = rng.uniform(robot.lower[3 * k : 3 * k + 3], robot.upper[3 * k : 3 * k + 3]), rng.normal(size=3)
        for rates in (qd, None):
            y = np.full(n_y, np.nan)
            args = [np.ascontiguousarray(x) for x in (q, np.sin(q), np.cos(q))]
            qd_arg = None if rates is None else np.ascontiguousarray(rates).ctypes.data_as(reals)
            flag = c_foot(k, args[0].ctypes.data_as(reals), qd_arg, args[1].ctypes.data_as(reals),
                          args[2].ctypes.data_as(reals), y.ctypes.data_as(reals))
            assert flag == 0
            expected = np.array(whole(q, np.zeros(3) if rates is None else rates)).ravel()
            assert_close(y, expected, REL_TOL_GRAPH, f"leg {k}'s foot in C, {'with rates' if rates is not None else 'at rest'}")
