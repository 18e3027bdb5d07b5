"""The track stage's frame rate: from the second frame on, the frames' fits only, compiling aside."""

import math

from benchmark.commands.stages.track import _fits_s, frames_per_s_after_first


def test_the_rate_leaves_out_the_first_frame_and_the_compilation():
    # 11 frames; 2 s of fits, of which 0.5 s the first frame and 0.5 s compiling: 10 frames in 1 s
    assert frames_per_s_after_first(11, 2.0, 0.5, 0.5) == 10.0
    assert frames_per_s_after_first(11, 2.0, 0.5, 0.0) == 10 / 1.5  # a run that compiled nothing
    assert math.isnan(frames_per_s_after_first(1, 2.0, 0.5, 0.5))  # no second frame
    assert math.isnan(frames_per_s_after_first(11, 1.0, 0.5, 0.5))  # no time left to divide by


def test_the_fits_are_the_box_and_hand_fits_else_the_whole_tracking():
    stages = {"box": 1.25, "hand": 2.5, "contacts": 0.5, "table": 0.25}  # contacts and table: once, not per frame
    assert _fits_s(stages, 9.0) == 3.75
    assert _fits_s({}, 9.0) == 9.0  # a tracker that times no stages: its whole time
