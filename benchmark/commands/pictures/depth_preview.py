"""Pictures of a depth video a person can look at: a PNG strip of frames and an animated GIF.

Depth is shown with matplotlib's "turbo" colour map over the sensor's range (near = blue,
far = red), the map's dark ends left out (:data:`TURBO_SPAN`) so that no depth is drawn near the
black of pixels without a measurement. The PNG strip carries a colour bar in metres. Both pictures
are palette images over one fixed palette (:func:`palette`), so the colour bar shows exactly the
colours of the frames.
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.atomic import atomic_path
from benchmark.errors import BenchmarkError

TURBO_SPAN = (0.1, 0.93)
"""The part of the turbo map that depth is drawn with, near to far: its ends are near-black violet
(0.0) and dark brown (1.0), which would read as "no measurement"."""

DEPTH_LEVELS = 248
"""Entries of the palette given to depth (the rest: black, white and greys for the labels)."""

_LABEL_GREYS = (0, 255, 64, 128, 192, 224, 32, 160)
"""The palette's first entries: black (no measurement, text), white (gaps, background) and greys
(the labels' anti-aliased edges)."""


def colorize(depth_m: np.ndarray, near_m: float = 0.15, far_m: float = 1.0) -> np.ndarray:
    """Colour-maps depth images.

    Args:
        depth_m: Depth, shape (..., H, W), [m]; 0 = no measurement.
        near_m: Depth shown at the blue end of the map, [m].
        far_m: Depth shown at the red end, [m].

    Returns:
        RGB images, shape (..., H, W, 3), uint8; missing pixels black.
    """
    from matplotlib import colormaps  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    if not far_m > near_m:
        raise BenchmarkError(f"preview range needs far_m > near_m, got {near_m}, {far_m}")
    d = np.asarray(depth_m, dtype=np.float64)
    lo, hi = TURBO_SPAN
    rgb = colormaps["turbo"](lo + (hi - lo) * np.clip((d - near_m) / (far_m - near_m), 0, 1))[..., :3]
    rgb[d <= 0] = 0
    return np.round(rgb * 255).astype(np.uint8)


def strip(depth_m: np.ndarray, t: np.ndarray, num: int = 6, near_m: float = 0.15, far_m: float = 1.0) -> np.ndarray:
    """A horizontal strip of `num` evenly spaced frames, each stamped with its time.

    Args:
        depth_m: Depth video, shape (T, H, W), [m].
        t: Frame times, shape (T,), [s].
        num: Number of frames shown (fewer if the video is shorter).
        near_m, far_m: Colour-map range, [m].

    Returns:
        RGB image, shape (H, n * W + (n - 1) * 4, 3), uint8 (4-pixel white gaps).
    """
    depth_m = np.asarray(depth_m)
    if depth_m.ndim != 3 or depth_m.shape[0] == 0:
        raise BenchmarkError(f"a depth video of shape (T, H, W) with T >= 1 is needed, got {depth_m.shape}")
    if num < 1:
        raise BenchmarkError(f"num must be >= 1 frame, got {num}")
    idx = np.unique(np.linspace(0, depth_m.shape[0] - 1, min(num, depth_m.shape[0])).round().astype(int))
    frames = [_stamp(colorize(depth_m[k], near_m, far_m), f"{t[k]:.2f} s") for k in idx]
    gap = np.full((depth_m.shape[1], 4, 3), 255, dtype=np.uint8)
    out = [frames[0]]
    for f in frames[1:]:
        out += [gap, f]
    return np.concatenate(out, axis=1)


def write_preview(
    depth_m: np.ndarray, fps: float, out_dir, num: int = 6, gif: bool = True, gif_fps: float = 10.0
) -> list[pathlib.Path]:
    """Writes ``depth_preview.png`` (a strip of frames) and ``depth.gif`` (the video) to out_dir.

    Both are palette images over :func:`palette`: the strip is mapped onto it (its colours are the
    palette's, to within the 248 depth levels), the animation indexes it by depth level directly.

    Args:
        depth_m: Depth video, shape (T, H, W), [m].
        fps: Frame rate of the video, [Hz].
        out_dir: Directory (created if missing).
        num: Frames in the strip.
        gif: Also write the animation.
        gif_fps: Highest frame rate of the animation (frames are skipped evenly above it), [Hz].

    Returns:
        Paths of the files written.
    """
    if not (fps > 0 and gif_fps > 0):
        raise BenchmarkError(f"frame rates must be > 0, got fps={fps}, gif_fps={gif_fps}")
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t = np.arange(len(depth_m)) / fps
    paths = preview_paths(out_dir, gif)
    frames = strip(depth_m, t, num)
    png = _on_palette(np.concatenate([frames, colour_bar(frames.shape[1])], axis=0))
    _atomic(paths[0], lambda p: png.save(p, format="PNG", optimize=True))
    if gif:
        step = max(1, int(np.ceil(fps / gif_fps)))
        frames = [_indexed(d) for d in np.asarray(depth_m)[::step]]
        _atomic(
            paths[1],
            lambda p: frames[0].save(
                p, format="GIF", save_all=True, append_images=frames[1:], duration=1000 * step / fps, loop=0
            ),
        )
    return paths


def preview_paths(out_dir, gif: bool = True) -> list[pathlib.Path]:
    """The files :func:`write_preview` writes into ``out_dir``: the PNG strip, then the GIF if ``gif``."""
    out_dir = pathlib.Path(out_dir)
    return [out_dir / "depth_preview.png"] + ([out_dir / "depth.gif"] if gif else [])


def write_colour_preview(rgb: np.ndarray, fps: float, out_dir, num: int = 6) -> pathlib.Path:
    """Writes ``colour_preview.png``: a strip of ``num`` evenly spaced colour frames at half size,
    each stamped with its time (the colour stream as recorded: sRGB, not retouched).

    Args:
        rgb: Colour video, shape (T, H, W, 3), uint8.
        fps: Its frame rate, [Hz].
        out_dir: Directory (created if missing).

    Returns:
        The path written.
    """
    rgb = np.asarray(rgb)
    if rgb.ndim != 4 or rgb.shape[0] == 0 or rgb.shape[3] != 3 or rgb.dtype != np.uint8:
        raise BenchmarkError(f"a colour video (T, H, W, 3) uint8 with T >= 1 is needed, got {rgb.shape} {rgb.dtype}")
    from PIL import Image  # lazy: PIL (10 ms) off `fsv-bench`'s start-up

    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    idx = np.unique(np.linspace(0, rgb.shape[0] - 1, min(num, rgb.shape[0])).round().astype(int))
    frames = [_stamp(rgb[k, ::2, ::2], f"{k / fps:.2f} s") for k in idx]
    gap = np.full((frames[0].shape[0], 4, 3), 255, dtype=np.uint8)
    out = [frames[0]]
    for f in frames[1:]:
        out += [gap, f]
    path = out_dir / "colour_preview.png"
    _atomic(path, lambda p: Image.fromarray(np.concatenate(out, axis=1)).save(p, format="PNG", optimize=True))
    return path


COLOUR_BAR_HEIGHT = 40
"""Height in pixels of the colour bar under the PNG strip."""


def colour_bar(width: int, near_m: float = 0.15, far_m: float = 1.0) -> np.ndarray:
    """A labelled colour bar of the depth colour map, shape (COLOUR_BAR_HEIGHT, width, 3), uint8.

    The gradient spans the middle of the strip from ``near_m`` to ``far_m`` with ticks every 0.1 m,
    and a black swatch labels "no measurement".
    """
    from PIL import Image, ImageDraw  # lazy: PIL (10 ms) off `fsv-bench`'s start-up

    img = np.full((COLOUR_BAR_HEIGHT, width, 3), 255, np.uint8)
    x0, x1 = width // 4, 3 * width // 4
    ramp = np.linspace(near_m, far_m, x1 - x0)
    img[4:18, x0:x1] = colorize(np.broadcast_to(ramp, (14, x1 - x0)), near_m, far_m)
    pil = Image.fromarray(img)
    draw = ImageDraw.Draw(pil)
    if x0 >= 110:  # room for the "no measurement" swatch on the left
        draw.rectangle([x0 - 110, 4, x0 - 97, 17], fill=(0, 0, 0))
        draw.text((x0 - 92, 5), "no measurement", fill=(0, 0, 0))
    for d in np.arange(np.ceil(near_m * 10) / 10, far_m + 1e-9, 0.1):
        x = x0 + int(round((d - near_m) / (far_m - near_m) * (x1 - x0 - 1)))
        draw.line([(x, 18), (x, 21)], fill=(0, 0, 0))
        draw.text((x - 8, 23), f"{d:.1f}", fill=(0, 0, 0))
    draw.text((x1 + 8, 5), "depth along the optical axis [m]" if width - x1 > 200 else "[m]", fill=(0, 0, 0))
    return np.asarray(pil)


def palette() -> np.ndarray:
    """The pictures' palette, shape (256, 3), uint8: :data:`_LABEL_GREYS` (black first), then
    :data:`DEPTH_LEVELS` levels of the depth map from near to far."""
    from matplotlib import colormaps  # lazy: matplotlib (0.4 s) off `fsv-bench`'s start-up

    lo, hi = TURBO_SPAN
    out = np.empty((256, 3), dtype=np.uint8)
    out[:len(_LABEL_GREYS)] = np.array(_LABEL_GREYS, dtype=np.uint8)[:, None]
    out[len(_LABEL_GREYS):] = np.round(colormaps["turbo"](np.linspace(lo, hi, DEPTH_LEVELS))[:, :3] * 255)
    return out


def _indexed(depth_m: np.ndarray, near_m: float = 0.15, far_m: float = 1.0):
    """A depth image as a palette image over :func:`palette` (index 0 black: no measurement)."""
    from PIL import Image  # lazy: PIL (10 ms) off `fsv-bench`'s start-up

    d = np.asarray(depth_m, dtype=np.float32)
    level = np.rint(np.clip((d - near_m) / (far_m - near_m), 0, 1) * (DEPTH_LEVELS - 1)).astype(np.uint8)
    idx = len(_LABEL_GREYS) + level
    idx[d <= 0] = 0
    img = Image.fromarray(idx, mode="P")
    img.putpalette(palette().ravel().tolist())
    return img


def _on_palette(rgb: np.ndarray):
    """An RGB picture as a palette image over :func:`palette`, each pixel its nearest entry."""
    from PIL import Image  # lazy: PIL (10 ms) off `fsv-bench`'s start-up

    ref = Image.new("P", (1, 1))
    ref.putpalette(palette().ravel().tolist())
    return Image.fromarray(rgb).quantize(palette=ref, dither=Image.Dither.NONE)


def _atomic(path: pathlib.Path, write) -> None:
    with atomic_path(path) as tmp:
        write(tmp)


def _stamp(img: np.ndarray, text: str) -> np.ndarray:
    """Writes `text` in white on a black box at the top left of an RGB image."""
    from PIL import Image, ImageDraw  # lazy: PIL (10 ms) off `fsv-bench`'s start-up

    pil = Image.fromarray(img)
    draw = ImageDraw.Draw(pil)
    box = draw.textbbox((4, 2), text)
    draw.rectangle((box[0] - 2, box[1] - 2, box[2] + 2, box[3] + 2), fill=(0, 0, 0))
    draw.text((4, 2), text, fill=(255, 255, 255))
    return np.asarray(pil)
