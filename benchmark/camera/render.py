"""Depth rendering: what a DS325-like depth camera sees of the simulated scene.

The rendered scene mirrors the MuJoCo geoms one to one (the table, the box, every capsule and
sphere of the hand): each geom's triangle mesh is built once from the MjModel in its body's
frame, and per frame only the bodies' poses (``data.xpos`` / ``data.xmat``) are applied. One pass
per frame of this project's CPU rasteriser (:mod:`benchmark.camera.depth`) gives the exact depth
along the optical axis and a label image (which geom is seen where), the same bits on every
machine, with or without a GPU.
The sensor model (:mod:`benchmark.camera.sensor`) then turns the exact depth into a measurement.

Camera conventions: `fsv` and :class:`fsv.Calibration` use OpenCV's pinhole camera (x right,
y down, z forward; pixel centres at integer coordinates); the rasteriser casts each pixel's ray
in that frame. ``GL_FROM_CV`` converts camera poses for OpenGL-style cameras (MuJoCo's, a peer in
the tests and the speed script).

The renderer is :mod:`benchmark.camera.depth` (kernels :mod:`benchmark.camera.raster_kernels`),
the camera :mod:`benchmark.camera.camera`, the scene's meshes and labels :mod:`benchmark.camera.scene`."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from benchmark.camera.camera import Camera
from benchmark.camera.colour import ColourFrames, render_colour
from benchmark.camera.colour_sensor import colour_camera, colour_preset
from benchmark.camera.depth import DepthRenderer, HandSkin, drawn_hand, hand_skin, pulp_presses  # noqa: F401 (re-exported)
from benchmark.camera.labelling import Annotations, Labeller, StreamLabels
from benchmark.camera.scene import world_labels
from benchmark.camera.sensor import SensorModel, sensor_preset
from benchmark.camera.views import camera_of
from benchmark.errors import BenchmarkError
from benchmark.world.assets import build_world, set_frame
from benchmark.world.episode import Episode
from fsv import DepthVideo
from fsv.types import check_streams


def render_video(model, set_frame, num_frames: int, *, camera: Camera, labels: np.ndarray, sensor, rng,
                 skin: HandSkin | None = None, pulps: tuple | None = None, observe=None, out: tuple | None = None,
                 on_frame=None):
    """Renders and measures a depth video of a MuJoCo model.

    Args:
        model: A compiled ``mujoco.MjModel``.
        set_frame: ``set_frame(data, k)`` puts frame k's kinematic state into ``data`` (qpos and
            mocap poses) and runs ``mujoco.mj_kinematics``.
        num_frames: Number of frames T.
        camera: The camera.
        labels: Label per geom, (ngeom,) uint8 (see :func:`world_labels`).
        sensor: A :class:`benchmark.camera.sensor.SensorModel`.
        rng: Generator of the sensor noise (the scenario's "depth" stream).
        skin: Draw the hand as this skin instead of its primitives (None: the primitives).
        pulps: With a skin, ``(centre, push)`` per frame and finger, each (T, K, 3), world frame
            (:func:`benchmark.camera.depth.pulp_presses`); None presses no pulp.
        observe: Called as ``observe(k, exact_depth, labels)`` with each frame's exact depth (H, W)
            float32 and labels (before the sensor; e.g. :meth:`benchmark.camera.labelling.Labeller.see`).
        out: ``(depth, label_images)`` arrays (T, H, W), float32 and uint8, to render into (e.g.
            memory shared with another process), or None: new ones.
        on_frame: Called as ``on_frame(k + 1)`` once frame k is in both arrays (the frames are
            rendered in order: the first k + 1 are done).

    Returns:
        ``(depth, label_images)``: measured depth (T, H, W) float32 metres (0 = no measurement)
        and the exact label images (T, H, W) uint8 (from the noise-free render).
    """

    if int(num_frames) < 1:
        raise BenchmarkError(f"num_frames must be >= 1, got {num_frames}")
    data = mujoco.MjData(model)
    shape = (int(num_frames), camera.height, camera.width)
    if out is None:
        depth, label_images = np.empty(shape, dtype=np.float32), np.empty(shape, dtype=np.uint8)
    else:
        depth, label_images = out
        if depth.shape != shape or label_images.shape != shape or (depth.dtype, label_images.dtype) != (
                np.float32, np.uint8):
            raise BenchmarkError(f"out must be float32 and uint8 arrays of shape {shape}, got {depth.dtype} "
                                 f"{depth.shape} and {label_images.dtype} {label_images.shape}")
    renderer = DepthRenderer(model, camera, labels, skin=skin)
    for k in range(shape[0]):
        set_frame(data, k)
        centre, push = (None, None) if pulps is None else (pulps[0][k], pulps[1][k])
        exact, label_images[k] = renderer.render(data.xpos, data.xmat, centre, push)
        if observe is not None:
            observe(k, exact, label_images[k])
        depth[k] = sensor.measure(exact, camera.K, rng)
        if on_frame is not None:
            on_frame(k + 1)
    return depth, label_images


def render(episode: Episode, *, sensor: SensorModel | None = None, camera: Camera | None = None,
           streams: tuple = ("depth",)) -> Episode:
    """Renders the streams the scenario's RGB-D camera would record of a simulated episode.

    The depth is always rendered (once: an episode that has it keeps it); the colour when
    ``streams`` names it (:func:`benchmark.camera.colour.render_colour`, from its own random
    stream, so rendering it later, onto a cached depth episode, gives the same bits as rendering
    both at once).

    Args:
        episode: A simulated episode (its truth gives the box and hand pose per frame).
        sensor: The sensor model; default the scenario's preset with its noise,
            ``sensor_preset(scenario.sensor, scenario.noise_m)`` (docs/scenarios.md). Its
            ``noise_m`` must equal the scenario's.
        camera: The camera; default the scenario's view's (:func:`benchmark.camera.views.camera_of`:
            ``sim_assets/camera.yaml``'s for view 0).

        streams: The streams to render (names of :data:`fsv.types.STREAMS`; the depth always).

    Returns:
        The episode with ``depth`` (T frames at the scenario's fps, T = len(truth.t)),
        ``calib`` and the truth-side ``labels`` (T, H, W) uint8 (never handed to `fsv`).
        The noise comes from the scenario's "depth" random stream: same scenario, same bits.
        The hand is drawn as the scenario's ``hand_surface`` says: its collision primitives
        ("capsules"), the person's skin ("skin", :mod:`benchmark.world.skin`) or that skin with
        rigid pulps ("skin-rigid").
    """
    streams = check_streams(streams)
    if episode.depth is None:
        episode = render_depth(episode, sensor=sensor, camera=camera)
    if "colour" in streams and episode.colour is None:
        # the colour's labels beside the depth's (an episode read from a file of version 2 has none)
        stream = render_colour_stream(episode, camera=camera, labelled=episode.annotations is not None)
        episode = with_colour_stream(episode, stream)
    return episode


@dataclass(frozen=True)
class ColourStream:
    """The colour stream of an episode as :func:`render_colour_stream` renders it.

    Attributes:
        frames: The :class:`benchmark.camera.colour.ColourFrames`.
        labels: The stream's :class:`benchmark.camera.labelling.StreamLabels`, or None (not labelled).
    """

    frames: ColourFrames
    labels: StreamLabels | None = None


def render_colour_stream(episode: Episode, *, camera: Camera | None = None, labelled: bool = True,
                         out: tuple | None = None) -> ColourStream:
    """Renders the colour stream of a simulated episode and its labels: it needs no depth, so it
    may be rendered beside it (in another process) and joined to it with :func:`with_colour_stream`,
    the same bits as :func:`render` gives (the noise comes from the scenario's own "colour" stream;
    the keypoints are the depth's, else computed from the truth alike).

    Args:
        episode: A simulated episode (rendered or not).
        camera: The depth camera the colour camera sits beside; default the scenario's view's.
        labelled: Label the stream (keypoints, visibility, BOP poses, contacts in its frame).
        out: ``(rgb, labels)`` arrays to render into (:func:`benchmark.camera.colour.render_colour_video`).
    """
    labeller = None
    if labelled:
        colour_calib = colour_camera(camera_of(episode.scenario.view) if camera is None else camera,
                                     colour_preset(episode.scenario.sensor)).calibration()
        keypoints = None if episode.annotations is None else episode.annotations.keypoints_world
        labeller = Labeller(build_world(episode.scenario), episode.truth, colour_calib, keypoints=keypoints)
    frames = render_colour(episode, camera=camera, observe=None if labeller is None else labeller.see, out=out)
    return ColourStream(frames=frames, labels=None if labeller is None else labeller.labels())


def with_colour_stream(episode: Episode, stream: ColourStream) -> Episode:
    """``episode`` (rendered: its depth's annotations, if labelled) with the colour stream and its labels."""
    episode = episode.with_colour(stream.frames.video, stream.frames.labels)
    if stream.labels is not None and episode.annotations is not None:
        episode = episode.with_annotations(episode.annotations.with_stream("colour", stream.labels))
    return episode


def scenario_sensor(scenario, sensor: SensorModel | None = None) -> SensorModel:
    """The depth sensor of ``scenario``: ``sensor``, or its preset with its noise
    (``sensor_preset(scenario.sensor, scenario.noise_m)``); BenchmarkError if ``sensor``'s noise is
    not the scenario's (the scenario sets the noise)."""
    sensor = sensor_preset(scenario.sensor, scenario.noise_m) if sensor is None else sensor
    if sensor.noise_m != scenario.noise_m:
        raise BenchmarkError(f"sensor.noise_m = {sensor.noise_m} differs from the scenario's noise_m = "
                             f"{scenario.noise_m}; the scenario sets the noise")
    return sensor


def render_depth(episode: Episode, *, sensor: SensorModel | None = None, camera: Camera | None = None,
                 out: tuple | None = None, on_frame=None) -> Episode:
    """The depth stream of :func:`render` alone: the episode with its ``depth``, ``calib``,
    ``labels`` and depth ``annotations``, rendered frame after frame into ``out`` (``(depth,
    labels)`` arrays, :func:`render_video`; None: new ones), calling ``on_frame(k + 1)`` once frame
    k is there (a reader in another process may take it). The same bits either way."""
    sc = episode.scenario
    sensor = scenario_sensor(sc, sensor)
    camera = camera_of(sc.view) if camera is None else camera
    world = build_world(sc)
    truth = episode.truth

    def set_k(data, k):
        set_frame(world, data, truth.box_pos[k], truth.box_quat[k], truth.hand_qpos[k])

    skin, pulps = drawn_hand(world, truth, sc.hand_surface)
    labeller = Labeller(world, truth, camera.calibration())
    depth, labels = render_video(
        world.model, set_k, len(truth.t), camera=camera, labels=world_labels(world), sensor=sensor, rng=sc.rng("depth"),
        skin=skin, pulps=pulps, observe=labeller.see, out=out, on_frame=on_frame,
    )
    episode = episode.with_depth(DepthVideo(depth_m=depth, fps=sc.fps), camera.calibration(), labels)
    return episode.with_annotations(Annotations(keypoints_world=labeller.keypoints_world,
                                                streams={"depth": labeller.labels()}))
