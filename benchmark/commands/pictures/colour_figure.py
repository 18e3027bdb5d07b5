"""Pictures of the colour stream for the docs: three drawn people of different skin tones, their
colour and depth frames, the labels over both streams, and a frame blurred by a shake.

    python -m benchmark.commands.pictures.colour_figure --out docs/pictures

Writes three PNGs (:data:`FILES`):

- ``colour_depth.png``: per person, a colour frame beside the depth frame taken at the same time,
  each whole, in its own resolution (colour 640 x 480, depth 320 x 240; depth in the turbo map of
  :func:`benchmark.commands.pictures.depth_preview.colorize`, black: no measurement);
- ``colour_labels.png``: the same frames cropped around the hand and the box, with the
  segmentation (hand, box, table, background, translucent) and the 21 keypoints (coloured by digit,
  OpenPose's skeleton; a filled dot: visible, a cross: not visible) drawn over each stream in that
  stream's own pixels (``episode.colour_labels`` and ``annotations.streams["colour"]`` on the colour,
  ``episode.labels`` and ``annotations.streams["depth"]`` on the depth);
- ``colour_blur.png``: a frame of a ``shake`` taken at the fastest image motion of the hand's
  visible keypoints, as the sensor records it (exposure 1/60 s) beside the same frame with zero
  exposure (the same sensor, camera and noise draws: only the blur differs).

The people (:data:`SHOTS`) are the first drawn users (N >= 5) of Monk tones 2, 6 and 9
(:func:`benchmark.camera.appearance.people_with_tone`); their grasps and views were chosen by
looking at every grasp 0-2 in views 0, 1, 5 and 13 of a 2 s lift for views that show the fingers
(not the palm's back alone) and differ from one another; the seeds 1-4 are fixed, not chosen.
The frame shown of a lift is the middle one of the frames in which the hand holds the box.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import pathlib

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgb
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from PIL import Image

from benchmark.atomic import write_bytes
from benchmark.camera.annotations import SEGMENTATION_CLASSES, segmentation
from benchmark.camera.appearance import people_with_tone
from benchmark.camera.colour import render_colour
from benchmark.camera.colour_sensor import colour_preset
from benchmark.camera.keypoints import DIGITS
from benchmark.camera.render import render
from benchmark.commands.pictures.depth_preview import colorize
from benchmark.errors import BenchmarkError
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from benchmark.world.tasks.shake import CENTRE_M

FILES = ("colour_depth.png", "colour_labels.png", "colour_blur.png")
"""The pictures :func:`write_colour_figures` writes, in order."""

FIRST_DRAWN_USER = 5
"""Users 0-4 are the named cohort; the pictures show drawn people."""


@dataclasses.dataclass(frozen=True)
class Shot:
    """One person's episode in the pictures.

    Attributes:
        tone: The Monk Skin Tone index (1..10) of the person: the first drawn user of that tone.
        grasp: The grasp index.
        view: The camera view.
        seed: The scenario's seed (the box's print, the table, the lights).
        task: The task.
    """

    tone: int
    grasp: int
    view: int
    seed: int
    task: str = "lift"


SHOTS = (Shot(tone=2, grasp=1, view=13, seed=1), Shot(tone=6, grasp=0, view=1, seed=2),
         Shot(tone=9, grasp=2, view=0, seed=3))
"""The three people of :func:`write_colour_figures` (module docstring for how they were chosen)."""

BLUR_SHOT = Shot(tone=6, grasp=0, view=1, seed=4, task="shake")
"""The shake of the blur picture."""

DIGIT_COLOURS = ("#e41a1c", "#ff7f00", "#4daf4a", "#377eb8", "#984ea3")
"""Keypoint and skeleton colours per digit, thumb to little finger; the wrist is white."""

SEGMENT_COLOURS = {0: "#3b4cc0", 1: "#ffd92f", 2: "#00bcd4", 3: "#ff1493"}
"""Translucent mask colour per segmentation class (background, table, box, hand)."""

MASK_ALPHA = 0.35
"""Opacity of the masks over the images."""

SKELETON = tuple((0 if j == 0 else 1 + 4 * d + j - 1, 1 + 4 * d + j) for d in range(5) for j in range(4))
"""OpenPose's hand skeleton: the wrist to each digit's base joint, then along the digit, (20 pairs)."""


def person_of(shot: Shot) -> int:
    """The user index of a shot: the first drawn user of its Monk tone."""

    return people_with_tone(shot.tone, 1, start=FIRST_DRAWN_USER)[0]


def scenario_of(shot: Shot, duration_s: float, fps: float = 30.0):
    """The :class:`benchmark.world.scenario.Scenario` of a shot."""

    return Scenario(task=shot.task, user=person_of(shot), grasp=shot.grasp, view=shot.view, seed=shot.seed,
                    duration_s=float(duration_s), fps=float(fps))


def rendered(scenario):
    """The scenario simulated and rendered with both streams and their labels."""

    return render(simulate(scenario), streams=("depth", "colour"))


def held_frame(episode) -> int:
    """The middle frame of those in which the hand holds the box (the middle frame if none)."""
    held = np.flatnonzero(np.asarray(episode.truth.held, bool))
    return int(held[len(held) // 2]) if len(held) else len(episode.truth.t) // 2


def image_speed(labels, k: int) -> float:
    """How fast the hand moves in a stream's pixels at frame k: the median over the keypoints
    visible at k - 1, k and k + 1 of |uv[k+1] - uv[k-1]| / 2 [px per frame] (-1 if none is).

    Args:
        labels: A :class:`benchmark.camera.labelling.StreamLabels`.
        k: A frame, 1..T-2.
    """
    uv, vis = labels.keypoints_uv, labels.keypoint_visibility
    seen = (vis[k - 1] == 0) & (vis[k] == 0) & (vis[k + 1] == 0)
    if not seen.any():
        return -1.0
    d = uv[k + 1, seen] - uv[k - 1, seen]
    return float(np.median(np.sqrt(d[:, 0] ** 2 + d[:, 1] ** 2))) / 2


def shaking_frames(truth) -> np.ndarray:
    """The frames of a ``shake`` from the box's first reaching the oscillation's centre
    (:data:`benchmark.world.tasks.shake.CENTRE_M` above its start) while held, to the last held
    frame: the oscillation, without the lift before it."""

    held = np.asarray(truth.held, bool)
    up = held & (truth.box_pos[:, 2] - truth.box_pos[0, 2] >= CENTRE_M)
    if not up.any():
        raise BenchmarkError("the box never reaches the shake's centre height: no oscillation to show")
    first, last = int(np.flatnonzero(up)[0]), int(np.flatnonzero(held)[-1])
    return np.arange(first, last + 1)


def fastest_frame(labels, frames=None) -> int:
    """The frame in which the hand moves fastest in a stream's pixels (:func:`image_speed`),
    among ``frames`` (default every frame 1..T-2; the first and the last have no neighbours).

    Args:
        labels: A :class:`benchmark.camera.labelling.StreamLabels`.
        frames: Candidate frames.
    """
    T = len(labels.keypoints_uv)
    if T < 3:
        raise BenchmarkError(f"the fastest frame needs at least 3 frames, got {T}")
    frames = range(1, T - 1) if frames is None else [int(k) for k in frames if 1 <= k <= T - 2]
    best, speed = None, -1.0
    for k in frames:
        s = image_speed(labels, k)
        if s > speed:
            best, speed = k, s
    if best is None:
        raise BenchmarkError("no candidate frame shows the hand")
    return best


def crop_of(label_image: np.ndarray, uv: np.ndarray, margin: float = 0.2, min_px: int = 24) -> tuple:
    """A square-ish crop around the hand and the box in one stream's pixels: the bounding box of
    their labels (>= 2) and of the keypoints on the image, widened by ``margin`` of its size on
    each side (at least ``min_px`` across), clipped to the image: ``(u0, u1, v0, v1)``, ends excluded."""
    H, W = label_image.shape
    vv, uu = np.nonzero(label_image >= 2)
    pts = uv[np.all(np.isfinite(uv), axis=1)]
    pts = pts[(pts[:, 0] >= 0) & (pts[:, 0] < W) & (pts[:, 1] >= 0) & (pts[:, 1] < H)]
    us = np.concatenate([uu, pts[:, 0]]) if len(uu) or len(pts) else np.array([0, W - 1])
    vs = np.concatenate([vv, pts[:, 1]]) if len(vv) or len(pts) else np.array([0, H - 1])
    cu, cv = (us.min() + us.max()) / 2, (vs.min() + vs.max()) / 2
    half = max(us.max() - us.min(), vs.max() - vs.min(), min_px) * (0.5 + margin)
    u0, v0 = int(max(0, np.floor(cu - half))), int(max(0, np.floor(cv - half)))
    u1, v1 = int(min(W, np.ceil(cu + half) + 1)), int(min(H, np.ceil(cv + half) + 1))
    return u0, u1, v0, v1


def mask_rgba(label_image: np.ndarray) -> np.ndarray:
    """The segmentation as a translucent RGBA image, (H, W, 4) float in [0, 1]
    (:data:`SEGMENT_COLOURS`, :data:`MASK_ALPHA`)."""

    seg = segmentation(label_image)
    out = np.zeros(seg.shape + (4,))
    for c, colour in SEGMENT_COLOURS.items():
        out[seg == c] = (*to_rgb(colour), MASK_ALPHA)
    return out


def draw_keypoints(ax, uv: np.ndarray, visibility: np.ndarray, size: float = 5.0) -> None:
    """The 21 keypoints of one frame over an axes in that stream's pixels: skeleton lines and a
    filled dot (visible) or a cross (not visible), coloured by digit, the wrist white."""
    colours = ["white"] + [c for c in DIGIT_COLOURS for _ in range(4)]
    for a, b in SKELETON:
        if np.all(np.isfinite(uv[[a, b]])):
            ax.plot(uv[[a, b], 0], uv[[a, b], 1], "-", color=colours[b], lw=1.2, alpha=0.9, zorder=3)
    for i in range(21):
        if not np.all(np.isfinite(uv[i])):
            continue
        if visibility[i] == 0:
            ax.plot(*uv[i], "o", ms=size, mfc=colours[i], mec="black", mew=0.6, zorder=4)
        else:
            ax.plot(*uv[i], "x", ms=size, color=colours[i], mew=1.6, zorder=4)


def _depth_rgb(depth_m: np.ndarray) -> np.ndarray:
    return colorize(depth_m)


def _grey_depth(depth_m: np.ndarray, crop: tuple) -> np.ndarray:
    """Depth as grey levels over the crop's range (near dark, far light), black where missing, (H, W, 3)."""
    u0, u1, v0, v1 = crop
    d = np.asarray(depth_m, dtype=float)
    inside = d[v0:v1, u0:u1]
    valid = inside[inside > 0]
    lo, hi = (np.percentile(valid, 1), np.percentile(valid, 99)) if valid.size else (0.0, 1.0)
    g = np.clip((d - lo) / max(hi - lo, 1e-6), 0, 1) * 0.8 + 0.1
    g[d <= 0] = 0.0
    return np.repeat(g[..., None], 3, axis=-1)


