"""The plant perturbations of a ``control`` sweep: each run draws one sample, uniform in each range of
the sweep file (``tasks.control.perturbations``), from (seed, run index) alone, so a run's sample —
what makes MuJoCo's deterministic runs differ — is the same on any worker, for every controller."""

from __future__ import annotations

from typing import Any

import numpy as np

from quadruped_dyn.control.ground import GROUND_HALF_SIZE_M, MAX_GROUND_STEP_M
from quadruped_dyn.errors import InputError

#: Each perturbation's accepted [lowest, highest] value.
BOUNDS: dict[str, tuple[float, float]] = {
    "mass_scale": (1e-3, 10.0), "trunk_mass_scale": (1e-3, 10.0), "link_mass_scale": (1e-3, 10.0),
    "payload_kg": (0.0, 1e3), "payload_offset_x_m": (-1.0, 1.0), "payload_offset_y_m": (-1.0, 1.0),
    "payload_offset_z_m": (-1.0, 1.0), "mu": (0.0, 10.0), "foot_radius_m": (1e-3, 0.19),
    "push_x_N_s": (-1e3, 1e3), "push_y_N_s": (-1e3, 1e3), "push_z_N_s": (-1e3, 1e3), "push_at_s": (0.0, 1e3),
    "imu_noise_rad_s": (0.0, 10.0), "imu_noise_rad": (0.0, 1.0), "imu_delay_ticks": (0.0, 1000.0),
    "step_x_m": (-GROUND_HALF_SIZE_M, GROUND_HALF_SIZE_M), "step_height_m": (-MAX_GROUND_STEP_M, MAX_GROUND_STEP_M),
}


def check_perturbations(key: str, ranges: dict[str, tuple[float, float]]) -> None:
    for name, (lo, hi) in ranges.items():
        low, high = BOUNDS[name]
        if lo < low or hi > high:
            raise InputError(f"sweep file: {key}.{name} is [{lo:g}, {hi:g}]; expected values from {low:g} to {high:g}")


def sample(ranges: dict[str, tuple[float, float]], seed: int, run: int) -> dict[str, Any]:
    """Run ``run``'s perturbation: each name uniform in its range (a fixed value for lo = hi); IMU delay in whole ticks."""
    rng = np.random.default_rng([seed, run])
    out: dict[str, Any] = {}
    for name in sorted(ranges):
        lo, hi = ranges[name]
        x = float(rng.uniform(lo, hi)) if hi > lo else float(lo)
        out[name] = int(round(x)) if name == "imu_delay_ticks" else x
    return out
