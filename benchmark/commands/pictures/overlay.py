"""The tracker on the depth: the tracked box, hand and contacts drawn over depth frames, the truth beneath."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from benchmark.atomic import write_bytes
from benchmark.world.truth import Truth
from fsv import Calibration, DepthVideo, HandModel, ObjectModel
from fsv.hand import capsule_endpoints, forward_kinematics_qpos
from fsv.track.tracker import Tracking


def _project(calib: Calibration, pts: np.ndarray) -> np.ndarray:
    T = calib.T_world_cam
    p = (pts - T[:3, 3]) @ T[:3, :3]
    return np.stack([calib.K[0, 0] * p[..., 0] / p[..., 2] + calib.K[0, 2],
                     calib.K[1, 1] * p[..., 1] / p[..., 2] + calib.K[1, 2]], -1)


_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]


def plot_overlay(depth: DepthVideo, calib: Calibration, tracking: Tracking, object_model: ObjectModel,
                 hand_model: HandModel, path: str | os.PathLike, frames: int = 6, truth: Truth | None = None) -> Path:
    """Writes :func:`overlay_figure` as a PNG (atomically) at ``path`` and returns the path."""
    fig = overlay_figure(depth, calib, tracking, object_model, hand_model, frames=frames, truth=truth)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return write_bytes(path, buf.getvalue())


def overlay_figure(depth: DepthVideo, calib: Calibration, tracking: Tracking, object_model: ObjectModel,
                   hand_model: HandModel, frames: int = 6, truth: Truth | None = None):
    """A strip of depth frames (grey: near dark, far light) with the tracked box (green), hand
    capsules (orange), fingertips (red: seen, white: hidden) and active contact points (cyan crosses)
    drawn over them; with ``truth``, the true box (gold dashed), hand (faint gold) and contact
    points (magenta plus signs) beneath. A legend under the strip names every mark.

    The layout is fixed in inches (:data:`PANEL_WIDTH_IN`, :data:`TITLE_IN`, :data:`LEGEND_ENTRY_IN`):
    each frame's panel is as wide as the strip's crop asks, its time above it, three panels to a
    row, the legend in as many rows as the strip's width needs; nothing is measured by drawing the figure twice.

    Args:
        depth: The depth video.
        calib: Its calibration.
        tracking: The tracker's output.
        object_model: The box (its size).
        hand_model: The hand (its capsules).
        frames: How many evenly spaced frames to show.
        truth: The episode's truth, drawn faintly for comparison (None: the estimate only).

    Returns:
        A ``matplotlib.figure.Figure`` (no pyplot figure: nothing to close).
    """
    from matplotlib.figure import Figure  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    T = depth.num_frames
    idx = np.unique(np.linspace(0, T - 1, max(1, min(frames, T))).round().astype(int))
    lo, hi = _crop(calib, tracking, object_model, hand_model, idx)
    cols = min(len(idx), PANELS_PER_ROW)
    rows = -(-len(idx) // cols)
    panel_h = PANEL_WIDTH_IN * (hi[1] - lo[1] + 1) / max(1.0, hi[0] - lo[0] + 1)
    handles = _legend(truth is not None)
    W = PANEL_WIDTH_IN * cols
    ncol = max(1, min(len(handles), int((W - 2 * PANEL_PAD_IN) // LEGEND_ENTRY_IN)))
    H = rows * (panel_h + TITLE_IN) + LEGEND_PAD_IN + LEGEND_ROW_IN * -(-len(handles) // ncol)
    fig = Figure(figsize=(W, H))
    for k, i in enumerate(idx):
        r, c = divmod(k, cols)
        bottom = H - (r + 1) * (panel_h + TITLE_IN)
        ax = fig.add_axes(((c * PANEL_WIDTH_IN + PANEL_PAD_IN) / W, bottom / H,
                           (PANEL_WIDTH_IN - 2 * PANEL_PAD_IN) / W, panel_h / H))
        d = np.where(depth.depth_m[i] > 0, depth.depth_m[i], np.nan)
        crop = d[int(lo[1]) : int(hi[1]) + 1, int(lo[0]) : int(hi[0]) + 1]
        vmin, vmax = (np.nanpercentile(crop, 1), np.nanpercentile(crop, 99)) if np.isfinite(crop).any() else (0, 1)
        ax.imshow(d, cmap="Greys_r", vmin=vmin, vmax=vmax)
        if truth is not None:
            _draw_truth(ax, calib, truth, object_model, hand_model, i)
        _draw_estimate(ax, calib, tracking, object_model, hand_model, i)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(hi[1], lo[1])
        ax.axis("off")
        # the frame's time above its panel, as text: a title would measure the hidden axes' ticks
        ax.text(0.5, 1 + TITLE_GAP_IN / panel_h, f"t = {depth.t[i]:.2f} s", transform=ax.transAxes, ha="center",
                va="bottom", fontsize=9)
    fig.legend(handles=handles, loc="lower center", ncol=ncol, fontsize=7, frameon=False)
    return fig


PANELS_PER_ROW = 3
"""Frames per row of the strip (six frames: two rows)."""

PANEL_WIDTH_IN = 4.6
"""Width of one frame's panel [in] (about 500 px at the 110 dpi the picture is saved with)."""

PANEL_PAD_IN = 0.1
"""Space left and right of each frame inside its panel [in]."""

TITLE_IN = 0.35
"""Height above each frame for its time [in]."""

TITLE_GAP_IN = 0.06
"""Gap between a frame and its time [in]."""

LEGEND_ENTRY_IN = 1.2
"""Width of one entry of the legend at its 7 pt [in] (measured: eight entries 8.7 in, five 5.8 in):
as many to a row as the strip is wide."""

LEGEND_ROW_IN = 0.18
"""Height of one row of the legend [in]."""

