"""The warning signs of a closed-loop run, read from its log (``run.Trace``): when each was first
crossed, and which came first. A sign counts once it has held for ``PERSIST_S`` (single-tick
transients at touch-down and lift-off are not signs).

* ``stance foot unloaded``: a foot the plan has in stance carries less than ``UNLOADED_FRACTION``
  of the robot's weight (MuJoCo's normal force), or is off the ground;
* ``torque saturation``: a joint's commanded torque above its URDF effort limit (MuJoCo clamps it);
* ``foot slip``: a stance foot on the ground moving horizontally faster than ``SLIP_SPEED_M_S``;
* ``trunk tilt``: the trunk's z axis more than ``TILT_RAD`` from the world's (half the fall's).
"""

from __future__ import annotations

import numpy as np

from quadruped_dyn.control.run import FALL_TILT_RAD, Trace

#: A sign holds this long before it counts (s): 20 control ticks at 1 kHz, shorter than a stance phase.
PERSIST_S = 0.02
#: A stance foot with a normal force below this fraction of the robot's weight is unloaded: a foot
#: bearing its share carries 25-50 % of it.
UNLOADED_FRACTION = 0.02
#: Horizontal speed of a stance foot on the ground above which it slips (m/s): a rolling foot
#: sphere moves its centre at radius x its angular rate, ~0.02 m/s at these gaits' joint rates.
SLIP_SPEED_M_S = 0.1
#: Trunk tilt that counts as a sign (rad): half the tilt at which a run is a fall.
TILT_RAD = FALL_TILT_RAD / 2

SIGNS = ("stance foot unloaded", "torque saturation", "foot slip", "trunk tilt")


def _first_held(flags: np.ndarray, t: np.ndarray, dt: float) -> float | None:
    """The time at which ``flags`` (N,) first stayed true for PERSIST_S (the start of that run), or None."""
    need = max(1, int(round(PERSIST_S / dt)))
    run = 0
    for k, flag in enumerate(flags):
        run = run + 1 if flag else 0
        if run >= need:
            return float(t[k - need + 1])
    return None


def sign_flags(trace: Trace, effort: np.ndarray, weight_N: float, dt: float) -> dict[str, np.ndarray]:
    """(N,) bool per sign, at every tick of ``trace``."""
    n = trace.t.size
    stance = np.zeros((n, 4), dtype=bool)
    for k, feet in enumerate(trace.stance):
        stance[k, list(feet)] = True
    unloaded = stance & ((trace.contact_f[:, :, 2] < UNLOADED_FRACTION * weight_N) | ~trace.touching)
    speed = np.zeros((n, 4))
    if n > 1:
        speed[1:] = np.linalg.norm(np.diff(trace.feet[:, :, :2], axis=0), axis=2) / dt
    slipping = stance & trace.touching & (speed > SLIP_SPEED_M_S)
    tilt = np.arccos(np.clip(trace.trunk_R[:, 2, 2], -1.0, 1.0)) if n else np.zeros(0)
    return {"stance foot unloaded": unloaded.any(axis=1), "torque saturation": (np.abs(trace.tau) > effort).any(axis=1),
            "foot slip": slipping.any(axis=1), "trunk tilt": tilt > TILT_RAD}


def first_crossings(trace: Trace, effort: np.ndarray, weight_N: float, dt: float) -> dict[str, object]:
    """``{"crossed": {sign: time s or None}, "first": the earliest sign or None, "first_at_s": its time}``."""
    crossed = {name: _first_held(flags, trace.t, dt) for name, flags in sign_flags(trace, effort, weight_N, dt).items()}
    times = {k: v for k, v in crossed.items() if v is not None}
    first = min(times, key=lambda k: (times[k], SIGNS.index(k))) if times else None
    return {"crossed": crossed, "first": first, "first_at_s": times[first] if first else None}
