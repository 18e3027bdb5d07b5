"""The tracker against the truth: its scores and a picture of it on the depth.

The initialisation the tracker is given is :func:`benchmark.method.init.tracker_init`.

Scores (docs/design.md, "Metric definitions"):

* box position error: Euclidean distance of the tracked centre from the true one, median over
  frames, [mm]; box rotation error: geodesic angle, median, [deg];
* fingertip error: Euclidean distance of the tracked pad centres, median over frames and fingers;
* contact point error: vision contact point minus true contact point in the object frame, per axis,
  pooled over axes and over the frames where both the truth and the estimate have the contact;
  mean and standard deviation (the paper: mean -1.55 mm, std 6.13 mm), and the Euclidean median;
* contact detection: recall (true contacts found) and precision (found contacts that are true),
  over fingers and frames.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from benchmark.atomic import write_bytes
from benchmark.method.init import INIT_PERTURBATION
from benchmark.world.truth import Truth
from fsv import Calibration, DepthVideo, HandModel, ObjectModel
from fsv.hand import capsule_endpoints, forward_kinematics_qpos
from fsv.rotation import angle_between
from fsv.track.tracker import Tracking
from fsv.types import Contacts
from benchmark.background import background_of

def score_tracking(tracking: Tracking, truth: Truth, contacts: Contacts | None = None) -> dict:
    """The tracker's scores against the truth (see the module docstring).

    Args:
        tracking: The tracker's output.
        truth: The episode's truth.
        contacts: Contacts to score instead of ``tracking.contacts``.

    Returns:
        A dict of floats: ``box_pos_err_mm_median``, ``box_rot_err_deg_median``,
        ``fingertip_err_mm_median``, ``contact_err_mm_mean``, ``contact_err_mm_std``,
        ``contact_err_mm_median_euclid``, ``contact_recall``, ``contact_precision``, ``frames``,
        ``contact_pairs`` (NaN where undefined, e.g. no contact at all).
    """
    c = tracking.contacts if contacts is None else contacts
    pos_err = np.linalg.norm(tracking.box.pos - truth.box_pos, axis=1)
    rot_err = np.degrees(angle_between(tracking.box.rot, truth.box_rot))
    tips = getattr(tracking, "fingertips", None)  # optional for a tracker other than the reference
    tip_err = np.linalg.norm(tips - truth.fingertip_pos, axis=-1) if tips is not None else np.full(1, np.nan)
    t_act = np.asarray(truth.contact_active, bool)
    both = c.active & t_act
    diff = (c.point - truth.contact_point)[both] * 1e3  # (P, 3) mm
    nan = float("nan")
    return {
        "frames": int(len(truth.t)),
        "box_pos_err_mm_median": float(np.median(pos_err) * 1e3),
        "box_rot_err_deg_median": float(np.median(rot_err)),
        "fingertip_err_mm_median": float(np.median(tip_err) * 1e3),
        "contact_pairs": int(both.sum()),
        "contact_err_mm_mean": float(diff.mean()) if diff.size else nan,
        "contact_err_mm_std": float(diff.std()) if diff.size else nan,
        "contact_err_mm_median_euclid": float(np.median(np.linalg.norm(diff, axis=1))) if diff.size else nan,
        "contact_recall": float(both.sum() / t_act.sum()) if t_act.any() else nan,
        "contact_precision": float(both.sum() / c.active.sum()) if c.active.any() else nan,
    }


def _project(calib: Calibration, pts: np.ndarray) -> np.ndarray:
    T = calib.T_world_cam
    p = (pts - T[:3, 3]) @ T[:3, :3]
    return np.stack([calib.K[0, 0] * p[..., 0] / p[..., 2] + calib.K[0, 2],
                     calib.K[1, 1] * p[..., 1] / p[..., 2] + calib.K[1, 2]], -1)


_BOX_EDGES = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5), (2, 6), (3, 7)]


def plot_overlay(depth: DepthVideo, calib: Calibration, tracking: Tracking, object_model: ObjectModel,
                 hand_model: HandModel, path: str | os.PathLike, frames: int = 6, truth: Truth | None = None) -> Path:
    """A PNG strip: depth frames (grey: near dark, far light) with the tracked box (green), hand
    capsules (orange), fingertips (red: seen, white: hidden) and active contact points (cyan crosses)
    drawn over them; with ``truth``, the true box (white dashed), hand (faint white) and contact
    points (magenta plus signs) beneath. A legend under the strip names every mark.

    Args:
        depth: The depth video.
        calib: Its calibration.
        tracking: The tracker's output.
        object_model: The box (its size).
        hand_model: The hand (its capsules).
        path: Where to write the PNG (atomically).
        frames: How many evenly spaced frames to show.
        truth: The episode's truth, drawn faintly for comparison (None: the estimate only).

    Returns:
        The path written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    T = depth.num_frames
    idx = np.unique(np.linspace(0, T - 1, max(1, min(frames, T))).round().astype(int))
    fig, axes = plt.subplots(1, len(idx), figsize=(3.2 * len(idx), 3.4), squeeze=False)
    half = object_model.half_extents
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    # One crop for the whole strip: the tracked box and hand over the shown frames, plus a margin.
    hand_qpos = getattr(tracking, "hand_qpos", None)  # a tracker other than the reference may have no hand
    tips_all = getattr(tracking, "fingertips", None)
    pts = []
    for i in idx:
        pts.append(_project(calib, tracking.box.pos[i] + (signs * half) @ tracking.box.rot[i].T))
        if hand_qpos is not None:
            ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, hand_qpos[i]))
            pts.append(_project(calib, ends.reshape(-1, 3)))
    uv = np.concatenate(pts)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    lo = np.maximum(np.floor(uv.min(0)) - 25, 0) if uv.size else np.zeros(2)
    hi = np.minimum(np.ceil(uv.max(0)) + 25, [calib.width - 1, calib.height - 1]) if uv.size else np.array(
        [calib.width - 1, calib.height - 1])
    for ax, i in zip(axes[0], idx):
        d = np.where(depth.depth_m[i] > 0, depth.depth_m[i], np.nan)
        crop = d[int(lo[1]) : int(hi[1]) + 1, int(lo[0]) : int(hi[0]) + 1]
        vmin, vmax = (np.nanpercentile(crop, 1), np.nanpercentile(crop, 99)) if np.isfinite(crop).any() else (0, 1)
        ax.imshow(d, cmap="Greys_r", vmin=vmin, vmax=vmax)
        if truth is not None:
            corners = truth.box_pos[i] + (signs * half) @ truth.box_rot[i].T
            uv = _project(calib, corners)
            ax.add_collection(LineCollection([uv[[a, b]] for a, b in _BOX_EDGES], colors="white", linewidths=1.0,
                                             linestyles="--", alpha=0.8))
            ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, truth.hand_qpos[i]))
            uv = _project(calib, ends.reshape(-1, 3)).reshape(-1, 2, 2)
            ax.add_collection(LineCollection(uv, colors="white", linewidths=2.5, alpha=0.3, capstyle="round"))
            act_t = np.asarray(truth.contact_active[i], bool)
            if act_t.any():
                uv = _project(calib, truth.box_pos[i] + truth.contact_point[i, act_t] @ truth.box_rot[i].T)
                ax.scatter(uv[:, 0], uv[:, 1], marker="+", s=40, c="magenta", zorder=3, linewidths=1.0)
        corners = tracking.box.pos[i] + (signs * half) @ tracking.box.rot[i].T
        uv = _project(calib, corners)
        ax.add_collection(LineCollection([uv[[a, b]] for a, b in _BOX_EDGES], colors="lime", linewidths=1.2))
        if hand_qpos is not None:
            ends = capsule_endpoints(hand_model, forward_kinematics_qpos(hand_model, hand_qpos[i]))
            depth_mid = ((ends[:, 0] + ends[:, 1]) / 2 - calib.T_world_cam[:3, 3]) @ calib.T_world_cam[:3, 2]
            px = hand_model.geom_radius * calib.K[0, 0] / np.maximum(1e-3, depth_mid)  # capsule radius in pixels
            uv = _project(calib, ends.reshape(-1, 3)).reshape(-1, 2, 2)
            ax.add_collection(LineCollection(uv, colors="orange", linewidths=np.maximum(1.0, 1.4 * px), alpha=0.55,
                                             capstyle="round"))
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
        ax.set_title(f"t = {depth.t[i]:.2f} s", fontsize=8)
        ax.set_xlim(lo[0], hi[0])
        ax.set_ylim(hi[1], lo[1])
        ax.axis("off")
    from matplotlib.lines import Line2D

    marks = [Line2D([], [], color="lime", lw=1.2, label="tracked box"),
             Line2D([], [], color="orange", lw=3, alpha=0.55, label="tracked hand"),
             Line2D([], [], color="red", marker="o", ls="", ms=4, label="fingertip (seen)"),
             Line2D([], [], color="white", markeredgecolor="red", marker="o", ls="", ms=4, label="fingertip (hidden)"),
             Line2D([], [], color="cyan", marker="x", ls="", ms=6, label="tracked contact")]
    if truth is not None:
        marks += [Line2D([], [], color="grey", lw=1.0, ls="--", label="true box"),
                  Line2D([], [], color="grey", lw=2.5, alpha=0.4, label="true hand"),
                  Line2D([], [], color="magenta", marker="+", ls="", ms=7, label="true contact")]
    fig.legend(handles=marks, loc="lower center", ncol=len(marks), fontsize=7, frameon=False)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    path = write_bytes(path, buf.getvalue())
    return path


