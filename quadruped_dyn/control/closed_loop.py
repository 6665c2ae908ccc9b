"""One closed-loop study: a robot, a gait, the selected controllers, each run on the same plant
from the same settled state (``run``), measured (``measures``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from quadruped_dyn.control.controllers import Gains, GeneratedC, parse_controllers
from quadruped_dyn.control.measures import grf_comparison, summary
from quadruped_dyn.control.plan import target_cycle
from quadruped_dyn.control.plant import Plant, PlantOptions, build_plant
from quadruped_dyn.control.run import LoopOptions, Progress, Trace, run_controller, settled_state
from quadruped_dyn.errors import InputError
from quadruped_dyn.experiment.gait import GAITS, Plan, gait_plan
from quadruped_dyn.model.robot import Robot


@dataclass
class ClosedLoop:
    robot: Robot
    plan: Plan
    plant: Plant
    gains: Gains
    loop: LoopOptions
    substeps: int
    controllers: list[str]
    results: dict[str, dict[str, Any]] = field(default_factory=dict)
    traces: dict[str, Trace] = field(default_factory=dict)
    standing_grf: list[dict] = field(default_factory=list)  # four feet, while settling

    def as_dict(self) -> dict[str, Any]:
        p = self.plant
        return {
            "robot": self.robot.name, "urdf": str(self.robot.urdf), "gait": self.plan.gait.name,
            "cycles": self.loop.cycles, "period_s": self.plan.gait.period, "control_rate_hz": self.loop.rate_hz,
            "push": None if self.loop.push is None else {"t_s": self.loop.push[0], "impulse_N_s": list(self.loop.push[1:])},
            "plant": {"timestep_s": p.options.timestep, "integrator": p.options.integrator, "mu": p.options.mu,
                      "foot_radius_m": p.foot_radius, "foot_radius_from": p.foot_radius_source,
                      "floor_z_m": p.floor_z, "substeps_per_tick": self.substeps, "settle_s": self.loop.settle_s,
                      "model_changes": p.changes, "effort_Nm": p.effort.tolist()},
            "gains": self.gains.as_dict(self.robot),
            "measured": "joint q, qd; trunk orientation and angular rate (IMU, exact); foot contact switches; stance set "
                        "from the plan (wbc: trunk linear velocity by leg odometry)",
            "standing_grf": grf_comparison(self.standing_grf, self.robot.total_mass * 9.81)["4 feet"],
            "controllers": {k: {kk: vv for kk, vv in v.items() if kk != "series"} for k, v in self.results.items()},
        }


def parse_gait(name: str) -> str:
    if not isinstance(name, str) or name not in GAITS:
        raise InputError(f"unknown gait '{name}'; expected one of {', '.join(GAITS)}")
    return name


def prepare(robot: Robot, gait: str, controllers: list[str] | tuple[str, ...] = (), gains: Gains | None = None,
            loop: LoopOptions | None = None, plant_options: PlantOptions | None = None) -> ClosedLoop:
    """Validate everything and build the plant (InputError before any simulation); defaults:
    ``Gains()``, ``LoopOptions()``, ``PlantOptions()``."""
    gains, loop, plant_options = gains or Gains(), loop or LoopOptions(), plant_options or PlantOptions()
    names = parse_controllers(controllers)
    plan = gait_plan(robot, GAITS[parse_gait(gait)])
    gains.validate()
    plant_options.validate()
    substeps = loop.validate(plant_options, plan.gait.period)
    loop.validate_push(loop.cycles * plan.gait.period, robot.total_mass)
    plant = build_plant(robot, plan, plant_options)
    return ClosedLoop(robot, plan, plant, gains, loop, substeps, names)


def run_all(study: ClosedLoop, progress: Progress | None = None, keep_qpos: bool = False) -> ClosedLoop:
    """Run every selected controller; ``progress`` gets the simulated time summed over the runs."""
    c = GeneratedC(study.robot)
    target_cycle(study.plan, study.loop.rate_hz)
    initial, study.standing_grf = settled_state(study.plant, study.plan, study.gains, c, study.loop.rate_hz,
                                                study.substeps, study.loop.settle_s, study.loop.grf_every)
    horizon = study.loop.cycles * study.plan.gait.period
    for j, name in enumerate(study.controllers):
        tick = (lambda t, j=j: progress(j * horizon + t)) if progress else None
        trace = run_controller(study.plant, study.plan, name, study.gains, study.loop, study.substeps, initial, c, tick,
                               keep_qpos)
        study.traces[name] = trace
        study.results[name] = summary(trace, study.plant, study.plan, 1.0 / study.loop.rate_hz, study.loop.cycles)
        if progress:
            progress((j + 1) * horizon)
    return study
