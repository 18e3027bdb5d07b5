"""The render stage: the episode's depth video from its sensor; the ``render`` block and the depth preview."""

from __future__ import annotations

import numpy as np

from benchmark.camera.appearance import appearance_of
from benchmark.camera.colour_sensor import colour_preset
from benchmark.camera.depth import RASTERISER
from benchmark.camera.episode_file import save_episode
from benchmark.camera.render import render
from benchmark.camera.scene import LABEL_BOX
from benchmark.camera.views import view_of
from benchmark.commands.pictures.depth_preview import preview_paths, write_colour_preview, write_preview
from benchmark.commands.stage import Picture, Run, Stage, StageResult
from benchmark.suites.options import add_streams_argument
from fsv.types import check_streams


def add_arguments(parser) -> None:
    """Options of the render stage of ``fsv-bench``."""
    parser.add_argument("--no-gif", action="store_true", help="write the PNG depth preview but no animated GIF")
    add_streams_argument(parser)


def run(record: Run, options) -> StageResult:
    """Renders the run's episode (the streams ``--streams`` asks for and those the method reads);
    the depth preview is drawn beside the next stages."""
    episode = render(record.episode, streams=check_streams([*options["streams"], *record.method_spec.streams]))
    depth = episode.depth
    gif = not options["no_gif"]
    paths = preview_paths(record.out, gif=gif)
    T, H, W = depth.depth_m.shape
    block = {
        "frames": T,
        "width": W,
        "height": H,
        "fps": depth.fps,
        "noise_m": record.scenario.noise_m,
        "rasteriser": RASTERISER,
        "view": view_of(record.scenario.view).record(),
        "valid_fraction": float(np.mean(depth.depth_m > 0)),
        "box_pixels_median": float(np.median(np.sum(episode.labels == LABEL_BOX, axis=(1, 2)))),
        "preview": [p.name for p in paths],
    }
    lines = [f"render: {T} depth frames {W}x{H} at {depth.fps:g} Hz, noise {record.scenario.noise_m:g} m, "
             f"{100 * block['valid_fraction']:.0f} % of pixels measured, box on {block['box_pixels_median']:.0f} px; "
             f"preview {paths[0]}"]
    pictures = [Picture("depth preview", write_preview, (depth.depth_m, depth.fps, record.out), {"gif": gif})]
    blocks = [("render", block)]
    if episode.colour is not None:
        colour = episode.colour
        _, Hc, Wc, _ = colour.rgb.shape
        sensor = colour_preset(record.scenario.sensor)
        appearance = appearance_of(record.scenario)
        blocks.append(("colour", {
            "frames": colour.num_frames, "width": Wc, "height": Hc, "fps": colour.fps, "exposure_s": colour.exposure_s,
            "sensor": record.scenario.sensor, "offset_from_depth_m": list(sensor.offset_m),
            "white_balance": sensor.white_balance, "noise": sensor.noise, "skin_tone_monk": appearance.skin_tone,
            "lights": len(appearance.lighting.kelvin), "light_kelvin": [float(k) for k in appearance.lighting.kelvin],
            "preview": "colour_preview.png",
        }))
        lines.append(f"render: {colour.num_frames} colour frames {Wc}x{Hc}, exposure {1e3 * colour.exposure_s:.1f} ms, "
                     f"skin tone {appearance.skin_tone} of 10 (Monk); preview {record.out / 'colour_preview.png'}")
        pictures.append(Picture("colour preview", write_colour_preview, (colour.rgb, colour.fps, record.out)))
    # the episode is complete: its archive is compressed beside the later stages
    pictures.append(Picture("episode.npz", save_episode, (episode, record.out / "episode.npz"), in_thread=True))
    return StageResult(blocks=tuple(blocks), lines=tuple(lines), pictures=tuple(pictures), episode=episode)


STAGE = Stage(name="render", run=run, options=("no_gif", "streams"), add_arguments=add_arguments)
