"""fsv.compile_clock: numba's compilations timed, nested ones once; the tracker sets them apart."""

import time

import numba
import numpy as np
from numba.core import event
from raycast import look_at_calibration, render_depth

from benchmark.world.hand import hand_model
from fsv import DepthVideo, ObjectModel, TrackInit
from fsv.compile_clock import CompileClock
from fsv.rotation import exp_so3
from fsv.track import tracker as tracker_module
from fsv.track.hand import HandKinematics, HandState


def _fake_compile(seconds: float, inner_s: float = 0.0) -> None:
    """A compilation numba reports, of a known length (with one nested inside it)."""
    with event.trigger_event("numba:compile", data={}):
        time.sleep(seconds)
        if inner_s:
            with event.trigger_event("numba:compile", data={}):
                time.sleep(inner_s)


def test_a_kernel_compiled_inside_is_timed_and_a_compiled_one_adds_nothing():
    @numba.njit(cache=False)
    def inner(x):
        return x * 2.0

    @numba.njit(cache=False)
    def outer(x):
        return inner(x) + 1.0

    t0 = time.perf_counter()
    with CompileClock() as clock:
        assert outer(1.0) == 3.0  # compiles outer, and inner within it
    wall = time.perf_counter() - t0
    assert 0 < clock.s <= wall  # counted once: the nested compile lies within the outer one
    with CompileClock() as again:
        outer(2.0)  # already compiled for a float
    assert again.s == 0.0


def test_nested_compilations_count_once_and_none_after_the_block():
    with CompileClock() as clock:
        _fake_compile(0.1, inner_s=0.1)
    assert 0.2 <= clock.s < 0.3  # not 0.3: the inner 0.1 s lies within the outer 0.2 s
    _fake_compile(0.05)  # after the block: not this clock's
    assert clock.s < 0.3


def test_the_tracker_sets_the_frames_compilation_apart_from_the_first_frames_time(monkeypatch):
    size = np.array([0.171, 0.111, 0.060])
    box = ObjectModel(size_m=size, mass_kg=0.4, inertia=ObjectModel.solid_box_inertia(size, 0.4), friction=0.8)
    calib = look_at_calibration([0.20, -0.48, 0.36], [0.0, 0.0, 0.08])
    hand = hand_model(1.0)
    q = np.mean(hand.joint_range, 1)
    palm, rot = np.array([0.0, -0.03, 0.115]), exp_so3([np.pi - 0.3, 0.0, 0.0])
    p, r, _, _ = HandKinematics(hand).pose(HandState(palm, rot, q))
    a, b = HandKinematics(hand).capsules(p, r)
    frame = render_depth(calib, [0.0, 0.0, 0.03], np.eye(3), size / 2, list(zip(a, b, hand.geom_radius)), 0.0)
    video = DepthVideo(np.stack([frame] * 4), 30.0)
    init = TrackInit(box_pos=np.array([0.0, 0.0, 0.03]), box_rot=np.eye(3), palm_pos=palm, palm_rot=rot, joints=q)
    tracker_module.track(video, calib, box, hand, init)  # its own kernels compiled or loaded first
    update = tracker_module.HandTracker.update
    calls = []

    def compiling_update(self, *args, **kwargs):  # frames 0 and 2 each compile a kernel for 0.2 s
        if len(calls) in (0, 2):
            _fake_compile(0.2)
        calls.append(1)
        return update(self, *args, **kwargs)

    monkeypatch.setattr(tracker_module.HandTracker, "update", compiling_update)
    tracking = tracker_module.track(video, calib, box, hand, init)
    fits = tracking.timing_s["box"] + tracking.timing_s["hand"]
    assert len(calls) == 4 and 0.4 <= tracking.compile_s < 0.5
    assert 0 < tracking.first_frame_s <= fits - tracking.compile_s  # the first frame's 0.2 s is not in it