PALETTE_COLOURS = 256
"""The pictures are palette PNGs of this many colours (Pillow's fast octree, no dithering): the
sensor's noise makes an RGB PNG of a colour frame about 400 kB on its own; the palette keeps each
picture under 400 kB, within 7 codes of the RGB rendering at 99 % of the pixels (mean 1.3)."""


def _save(fig, path) -> pathlib.Path:
    """Saves a figure as a palette PNG (:data:`PALETTE_COLOURS`), atomically."""

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=fig.dpi)
    plt.close(fig)
    img = Image.open(io.BytesIO(buf.getvalue())).convert("RGB")
    img = img.quantize(colors=PALETTE_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
    out = io.BytesIO()
    img.save(out, format="PNG", optimize=True)
    return write_bytes(path, out.getvalue())


def _title(shot: Shot, episode, k: int) -> str:
    sc = episode.scenario
    return f"MST{shot.tone}, user {sc.user}, {sc.task} g{sc.grasp} v{sc.view} s{sc.seed}, t = {k / sc.fps:.2f} s"


def _legend(fig) -> None:
    handles = [Patch(color=SEGMENT_COLOURS[c], alpha=0.6, label=name) for c, name in SEGMENTATION_CLASSES.items()]
    handles += [Line2D([], [], color=c, marker="o", mec="black", ls="-", label=d) for d, c in zip(DIGITS, DIGIT_COLOURS)]
    handles += [Line2D([], [], color="white", marker="o", mec="black", ls="", label="wrist"),
                Line2D([], [], color="grey", marker="o", mec="black", ls="", label="visible"),
                Line2D([], [], color="grey", marker="x", mew=1.6, ls="", label="not visible")]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=8, frameon=False)


