"""The report's drawings (matplotlib; the report selects the Agg backend): the robot as a stick figure, the GRF systems' free
and unbalanced directions on the footprint, and the sparsity of each symbolic term.
Each function takes plain data and returns a matplotlib Figure."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import matplotlib.pyplot as plt
import numpy as np

from quadruped_dyn.model.leg import LEG_LABELS

_LEG_COLOURS = {"FL": "tab:blue", "FR": "tab:orange", "BL": "tab:green", "BR": "tab:red"}


def stick_figure(chains: dict[str, np.ndarray], title: str) -> Any:
    """3-D view and side view of the legs: ``chains[label]`` (4, 3) world points HAA, HFE, KFE
    joint origins and the foot (m, world frame, z up, trunk x forward)."""
    fig = plt.figure(figsize=(11, 4.4))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    side = fig.add_subplot(1, 2, 2)
    hips = np.array([chains[label][0] for label in ("FL", "FR", "BR", "BL", "FL")])
    ax3.plot(*hips.T, "k-", lw=3)
    side.plot(hips[:, 0], hips[:, 2], "k-", lw=3)
    for label, pts in chains.items():
        c = _LEG_COLOURS[label]
        ax3.plot(*pts.T, "-o", color=c, lw=2.5, ms=4, label=label)
        ax3.scatter(*pts[-1], color=c, s=40, marker="s")
        side.plot(pts[:, 0], pts[:, 2], "-o", color=c, lw=2.5, ms=4, label=label)
    everything = np.vstack(list(chains.values()))
    span = float(np.ptp(everything, axis=0).max()) / 2 or 0.1
    centre = (everything.max(axis=0) + everything.min(axis=0)) / 2
    for setter, k in ((ax3.set_xlim, 0), (ax3.set_ylim, 1), (ax3.set_zlim, 2)):
        setter(centre[k] - span, centre[k] + span)
    ax3.set_box_aspect((1, 1, 1))
    ax3.set_xlabel("x (m)")
    ax3.set_ylabel("y (m)")
    ax3.set_zlabel("z (m)")
    ax3.view_init(elev=20, azim=-60)
    ax3.legend(fontsize=8, loc="upper left")
    side.axhline(0.0, color="0.6", lw=1)
    side.set_aspect("equal")
    side.set_xlabel("x (m), forward")
    side.set_ylabel("z (m)")
    side.set_title("side view (x-z plane)")
    side.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def footprint_figure(feet: np.ndarray, cases: Sequence[dict[str, Any]]) -> Any:
    """The free direction (lambda the model cannot determine) and the unbalanced direction
    (wrench the feet cannot produce) of rank-deficient GRF systems, drawn on the footprint.
    ``feet`` (4, 3) trunk frame, m; each case: stance (feet indices), f_free (k, 3) the forces
    of the free direction, name."""
    fig, axes = plt.subplots(1, len(cases), figsize=(4.6 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases):
        stance, f_free = list(case["stance"]), np.asarray(case["f_free"])
        ax.scatter(feet[:, 0], feet[:, 1], c="lightgray", s=80, zorder=1)
        for i, label in enumerate(LEG_LABELS):
            ax.annotate(label, feet[i, :2] + [0.01, 0.01])
        pts = feet[stance]
        if len(stance) == 4:
            colours = ["tab:red" if fz > 0 else "tab:blue" for fz in f_free[:, 2]]
            ax.scatter(pts[:, 0], pts[:, 1], s=2000 * np.abs(f_free[:, 2]), c=colours, alpha=0.5, zorder=2)
            c = pts[:, :2].mean(axis=0)
            radius = 0.15 * float(np.ptp(pts[:, 1]))
            ax.add_patch(plt.Circle(c, radius, fill=False, ls="--", color="k"))
            ax.annotate("unbalanced: yaw\nabout the centroid", c + [-radius, 1.2 * radius], fontsize=8)
            ax.set_title(f"{case['name']}: free f_z pattern\n(red up, blue down)", fontsize=10)
        else:
            ax.plot(pts[:, 0], pts[:, 1], "k--")
            ax.quiver(pts[:, 0], pts[:, 1], f_free[:, 0], f_free[:, 1], color="tab:green", scale=4, width=0.012, zorder=3)
            ax.annotate("unbalanced: moment\nabout this line", pts[:, :2].mean(axis=0) + [0.01, -0.05], fontsize=8)
            ax.set_title(f"{case['name']}: free squeeze along the line", fontsize=10)
        pad = 0.3 * float(np.ptp(feet[:, :2], axis=0).max())
        ax.set_xlim(feet[:, 0].min() - pad, feet[:, 0].max() + pad)
        ax.set_ylim(feet[:, 1].min() - pad, feet[:, 1].max() + pad)
        ax.set_aspect("equal")
        ax.set_xlabel("x_b (m)")
        ax.set_ylabel("y_b (m)")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def sparsity_figure(patterns: Sequence[tuple[str, np.ndarray]], columns: int = 6) -> Any:
    """Structural nonzeros (black) of each term: a matrix output itself, or the Jacobian of a
    vector output w.r.t. all inputs (columns: the inputs one after another)."""
    rows = -(-len(patterns) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(2.3 * columns, 2.5 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (name, pattern) in zip(axes.ravel(), patterns):
        ax.axis("on")
        ax.imshow(pattern, cmap="Greys", vmin=0, vmax=1, interpolation="nearest", aspect="auto")
        ax.set_title(f"{name}\n{pattern.shape[0]}x{pattern.shape[1]}, {int(pattern.sum())} nz", fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    return fig
