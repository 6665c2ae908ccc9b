"""``robots``, ``info``, ``make-urdf``: the robots the toolkit knows and the paper robot's URDF."""

from __future__ import annotations

import json
import sys

import click

from quadruped_dyn.cli.app import EXIT_CHECK_FAILED, echo, foot_frames_option


@click.command()
def robots() -> None:
    """List the built-in robot names."""
    from quadruped_dyn.model.registry import ROBOT_NAMES

    for name in ROBOT_NAMES:
        echo(name)


@click.command()
@click.argument("robot")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@foot_frames_option
def info(robot: str, as_json: bool, foot_frames: str | None) -> None:
    """Legs, joints, link lengths, masses and standing foot positions of ROBOT (name or URDF path)."""
    from quadruped_dyn.model.robot import load_robot
    from quadruped_dyn.model.robot_summary import robot_info

    data = robot_info(load_robot(robot, foot_frames=foot_frames))
    if as_json:
        echo(json.dumps(data, indent=2))
        return
    echo(f"{data['name']}  ({data['urdf']})")
    echo(f"total mass {data['total_mass_kg']:.3f} kg, trunk {data['trunk_mass_kg']:.3f} kg")
    echo(f"{'leg':<4}{'joints (HAA, HFE, KFE)':<48}{'thigh m':>8}{'shank m':>8}{'mass kg':>8}  foot at standing (b, m)")
    for leg in data["legs"]:
        foot = " ".join(f"{x:+.3f}" for x in leg["foot_position_standing_m"])
        echo(
            f"{leg['label']:<4}{', '.join(leg['joints']):<48}{leg['thigh_length_m']:>8.3f}"
            f"{leg['shank_length_m']:>8.3f}{sum(leg['link_masses_kg']):>8.3f}  {foot}"
        )


@click.command("make-urdf")
@click.option("--check", is_flag=True, help="Only compare the committed URDF with a fresh generation.")
def make_urdf(check: bool) -> None:
    """Regenerate the paper robot's URDF (package data, and urdf/ in a checkout) from the paper's DH table."""
    from quadruped_dyn.model.paper_robot import URDF_COPIES, stale_urdf_copies, write_urdf

    if check:
        stale = stale_urdf_copies()
        for path in URDF_COPIES:
            echo(f"{path}: {'DIFFERS from the generator' if path in stale else 'up to date'}")
        sys.exit(EXIT_CHECK_FAILED if stale else 0)
    for path in write_urdf():
        echo(f"wrote {path}")