def figure_colour_depth(shown: list, path) -> pathlib.Path:
    """``colour_depth.png``: per person a row, its colour frame beside its depth frame.

    Args:
        shown: ``(shot, episode, frame)`` per person.
        path: Where to write.
    """

    matplotlib.use("Agg")

    fig, axes = plt.subplots(len(shown), 2, figsize=(8.4, 3.3 * len(shown)), dpi=100, squeeze=False)
    for row, (shot, ep, k) in zip(axes, shown):
        c, d = ep.colour.calib, ep.calib
        row[0].imshow(ep.colour.rgb[k], interpolation="antialiased")
        row[0].set_title(f"colour {c.width} x {c.height}: " + _title(shot, ep, k), fontsize=8)
        row[1].imshow(_depth_rgb(ep.depth.depth_m[k]), interpolation="nearest")
        row[1].set_title(f"depth {d.width} x {d.height} (turbo, 0.15-1.0 m; black: no measurement)", fontsize=8)
        for a in row:
            a.axis("off")
    fig.tight_layout()
    return _save(fig, path)


def figure_labels(shown: list, path) -> pathlib.Path:
    """``colour_labels.png``: per person a row, the colour and the depth frame cropped around the
    hand and the box, masks and keypoints over each in its own pixels.

    Args:
        shown: ``(shot, episode, frame)`` per person.
        path: Where to write.
    """

    matplotlib.use("Agg")

    fig, axes = plt.subplots(len(shown), 2, figsize=(8.0, 4.0 * len(shown) + 0.7), dpi=100, squeeze=False)
    for row, (shot, ep, k) in zip(axes, shown):
        for ax, stream in zip(row, ("colour", "depth")):
            labels = ep.annotations.streams[stream]
            label_image = ep.colour_labels[k] if stream == "colour" else ep.labels[k]
            uv, vis = labels.keypoints_uv[k], labels.keypoint_visibility[k]
            u0, u1, v0, v1 = crop = crop_of(label_image, uv)
            image = ep.colour.rgb[k] if stream == "colour" else _grey_depth(ep.depth.depth_m[k], crop)
            ax.imshow(image, interpolation="nearest")
            ax.imshow(mask_rgba(label_image), interpolation="nearest")
            draw_keypoints(ax, uv, vis, size=5.0)
            ax.set_xlim(u0 - 0.5, u1 - 0.5)
            ax.set_ylim(v1 - 0.5, v0 - 0.5)
            ax.axis("off")
            seen = int(np.sum(vis == 0))
            ax.set_title(f"{_title(shot, ep, k)}\n{stream}, its own pixels {u0}-{u1 - 1} x {v0}-{v1 - 1}; "
                         f"{seen} of 21 keypoints visible", fontsize=8)
    _legend(fig)
    fig.tight_layout(rect=(0, 0.7 / fig.get_figheight(), 1, 1))
    return _save(fig, path)


