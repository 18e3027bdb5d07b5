"""The arrays handed to the tracker's compiled kernels: read-only, so that numba compiles each kernel
once (a read-only and a writable array are two types to it)."""

import sys

import numba
import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

from benchmark.method.init import tracker_init
from fsv.track.kernel_args import readonly
from fsv.track.tracker import track
from fsv.types import DepthVideo


def test_readonly_is_a_read_only_view_of_an_array_of_its_type_and_a_copy_of_any_other():
    x = np.arange(6.0).reshape(2, 3)
    view = readonly(x)
    assert np.shares_memory(view, x) and not view.flags.writeable and x.flags.writeable  # x itself stays writable
    assert readonly(view) is view  # already one: handed on as it is
    copied = readonly(x.T)  # another order: a C-ordered copy
    assert not np.shares_memory(copied, x) and copied.flags.c_contiguous and not copied.flags.writeable
    np.testing.assert_array_equal(copied, x.T)
    ints = readonly(np.array([1.0, 2.0]), np.int64)
    assert ints.dtype == np.int64 and not ints.flags.writeable and ints.tolist() == [1, 2]
    with pytest.raises(ValueError):
        view[0, 0] = 1.0


def _python_called_kernels() -> dict:
    """``{(module, name): dispatcher}`` of every compiled kernel a module of ``fsv`` holds under a
    name no compiled function of that module calls (compiled code resolves its callees' names when
    it is compiled: those stay the kernels themselves)."""
    out = {}
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] != "fsv":
            continue
        kernels = {attr: v for attr, v in vars(module).items() if isinstance(v, CPUDispatcher)}
        called = {n for v in kernels.values() if v.py_func.__module__ == name for n in v.py_func.__code__.co_names}
        out.update({(name, attr): v for attr, v in kernels.items() if attr not in called})
    return out


def test_each_compiled_kernel_the_tracker_calls_gets_one_type_of_arguments(rendered_lift_episode, monkeypatch):
    """Eight frames of the 2.5 s lift tracked with every kernel's Python calls watched: each kernel
    called from Python is called with one type of arguments, so a first run compiles it once. Before
    the kernels' inputs were made read-only, the hand's fit (``fsv.track.hand.lm.solve``, 8 s of the
    31 s a run with an empty numba cache compiled) was called with a read-only first-frame palm
    and writable later ones, and compiled twice; so were ``pose_chain`` and ``_box_depth_kernel``."""
    ep = rendered_lift_episode
    seen = {}

    def watched(key, kernel):
        def call(*args):
            seen.setdefault(key, set()).add(tuple(str(numba.typeof(a)) for a in args))
            return kernel(*args)
        return call

    for (module, attr), kernel in _python_called_kernels().items():
        monkeypatch.setattr(sys.modules[module], attr, watched(kernel.py_func.__qualname__, kernel))
    depth = DepthVideo(ep.depth.depth_m[:8], ep.depth.fps)
    tracking = track(depth, ep.calib, ep.object_model, ep.hand_model, tracker_init(ep.truth, ep.scenario, ep.hand_model),
                     rng=ep.scenario.rng("tracker"))
    assert tracking.box.pos.shape == (8, 3)
    assert {"solve", "pose_chain", "_box_depth_kernel"} <= set(seen)  # the control: the watch sees the fit's kernels
    assert {k: len(v) for k, v in seen.items() if len(v) > 1} == {}
