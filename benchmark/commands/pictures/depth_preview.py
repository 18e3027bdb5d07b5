"""Pictures of a depth video a person can look at: a PNG strip of frames and an animated GIF.

Depth is shown with matplotlib's "turbo" colour map over the sensor's range (near = blue,
far = red); pixels without a measurement are black. The PNG strip carries a colour bar in metres.
"""

from __future__ import annotations

import pathlib

import numpy as np

from benchmark.atomic import atomic_path
from benchmark.errors import BenchmarkError


def colorize(depth_m: np.ndarray, near_m: float = 0.15, far_m: float = 1.0) -> np.ndarray:
    """Colour-maps depth images.

    Args:
        depth_m: Depth, shape (..., H, W), [m]; 0 = no measurement.
        near_m: Depth shown at the blue end of the map, [m].
        far_m: Depth shown at the red end, [m].

    Returns:
        RGB images, shape (..., H, W, 3), uint8; missing pixels black.
    """
    from matplotlib import colormaps

    if not far_m > near_m:
        raise BenchmarkError(f"preview range needs far_m > near_m, got {near_m}, {far_m}")
    d = np.asarray(depth_m, dtype=np.float64)
    rgb = colormaps["turbo"](np.clip((d - near_m) / (far_m - near_m), 0, 1))[..., :3]
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

    The strip is quantised to 64 colours; the animation uses the colour map's own 255-entry
    palette (index = depth level, black = no measurement), which is exact and fast.

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
    png = _palette(np.concatenate([frames, colour_bar(frames.shape[1])], axis=0))
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


COLOUR_BAR_HEIGHT = 40
"""Height in pixels of the colour bar under the PNG strip."""


def colour_bar(width: int, near_m: float = 0.15, far_m: float = 1.0) -> np.ndarray:
    """A labelled colour bar of the depth colour map, shape (COLOUR_BAR_HEIGHT, width, 3), uint8.

    The gradient spans the middle of the strip from ``near_m`` to ``far_m`` with ticks every 0.1 m,
    and a black swatch labels "no measurement".
    """
    from PIL import Image, ImageDraw

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


def _indexed(depth_m: np.ndarray, near_m: float = 0.15, far_m: float = 1.0):
    """A depth image as a palette image: index 0 black (no measurement), 1..255 the turbo map."""
    from matplotlib import colormaps
    from PIL import Image

    d = np.asarray(depth_m, dtype=np.float32)
    idx = 1 + np.rint(np.clip((d - near_m) / (far_m - near_m), 0, 1) * 254).astype(np.uint8)
    idx[d <= 0] = 0
    palette = np.zeros((256, 3), dtype=np.uint8)
    palette[1:] = np.round(colormaps["turbo"](np.linspace(0, 1, 255))[:, :3] * 255)
    img = Image.fromarray(idx, mode="P")
    img.putpalette(palette.ravel().tolist())
    return img


def _palette(rgb: np.ndarray):
    from PIL import Image

    return Image.fromarray(rgb).quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)


def _atomic(path: pathlib.Path, write) -> None:
    with atomic_path(path) as tmp:
        write(tmp)


def _stamp(img: np.ndarray, text: str) -> np.ndarray:
    """Writes `text` in white on a black box at the top left of an RGB image."""
    from PIL import Image, ImageDraw

    pil = Image.fromarray(img)
    draw = ImageDraw.Draw(pil)
    box = draw.textbbox((4, 2), text)
    draw.rectangle((box[0] - 2, box[1] - 2, box[2] + 2, box[3] + 2), fill=(0, 0, 0))
    draw.text((4, 2), text, fill=(255, 255, 255))
    return np.asarray(pil)