# --- the ``tracking`` stage of fsv-bench --------------------------------------------------------

PAPER_CONTACT_ERROR_MM = {"mean": -1.55, "std": 6.13}
GATES = {
    "box_pos_err_mm_median": ("<=", 2.0),
    "box_rot_err_deg_median": ("<=", 1.5),
    "contact_err_mm_mean_abs": ("<=", 2.0),
    "contact_err_mm_std": ("<=", 4.0),
    "contact_recall": (">=", 0.9),
    "contact_precision": (">=", 0.9),
}
"""The issue's accuracy gates (on ``lift`` with 1 cm noise); the report says which ones hold."""


def gate_report(scores: dict) -> dict:
    """Pass/fail of every gate of :data:`GATES` for a scores dict (NaN fails)."""
    value = dict(scores, contact_err_mm_mean_abs=abs(scores["contact_err_mm_mean"]))
    out = {}
    for key, (op, limit) in GATES.items():
        v = value[key]
        ok = bool(np.isfinite(v) and (v <= limit if op == "<=" else v >= limit))
        out[key] = {"value": float(v), "limit": f"{op} {limit}", "pass": ok}
    return out


def add_arguments(parser) -> None:
    """Options of the tracking stage of ``fsv-bench``."""
    parser.add_argument("--init-perturbation", type=float, default=1.0, metavar="SCALE",
                        help="scale of the tracker's seeded first-frame perturbation (0 = the exact start; "
                             "see benchmark.method.init.INIT_PERTURBATION)")


