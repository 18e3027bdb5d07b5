"""Human-readable and JSON summaries of a run (docs/design.md, "Results schema").

``summary.json`` is a dict of blocks: ``scenario`` and ``world`` (this module), ``timing_s``, one
block per later stage (kinematics, tracking, forces, learning) added by that stage, and
``provenance`` (code, libraries, BLAS kernel and CPU: :func:`fsv.provenance.provenance`). Only
blocks that were really computed are written.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np

from benchmark.atomic import write_text
from benchmark.suites.evaluate import strict
from benchmark.world.episode import Episode
from benchmark.world.grasp_plan import grasp_spec
from benchmark.world.people import person_record


def scenario_block(episode: Episode) -> dict:
    """The ``scenario`` block: task, user, grasp, mass, sensor, hand_surface, grip_control, noise_m, seed, frames, fps, and the
    ``person`` (``benchmark.world.people.person_record``: name, anatomy, grip style) and the
    ``grasp_spec`` (family and spots, ``benchmark.world.grasp_plan.grasp_spec``)."""
    sc = episode.scenario
    return {"task": sc.task, "user": sc.user, "grasp": sc.grasp, "mass": sc.mass, "sensor": sc.sensor,
            "hand_surface": sc.hand_surface, "grip_control": sc.grip_control, "noise_m": sc.noise_m, "seed": sc.seed, "frames": int(len(episode.truth.t)), "fps": sc.fps,
            "person": person_record(sc.user), "grasp_spec": grasp_spec(sc)}


def max_slip_m(episode: Episode) -> float:
    """Largest drift of a finger's centre of pressure on the box while held, [m].

    For every finger in contact throughout the held frames, the distance of its contact point
    (object frame) from where it was at the first held frame; the maximum over fingers and frames.
    """
    tr = episode.truth
    held = tr.held if tr.held is not None else np.ones(len(tr.t), bool)
    if not held.any():
        return 0.0
    cp, act = tr.contact_point[held], tr.contact_active[held]
    slip = 0.0
    for k in range(act.shape[1]):
        if act[:, k].all():
            slip = max(slip, float(np.linalg.norm(cp[:, k] - cp[0, k], axis=1).max()))
    return slip


def world_block(episode: Episode, steps_per_s: float | None = None) -> dict:
    """The ``world`` block: what happened in the simulation and how well the truth holds together.

    Keys: ``lift_height_m`` (highest box centre above its start), ``max_slip_mm`` (see
    :func:`max_slip_m`), ``grip_n`` (per finger in contact while held: min and max normal force),
    ``ne_force_residual_n`` / ``ne_torque_residual_nm`` (largest Newton-Euler residuals over all
    frames), ``held_frames``, ``sliding_frames`` and ``steps_per_s``.
    """
    tr = episode.truth
    held = tr.held if tr.held is not None else np.ones(len(tr.t), bool)
    fn = tr.normal_force()
    grip = {}
    for k, name in enumerate(tr.finger_names):
        mask = held & tr.contact_active[:, k]
        if mask.any():
            grip[str(name)] = {"min": float(fn[mask, k].min()), "max": float(fn[mask, k].max())}
    res_f, res_t = tr.newton_euler_residual()
    out = {
        "lift_height_m": float(tr.box_pos[:, 2].max() - tr.box_pos[0, 2]),
        "max_slip_mm": 1000 * max_slip_m(episode),
        "grip_n": grip,
        "ne_force_residual_n": float(np.abs(res_f).max()),
        "ne_torque_residual_nm": float(np.abs(res_t).max()),
        "held_frames": int(held.sum()),
        "sliding_frames": int((tr.contact_sliding & held[:, None]).any(axis=1).sum()),
    }
    if steps_per_s is not None:
        out["steps_per_s"] = float(steps_per_s)
    return out


def format_world(block: dict) -> str:
    """A few lines for humans from a ``world`` block."""
    lines = [
        f"box lifted {1000 * block['lift_height_m']:.0f} mm, max slip while held {block['max_slip_mm']:.2f} mm, "
        f"{block['held_frames']} held frames ({block['sliding_frames']} with a sliding finger)",
        "grip while held [N]: " + ", ".join(f"{k} {v['min']:.1f}-{v['max']:.1f}" for k, v in block["grip_n"].items()),
        f"Newton-Euler residual: {block['ne_force_residual_n']:.1e} N, {block['ne_torque_residual_nm']:.1e} N m",
    ]
    if "steps_per_s" in block:
        lines.append(f"simulation speed: {block['steps_per_s']:.0f} steps/s")
    return "\n".join(lines)


def write_json(path, data: dict) -> pathlib.Path:
    """Writes strict JSON atomically (temp file in the same directory, then os.replace).

    NaN and infinities (a metric with nothing to score) become null, so strict readers accept the file.
    """

    path = write_text(path, json.dumps(strict(data), indent=2, sort_keys=False, allow_nan=False) + "\n")
    return path