def figure_blur(shot: Shot, episode, sharp, k: int, path) -> pathlib.Path:
    """``colour_blur.png``: frame ``k`` of a shake as recorded (exposure of the preset) beside the same
    frame with zero exposure, cropped around the hand and the box, with the image speed of the
    hand's visible keypoints.

    Args:
        shot: The shake's shot.
        episode: The rendered shake.
        sharp: Its colour frames rendered with zero exposure
            (:class:`benchmark.camera.colour.ColourFrames`).
        k: The frame.
        path: Where to write.
    """

    matplotlib.use("Agg")

    labels = episode.annotations.streams["colour"]
    uv = labels.keypoints_uv
    speed = max(image_speed(labels, k), 0.0)
    e = episode.colour.exposure_s
    blur = speed * e * episode.scenario.fps
    u0, u1, v0, v1 = crop_of(episode.colour_labels[k], uv[k], margin=0.12)
    fig, axes = plt.subplots(1, 2, figsize=(9.0, 5.0), dpi=100)
    for ax, rgb, title in ((axes[0], episode.colour.rgb[k], f"as recorded: exposure 1/{1 / e:.0f} s"),
                           (axes[1], sharp.rgb[k], "the same frame, zero exposure")):
        ax.imshow(rgb[v0:v1, u0:u1], interpolation="nearest")
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.suptitle(f"{_title(shot, episode, k)}\nthe hand moves {speed:.1f} px per frame in the image: "
                 f"a {blur:.1f} px streak over the exposure", fontsize=9)
    fig.tight_layout()
    return _save(fig, path)


def write_colour_figures(out_dir, *, shots: tuple = SHOTS, blur: Shot = BLUR_SHOT, duration_s: float = 2.0,
                         shake_duration_s: float = 3.0, fps: float = 30.0) -> list[pathlib.Path]:
    """Writes :data:`FILES` into ``out_dir`` (module docstring).

    Args:
        out_dir: The folder (created if missing).
        shots: The people of the first two pictures.
        blur: The shake of the third.
        duration_s: Length of each lift [s].
        shake_duration_s: Length of the shake [s] (the task's minimum is 3 s).
        fps: Frame rate [Hz].

    Returns:
        The paths written, in :data:`FILES` order.
    """

    if not shots:
        raise BenchmarkError("write_colour_figures needs at least one shot")
    out_dir = pathlib.Path(out_dir)
    shown = []
    for shot in shots:
        ep = rendered(scenario_of(shot, duration_s, fps))
        shown.append((shot, ep, held_frame(ep)))
    paths = [figure_colour_depth(shown, out_dir / FILES[0]), figure_labels(shown, out_dir / FILES[1])]
    shake = rendered(scenario_of(blur, shake_duration_s, fps))
    sensor = dataclasses.replace(colour_preset(shake.scenario.sensor), exposure_s=0.0)
    sharp = render_colour(shake, sensor=sensor)
    k = fastest_frame(shake.annotations.streams["colour"], shaking_frames(shake.truth))
    paths.append(figure_blur(blur, shake, sharp, k, out_dir / FILES[2]))
    return paths


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("docs/pictures"), help="folder of the PNGs")
    args = p.parse_args(argv)
    for path in write_colour_figures(args.out):
        print(f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main()
