"""The render stage: the episode's depth video from its sensor; the ``render`` block and the depth preview.

The depth of a method that reads no colour is rendered beside the track stage: a child forked at
the stage's start (:meth:`benchmark.background.Background.stream`) renders the frames in order
into memory shared with the command and says after each one that it is there, and the stage hands
the track stage an :class:`fsv.types.DepthRecording` of that memory: the tracker, which reads the
frames in order, tracks frame k while the child renders the later ones. The child then draws the
depth preview and returns the annotations, the ``render`` block and the depth's digest; a thread of
the command joins them to the episode and writes the episode file (with the colour, below). The
frames, the files, the blocks and the digests are those of rendering the depth before tracking,
bit for bit: the child renders exactly what :func:`benchmark.camera.render.render` does, and the
tracker reads the same frames in the same order.

The colour stream, when ``--streams`` asks for it and the method does not read it, is rendered
beside the depth and the later stages: in a child forked at the stage's start (the colour needs
only the simulated truth, and no later stage reads it) into memory shared with the command
(:func:`benchmark.background.shared_empty`), while the command renders the depth and runs the
method on the other core; a thread then joins it to the depth and writes the episode file. The
``colour`` block, line and digest are those of rendering both streams here, bit for bit (the colour
has its own random stream). A method that reads colour gets it before the track stage, rendered here.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from benchmark.background import shared_empty
from benchmark.camera.appearance import appearance_of
from benchmark.camera.colour_sensor import colour_preset
from benchmark.camera.depth import RASTERISER
from benchmark.camera.episode_file import save_episode
from benchmark.camera.render import render, render_colour_stream, render_depth, with_colour_stream
from benchmark.camera.scene import LABEL_BOX
from benchmark.camera.views import camera_of, view_of
from benchmark.commands.digests import colour_digest, digest
from benchmark.commands.pictures.depth_preview import preview_paths, write_colour_preview, write_preview
from benchmark.commands.stage import Picture, Run, Stage, StageResult
from benchmark.suites.options import add_streams_argument
from fsv.types import DepthRecording, check_streams


def add_arguments(parser) -> None:
    """Options of the render stage of ``fsv-bench``."""
    parser.add_argument("--no-gif", action="store_true", help="write the PNG depth preview but no animated GIF")
    add_streams_argument(parser)


def run(record: Run, options) -> StageResult:
    """Renders the run's episode (the streams ``--streams`` asks for and those the method reads);
    when the command runs stages beside each other (``record.background``), the depth of a method
    that reads no colour is rendered beside the track stage, and the colour beside the later stages."""
    streams = check_streams([*options["streams"], *record.method_spec.streams])
    gif, drawn = not options["no_gif"], not options["no_pictures"]
    beside = None
    if "colour" in streams and "colour" not in record.method_spec.streams and record.background is not None:
        beside = _start_colour(record, drawn)
        streams = tuple(s for s in streams if s != "colour")
    if streams == ("depth",) and record.background is not None and record.episode.depth is None:
        return _stream_depth(record, gif, drawn, beside)
    episode = render(record.episode, streams=streams)
    depth = episode.depth
    block, line = render_summary(record.scenario, depth, episode.labels, record.out, gif, drawn)
    lines = [line]
    pictures = [Picture("depth preview", write_preview, (depth.depth_m, depth.fps, record.out), {"gif": gif})] if drawn else []
    blocks = [("render", block)]
    if beside is not None:  # the colour, the episode file and the colour block come from the later job
        later = (record.background.thread("episode.npz", _finish_colour, *beside, episode, record.scenario, record.out),)
        return StageResult(blocks=tuple(blocks), lines=tuple(lines), pictures=tuple(pictures), episode=episode,
                           later=later)
    if episode.colour is not None:
        colour_block, colour_line = colour_summary(record.scenario, episode.colour, record.out, drawn)
        blocks.append(("colour", colour_block))
        lines.append(colour_line)
        if drawn:
            pictures.append(Picture("colour preview", write_colour_preview, (episode.colour.rgb, episode.colour.fps,
                                                                             record.out)))
    # the episode is complete: its archive is compressed beside the later stages
    pictures.append(Picture("episode.npz", save_episode, (episode, record.out / "episode.npz"), in_thread=True))
    return StageResult(blocks=tuple(blocks), lines=tuple(lines), pictures=tuple(pictures), episode=episode)


def render_summary(scenario, depth, labels: np.ndarray, out, gif: bool, drawn: bool = True) -> tuple:
    """``(block, line)``: the ``render`` block of ``summary.json`` and the printed line of a
    scenario's depth (an ``fsv.DepthVideo``) with its label images (T, H, W), whose preview is in
    the folder ``out`` (with the GIF if ``gif``; none unless ``drawn``: ``--no-pictures``)."""
    paths = preview_paths(out, gif=gif) if drawn else []
    T, H, W = depth.depth_m.shape
    block = {
        "frames": T,
        "width": W,
        "height": H,
        "fps": depth.fps,
        "noise_m": scenario.noise_m,
        "rasteriser": RASTERISER,
        "view": view_of(scenario.view).record(),
        "valid_fraction": float(np.mean(depth.depth_m > 0)),
        "box_pixels_median": float(np.median(np.sum(labels == LABEL_BOX, axis=(1, 2)))),
        "preview": [p.name for p in paths],
    }
    line = (f"render: {T} depth frames {W}x{H} at {depth.fps:g} Hz, noise {scenario.noise_m:g} m, "
            f"{100 * block['valid_fraction']:.0f} % of pixels measured, box on {block['box_pixels_median']:.0f} px"
            + (f"; preview {paths[0]}" if paths else ""))
    return block, line


def _stream_depth(record: Run, gif: bool, drawn: bool, colour: tuple | None) -> StageResult:
    """Forks the depth's rendering into shared memory and returns at once: the episode with an
    ``fsv.types.DepthRecording`` of it for the track stage, and a later job that joins the rest
    (the ``render`` block and line, the depth's digest, the colour of ``colour`` (:func:`_start_colour`,
    or None) and writes the episode file."""
    sc = record.scenario
    camera = camera_of(sc.view)
    shape = (len(record.episode.truth.t), camera.height, camera.width)
    buffers = (shared_empty(shape, np.float32), shared_empty(shape, np.uint8))
    job = record.background.stream("depth", _render_depth, record.episode, buffers, record.out, gif, drawn)
    episode = record.episode.with_depth(DepthRecording(buffers[0], sc.fps, job.wait_for), camera.calibration(), None)
    later = record.background.thread("episode.npz", _finish_depth, job, buffers, episode, colour, sc, record.out)
    return StageResult(episode=episode, later=(later,))


def _render_depth(done, episode, buffers: tuple, out, gif: bool, drawn: bool) -> tuple:
    """In the forked child: renders the depth and its labels into ``buffers``, saying ``done(k + 1)``
    after frame k, then draws the preview if ``drawn``; returns ``(annotations, (block, line), digest)``."""
    episode = render_depth(episode, out=buffers, on_frame=done)
    if drawn:
        write_preview(episode.depth.depth_m, episode.depth.fps, out, gif=gif)
    return (episode.annotations, render_summary(episode.scenario, episode.depth, episode.labels, out, gif, drawn),
            digest(episode.depth))


def _finish_depth(job, buffers: tuple, episode, colour: tuple | None, scenario, out) -> StageResult:
    """In a thread of the command: waits for the depth's child, makes ``episode`` (whose depth is
    the recording) whole, joins the colour to it if ``colour``, and writes the episode file."""
    annotations, (block, line), depth_digest = job.result()
    episode.depth.depth_m  # noqa: B018 (every frame checked; the recording, whole, is the episode's depth: no copy)
    episode = episode.with_depth(episode.depth, episode.calib, buffers[1]).with_annotations(annotations)
    if colour is not None:
        joined = _finish_colour(*colour, episode, scenario, out)
        return replace(joined, blocks=(("render", block), *joined.blocks), lines=(line, *joined.lines),
                       digests=(("depth", depth_digest), *joined.digests))
    save_episode(episode, out / "episode.npz")
    return StageResult(blocks=(("render", block),), lines=(line,), episode=episode,
                       digests=(("depth", depth_digest),))


def colour_summary(scenario, colour, out, drawn: bool = True) -> tuple:
    """``(block, line)``: the ``colour`` block of ``summary.json`` and the printed line of a
    scenario's colour stream (an ``fsv.ColourVideo``) whose preview is in the folder ``out`` (none
    unless ``drawn``: ``--no-pictures``)."""
    _, Hc, Wc, _ = colour.rgb.shape
    sensor = colour_preset(scenario.sensor)
    appearance = appearance_of(scenario)
    block = {
        "frames": colour.num_frames, "width": Wc, "height": Hc, "fps": colour.fps, "exposure_s": colour.exposure_s,
        "sensor": scenario.sensor, "offset_from_depth_m": list(sensor.offset_m),
        "white_balance": sensor.white_balance, "noise": sensor.noise, "skin_tone_monk": appearance.skin_tone,
        "lights": len(appearance.lighting.kelvin), "light_kelvin": [float(k) for k in appearance.lighting.kelvin],
        "preview": "colour_preview.png" if drawn else None,
    }
    line = (f"render: {colour.num_frames} colour frames {Wc}x{Hc}, exposure {1e3 * colour.exposure_s:.1f} ms, "
            f"skin tone {appearance.skin_tone} of 10 (Monk)" + (f"; preview {out / 'colour_preview.png'}" if drawn else ""))
    return block, line


def _start_colour(record: Run, drawn: bool) -> tuple:
    """Forks the colour's rendering (``(job, (rgb, labels), drawn)``: the job, the shared arrays it
    renders into, and whether it draws the preview)."""
    T = len(record.episode.truth.t)
    sensor = colour_preset(record.scenario.sensor)
    buffers = (shared_empty((T, sensor.height, sensor.width, 3), np.uint8),
               shared_empty((T, sensor.height, sensor.width), np.uint8))
    return record.background.fork("colour", _render_colour, record.episode, buffers, record.out, drawn), buffers, drawn


def _render_colour(episode, buffers: tuple, out, drawn: bool) -> tuple:
    """In the forked child: renders the colour stream and its labels into ``buffers`` and draws its
    preview if ``drawn``; returns ``(the stream without its two videos, its digest)`` (the videos are shared)."""
    stream = render_colour_stream(episode, out=buffers)
    if drawn:
        write_colour_preview(stream.frames.rgb, stream.frames.fps, out)
    return replace(stream, frames=replace(stream.frames, rgb=None, labels=None)), colour_digest(stream.frames.video)


def _finish_colour(job, buffers: tuple, drawn: bool, episode, scenario, out) -> StageResult:
    """In a thread of the command: waits for the colour, joins it to the rendered ``episode`` and
    writes the episode file; returns the ``colour`` block, line and digest and the whole episode."""
    stream, digest = job.result()
    rgb, labels = buffers
    rgb.setflags(write=False)  # done: fsv.ColourVideo takes it without a copy
    episode = with_colour_stream(episode, replace(stream, frames=replace(stream.frames, rgb=rgb, labels=labels)))
    save_episode(episode, out / "episode.npz")
    block, line = colour_summary(scenario, episode.colour, out, drawn)
    return StageResult(blocks=(("colour", block),), lines=(line,), episode=episode, digests=(("colour", digest),))


STAGE = Stage(name="render", run=run, options=("no_gif", "no_pictures", "streams"), add_arguments=add_arguments)