LEGEND_PAD_IN = 0.22
"""Space under the strip besides the legend's rows [in] (one row: 0.4 in)."""

TRUTH_COLOUR = "#ffd700"
"""The truth's colour (gold): it stands out on the grey depth at any brightness, unlike white."""

_SIGNS = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
"""The box's eight corners as signs of its half extents."""


def _crop(calib: Calibration, tracking, object_model: ObjectModel, hand_model: HandModel, idx) -> tuple:
    """One crop for the whole strip: the tracked box and hand over the shown frames, plus a margin,
    ``(lo, hi)`` pixel corners."""
    half = object_model.half_extents
    hand_qpos = getattr(tracking, "hand_qpos", None)  # a tracker other than the reference may have no hand
    pts = []
    for i in idx:
        pts.append(_project(calib, tracking.box.pos[i] + (_SIGNS * half) @ tracking.box.rot[i].T))
        if hand_qpos is not None:
            ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, hand_qpos[i]))
            pts.append(_project(calib, ends.reshape(-1, 3)))
    uv = np.concatenate(pts)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    lo = np.maximum(np.floor(uv.min(0)) - 25, 0) if uv.size else np.zeros(2)
    hi = np.minimum(np.ceil(uv.max(0)) + 25, [calib.width - 1, calib.height - 1]) if uv.size else np.array(
        [calib.width - 1, calib.height - 1])
    return lo, hi


def _draw_truth(ax, calib: Calibration, truth: Truth, object_model: ObjectModel, hand_model: HandModel, i: int) -> None:
    """The true box (gold dashed), hand (faint gold) and contact points (magenta plus signs) of frame ``i``."""
    from matplotlib.collections import LineCollection  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    corners = truth.box_pos[i] + (_SIGNS * object_model.half_extents) @ truth.box_rot[i].T
    uv = _project(calib, corners)
    ax.add_collection(LineCollection([uv[[a, b]] for a, b in _BOX_EDGES], colors=TRUTH_COLOUR, linewidths=1.3,
                                     linestyles="--"))
    ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, truth.hand_qpos[i]))
    uv = _project(calib, ends.reshape(-1, 3)).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(uv, colors=TRUTH_COLOUR, linewidths=2.5, alpha=0.35, capstyle="round"))
    act_t = np.asarray(truth.contact_active[i], bool)
    if act_t.any():
        uv = _project(calib, truth.box_pos[i] + truth.contact_point[i, act_t] @ truth.box_rot[i].T)
        ax.scatter(uv[:, 0], uv[:, 1], marker="+", s=40, c="magenta", zorder=3, linewidths=1.0)


def _draw_estimate(ax, calib: Calibration, tracking, object_model: ObjectModel, hand_model: HandModel, i: int) -> None:
    """The tracked box (green), hand capsules (orange), fingertips (red: seen, white: hidden) and
    active contact points (cyan crosses) of frame ``i``."""
    from matplotlib.collections import LineCollection  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    corners = tracking.box.pos[i] + (_SIGNS * object_model.half_extents) @ tracking.box.rot[i].T
    uv = _project(calib, corners)
    ax.add_collection(LineCollection([uv[[a, b]] for a, b in _BOX_EDGES], colors="lime", linewidths=1.2))
    hand_qpos = getattr(tracking, "hand_qpos", None)
    if hand_qpos is not None:
        ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, hand_qpos[i]))
        depth_mid = ((ends[:, 0] + ends[:, 1]) / 2 - calib.T_world_cam[:3, 3]) @ calib.T_world_cam[:3, 2]
        px = hand_model.geom_radius * calib.K[0, 0] / np.maximum(1e-3, depth_mid)  # capsule radius in pixels
        uv = _project(calib, ends.reshape(-1, 3)).reshape(-1, 2, 2)
        ax.add_collection(LineCollection(uv, colors="orange", linewidths=np.maximum(1.0, 1.4 * px), alpha=0.55,
                                         capstyle="round"))
    tips_all = getattr(tracking, "fingertips", None)
    if tips_all is not None:
        tips = _project(calib, tips_all[i])
        seen = getattr(tracking, "observed", np.ones(tips_all.shape[:2], bool))[i]
        ax.scatter(tips[seen, 0], tips[seen, 1], s=12, c="red", zorder=3)
        ax.scatter(tips[~seen, 0], tips[~seen, 1], s=12, c="white", edgecolors="red", zorder=3)
    act = tracking.contacts.active[i]
    if act.any():
        pts = tracking.box.pos[i] + tracking.contacts.point[i, act] @ tracking.box.rot[i].T
        uv = _project(calib, pts)
        ax.scatter(uv[:, 0], uv[:, 1], marker="x", s=30, c="cyan", zorder=4)


def _legend(with_truth: bool) -> list:
    """The legend's handles: every mark of the strip."""
    from matplotlib.lines import Line2D  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    marks = [Line2D([], [], color="lime", lw=1.2, label="tracked box"),
             Line2D([], [], color="orange", lw=3, alpha=0.55, label="tracked hand"),
             Line2D([], [], color="red", marker="o", ls="", ms=4, label="fingertip (seen)"),
             Line2D([], [], color="white", markeredgecolor="red", marker="o", ls="", ms=4, label="fingertip (hidden)"),
             Line2D([], [], color="cyan", marker="x", ls="", ms=6, label="tracked contact")]
    if with_truth:
        marks += [Line2D([], [], color=TRUTH_COLOUR, lw=1.3, ls="--", label="true box"),
                  Line2D([], [], color=TRUTH_COLOUR, lw=2.5, alpha=0.35, label="true hand"),
                  Line2D([], [], color="magenta", marker="+", ls="", ms=7, label="true contact")]
    return marks

