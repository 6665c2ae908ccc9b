"""Files of one closed-loop study: JSON (every controller's measures), a CSV of the time series
per controller, plots (tracking, trunk attitude, GRF differences) and a short animation.

Animation: MuJoCo's offscreen renderer (``mujoco.Renderer``) with ``MUJOCO_GL`` = egl (Debian
``libegl1``) or osmesa (``libosmesa6``), whichever works headless here; frames at
``ANIMATION_FPS`` from the recorded qpos, written as an animated GIF by Pillow (matplotlib's
dependency). ``rendering_available`` says whether it works and, if not, why.
"""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from quadruped_dyn.control.closed_loop import ClosedLoop
from quadruped_dyn.files.json import json_safe
from quadruped_dyn.files.safe_write import output_path, output_set, remove, save_figure, text_writer, write_bytes, write_text

ANIMATION_FPS = 20
ANIMATION_SIZE = (240, 320)  # height, width, px
ANIMATION_MAX_S = 3.0  # of simulated time, from the start


def output_paths(out_dir: Path, robot: str, gait: str) -> dict[str, Path]:
    stem = f"{robot}_{gait}_closed_loop"
    names = {"json": f"{stem}.json", "csv": f"{stem}_timeseries.csv", "plot": f"{stem}.png",
             "grf_plot": f"{stem}_grf.png", "animation": f"{stem}.gif"}
    return {key: output_path(out_dir, name) for key, name in names.items()}


def write_json(path: Path, study: ClosedLoop) -> dict[str, Any]:
    data: dict[str, Any] = json_safe(study.as_dict())
    write_text(path, json.dumps(data, indent=2, allow_nan=False))
    return data


def write_csv(path: Path, study: ClosedLoop) -> None:
    """Per controller and tick: t, measured and target joint angles, commanded torques, trunk
    position and roll/pitch/yaw, MuJoCo's normal force per foot."""
    names = study.robot.joint_names
    with text_writer(path) as f:
        w = csv.writer(f)
        w.writerow(["controller", "t_s", *[f"{n}_q" for n in names], *[f"{n}_q_ref" for n in names],
                    *[f"{n}_tau" for n in names], "trunk_x", "trunk_y", "trunk_z", "roll_deg", "pitch_deg", "yaw_deg",
                    *[f"{leg.label}_fz_N" for leg in study.robot.legs]])
        for name, tr in study.traces.items():
            s = study.results[name]["series"]
            for k in range(tr.t.size):
                w.writerow([name, f"{tr.t[k]:.4f}", *np.round(tr.q[k], 6), *np.round(tr.q_ref[k], 6), *np.round(tr.tau[k], 4),
                            *np.round(tr.trunk_p[k], 5), f"{s['roll_deg'][k]:.3f}", f"{s['pitch_deg'][k]:.3f}",
                            f"{s['yaw_deg'][k]:.3f}", *np.round(tr.contact_f[k, :, 2], 2)])