def run_stage(run) -> None:
    """Runs the method on the rendered episode's camera inputs (the one entry,
    :func:`benchmark.method.run_method`); adds the ``tracking`` block and the overlay.

    The estimate (tracking, kinematics, forces) is what the later stages (kinematics, forces,
    learning, verdict) score.
    """
    from benchmark.method import camera_input, run_method

    ep = run.episode
    scale = float(run.args.init_perturbation)
    if not (np.isfinite(scale) and scale >= 0):
        from benchmark.errors import ScenarioError

        raise ScenarioError(f"--init-perturbation must be a scale >= 0, got {scale!r}")
    run.estimate = run_method(run.method_spec, ep, inputs=camera_input(ep, scale), progress=not run.args.quiet)
    tracking = run.tracking = run.estimate.tracking
    elapsed = run.estimate.timing_s["track"]
    stages = dict(getattr(tracking, "timing_s", None) or {})
    first = float(getattr(tracking, "first_frame_s", 0.0))
    scores = score_tracking(tracking, ep.truth)
    run.out.mkdir(parents=True, exist_ok=True)
    overlay = run.out / "tracking_overlay.png"
    background_of(run).process("tracking overlay", plot_overlay, ep.depth, ep.calib, tracking, ep.object_model,
                           ep.hand_model, overlay, truth=ep.truth)
    T = len(ep.truth.t)
    block = {
        **scores,
        "paper_contact_err_mm": PAPER_CONTACT_ERROR_MM,
        "gates": gate_report(scores),
        "frames_per_s": T / elapsed,
        "frames_per_s_after_first": (T - 1) / (elapsed - first) if T > 1 and elapsed > first else float("nan"),
        "first_frame_s": first,
        "stage_ms_per_frame": {k: 1e3 * v / T for k, v in stages.items()},
        "tracker": run.estimate.labels.get("tracker"),
        "init_perturbation": {k: float(v) * scale for k, v in INIT_PERTURBATION.items()},
        "overlay": overlay.name,
    }
    run.summary["tracking"] = block
    failed = [k for k, g in block["gates"].items() if not g["pass"]]
    run.lines.append(
        f"tracking [{run.estimate.labels.get('tracker')}] ({block['frames_per_s_after_first']:.1f} frames/s after the "
        f"first frame, which took {first:.1f} s with any compilation): box {scores['box_pos_err_mm_median']:.2f} mm / "
        f"{scores['box_rot_err_deg_median']:.2f} deg (median), fingertips {scores['fingertip_err_mm_median']:.1f} mm, "
        f"contact point {scores['contact_err_mm_mean']:+.2f} ± {scores['contact_err_mm_std']:.2f} mm per axis "
        f"(paper -1.55 ± 6.13), median {scores['contact_err_mm_median_euclid']:.1f} mm, recall "
        f"{scores['contact_recall']:.2f}, precision {scores['contact_precision']:.2f}; "
        + ("all gates hold" if not failed else f"gates NOT met: {', '.join(failed)}")
        + f"; overlay {overlay.name}"
    )
