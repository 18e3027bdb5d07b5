"""fsv.track.hand.lm: the hand fit's compiled iterations, bit for bit the NumPy loop's."""

import numpy as np
import pytest

from fsv.linalg import dot, mm
from fsv.rotation import exp_so3, log_so3, project_to_so3, rot_from_skew, skew_stack
from fsv.track.hand import lm

pytestmark = pytest.mark.skipif(not lm.AVAILABLE, reason="the C library has no powf64 (not glibc): NumPy's loop runs")


def _rng(seed):
    rng = np.random.default_rng(seed)
    return rng, lambda *s: rng.normal(size=s) * 10.0 ** rng.uniform(-2, 2, size=s)


def test_dot_and_products_are_numpys_bits():
    rng, rnd = _rng(0)
    for n in range(1, 41):  # the lanes, the blocks of eight and every tail
        for _ in range(20):
            a, b = rnd(n), rnd(n)
            assert lm.edot(a, b) == float(dot(a, b)), n
    for _ in range(300):
        A, B = rnd(3, 3), rnd(3, 3)
        assert lm.mm3(A, B).tobytes() == mm(A, B).tobytes()
        assert lm.mm3t(A, B).tobytes() == mm(A, B.T).tobytes()
    # the order matters: the in-order sum of the same products differs somewhere
    a = rnd(3, 1000)
    seq = (a[0] * a[0] + a[1] * a[1]) + a[2] * a[2]
    assert not np.array_equal(seq, np.array([lm.edot(v, v) for v in a.T]))


def test_rotations_are_fsv_rotations_bits():
    rng, rnd = _rng(1)
    for scale in (1e-10, 1e-7, 1e-3, 0.3, 3.0):  # below and above exp_so3's small-angle switch
        for _ in range(200):
            w = rng.normal(size=3) * scale
            assert lm.exp_so3(w).tobytes() == exp_so3(w).tobytes(), scale
    for _ in range(300):
        R = exp_so3(rng.normal(size=3))
        assert lm.log_so3(R).tobytes() == log_so3(R).tobytes()
        near_pi = exp_so3((np.pi - rng.uniform(0, 5e-5)) * _unit(rng.normal(size=3)))
        assert lm.log_so3(near_pi).tobytes() == log_so3(near_pi).tobytes()
        tiny = exp_so3(rng.normal(size=3) * 1e-8)
        assert lm.log_so3(tiny).tobytes() == log_so3(tiny).tobytes()
        M = R + 1e-3 * rng.normal(size=(3, 3))
        X, ok = lm.project_to_so3(M)
        assert ok and X.tobytes() == project_to_so3(M).tobytes()
    assert not lm.project_to_so3(-np.eye(3))[1]  # det <= 0: NumPy's singular-value branch
    axes = rng.normal(size=(16, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    K = skew_stack(axes)
    KK = mm(K, K)
    q = rng.uniform(-2, 2, size=16)
    assert lm.hinges(K, KK, q).tobytes() == rot_from_skew(K, KK, q).tobytes()


def _unit(v):
    return v / np.sqrt(v @ v)


def test_the_tracked_hand_is_the_numpy_loops_bits(rendered_lift_episode, monkeypatch):
    """The whole tracker on the 2.5 s lift, the hand fit compiled and as NumPy runs it: the same
    poses to the last bit."""
    from benchmark.method.init import tracker_init
    from fsv.track.tracker import track

    ep = rendered_lift_episode

    def run():
        init = tracker_init(ep.truth, ep.scenario, ep.hand_model)
        return track(ep.depth, ep.calib, ep.object_model, ep.hand_model, init, rng=ep.scenario.rng("tracker"))

    compiled = run()
    monkeypatch.setattr(lm, "AVAILABLE", False)
    numpy_loop = run()
    for name in ("hand_qpos", "fingertips", "hand_explained"):
        assert getattr(compiled, name).tobytes() == getattr(numpy_loop, name).tobytes(), name
    assert compiled.box.pos.tobytes() == numpy_loop.box.pos.tobytes()
    assert np.ptp(compiled.hand_qpos[:, :3], axis=0).max() > 0.05  # the hand moved: the fit did work