def plot(path: Path, study: ClosedLoop) -> None:
    """Joint tracking error (RMS over joints), trunk roll, pitch and height error per controller."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, figsize=(8, 8), sharex=True)
    for name, tr in study.traces.items():
        s = study.results[name]["series"]
        if not tr.t.size:  # stopped at its first tick
            continue
        axes[0].plot(tr.t, np.sqrt(np.mean((tr.q_ref - tr.q) ** 2, axis=1)), lw=0.8, label=name)
        axes[1].plot(tr.t, s["roll_deg"], lw=0.8, label=name)
        axes[2].plot(tr.t, s["pitch_deg"], lw=0.8, label=name)
        axes[3].plot(tr.t, s["height_m"] * 1e3, lw=0.8, label=name)
    for ax, label in zip(axes, ("joint error RMS [rad]", "roll [deg]", "pitch [deg]", "height error [mm]")):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=4)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{study.robot.name} {study.plan.gait.name}: closed loop in MuJoCo")
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)


def plot_grf(path: Path, study: ClosedLoop) -> None:
    """|f_paper - f_mujoco| per stance foot over time, per controller (samples with matching contacts)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 3))
    for name, tr in study.traces.items():
        pts = [(s["t"], float(np.linalg.norm(s["paper"] - s["mujoco"], axis=1).max())) for s in tr.grf if s["contacts_match"]]
        if pts:
            ax.plot(*zip(*pts), ".", ms=2, label=name)
    ax.set_ylabel("max |f_paper - f_MuJoCo| [N]")
    ax.set_xlabel("t [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=4)
    fig.tight_layout()
    save_figure(fig, path, dpi=90)
    plt.close(fig)


def best_controller(results: dict[str, dict[str, Any]]) -> str:
    """The controller to animate: the longest run, then the smallest joint RMS error."""
    return max(results, key=lambda n: (results[n]["simulated_s"], -(results[n]["tracking"]["rms_rad"] or 1e9)))


def write_all(out_dir: Path, study: ClosedLoop, animation: bool = True) -> tuple[dict[str, Any], dict[str, Path]]:
    """JSON, CSV, plots and (if rendering works and qpos was kept) the animation of the best run."""
    paths = output_paths(out_dir, study.robot.name, study.plan.gait.name)
    with output_set():  # all or nothing: an interrupt never leaves the new JSON beside an old CSV
        data = write_json(paths["json"], study)
        write_csv(paths["csv"], study)
        plot(paths["plot"], study)
        plot_grf(paths["grf_plot"], study)
        drawn = animation and bool(study.results) and animate(paths["animation"], study, best_controller(study.results))
        if not drawn:  # the previous run's animation is not this result's
            remove(paths["animation"])
    return data, paths


def rendering_available() -> tuple[bool, str]:
    """(works, backend or why not): MuJoCo's offscreen renderer, headless."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    try:
        import mujoco

        m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom type='sphere' size='.1'/></worldbody></mujoco>")
        with mujoco.Renderer(m, 8, 8) as r:
            r.update_scene(mujoco.MjData(m))
            r.render()
        return True, os.environ["MUJOCO_GL"]
    except Exception as e:  # any failure of the GL stack means: no animation, said so
        return False, f"MUJOCO_GL={os.environ.get('MUJOCO_GL')}: {type(e).__name__}: {e}"


def animate(path: Path, study: ClosedLoop, controller: str, seconds: float = ANIMATION_MAX_S) -> bool:
    """An animated GIF of one controller's run (its first ``seconds``); False if rendering is
    unavailable or the run kept no qpos. Software GL here: shadows, reflections, skybox and
    multisampling off (0.08 s a frame instead of 0.36 s)."""
    tr = study.traces.get(controller)
    ok, _ = rendering_available()
    if not ok or tr is None or tr.qpos is None or not tr.t.size:
        return False
    import mujoco
    from PIL import Image

    model = study.plant.model
    data = mujoco.MjData(model)
    every = max(1, int(round(study.loop.rate_hz / ANIMATION_FPS)))
    last = min(tr.t.size, int(seconds * study.loop.rate_hz))
    model.vis.quality.offsamples = 0
    cam = mujoco.MjvCamera()
    cam.distance, cam.elevation, cam.azimuth = 4.0 * max(0.25, -study.plant.floor_z), -20.0, 135.0
    frames = []
    with mujoco.Renderer(model, *ANIMATION_SIZE) as r:
        for k in range(0, last, every):
            data.qpos[:] = tr.qpos[k]
            mujoco.mj_kinematics(model, data)
            cam.lookat[:] = data.qpos[:3]
            r.update_scene(data, camera=cam)
            for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION, mujoco.mjtRndFlag.mjRND_SKYBOX):
                r.scene.flags[flag] = 0
            frames.append(Image.fromarray(r.render()).quantize(colors=64))
    gif = io.BytesIO()
    frames[0].save(gif, format="GIF", save_all=True, append_images=frames[1:], duration=int(1000 / ANIMATION_FPS),
                   loop=0, optimize=True)
    write_bytes(path, gif.getvalue())
    return True
