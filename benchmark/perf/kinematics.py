"""Speed (and accuracy) of the kinematics stage beside peer differentiators, in one process.

    python -m benchmark.perf.kinematics [--task lift] [--noise 0.01] [--seed 0] [--repeat 200]

On one simulated episode with tracker-like pose errors it times, per channel (one scalar signal of
the episode's length), our stencils (velocity and acceleration) and, as peers, AlgDiff's algebraic
differentiator (``analytic`` weights, same (kappa, mu, L); velocity and acceleration) and pynumdiff's
``finitediff``, ``kerneldiff``, ``savgoldiff`` and ``rtsdiff`` (velocity only: that is what they
return). The full ``differentiate_poses`` call (3 position + 3 rotation channels, SO(3) included)
is reported per channel too; the target is < 1 ms per channel for a 300-frame episode. Times are
CPU times (medians of batches); on a shared machine compare the ratios within one run. Velocity RMS errors against the
truth are printed beside the timings so that speed is not bought with accuracy. Peers are optional
(``pip install .[peers]``); a missing one is reported and skipped.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from benchmark.world.motion import DECLARED
from benchmark.world.pose_error import tracker_like_poses
from benchmark.world.scenario import Scenario
from benchmark.world.simulate import simulate
from fsv.kinematics import differentiate_poses


def _best_time(fn, repeat: int) -> float:
    """Median CPU time of one ``fn()`` call, in seconds, over batches of 10 calls.

    CPU time (``time.process_time``) rather than wall time: on a machine shared with other jobs
    it does not count the time this process waits for a core.
    """
    fn()
    batches = []
    for _ in range(max(3, repeat // 10)):
        t0 = time.process_time()
        for _ in range(10):
            fn()
        batches.append((time.process_time() - t0) / 10)
    return float(np.median(batches))


def _centred(offsets: np.ndarray, coeffs: np.ndarray) -> np.ndarray:
    """Dense taps over -r..r for np.correlate(x, taps, "same") (r = the larger reach)."""
    r = int(max(-offsets.min(), offsets.max()))
    dense = np.zeros(2 * r + 1)
    dense[offsets + r] = coeffs
    return dense


def _rms(est: np.ndarray, ref: np.ndarray, margin: int) -> float:
    return float(np.sqrt(np.mean((est[margin:-margin] - ref[margin:-margin]) ** 2)))


def run(task: str = "lift", noise_m: float = 0.01, seed: int = 0, repeat: int = 200, duration_s: float | None = None) -> list[dict]:
    """Times every available differentiator on one episode; returns one row per method."""

    sc = Scenario(task=task, noise_m=noise_m, seed=seed, duration_s=duration_s)
    truth = simulate(sc).truth
    poses = tracker_like_poses(truth, sc)
    dt = float(truth.t[1] - truth.t[0])
    x = poses.pos[:, 2].copy()  # one channel: the height of the box
    v_true = truth.box_vel[:, 2]
    margin = 20
    alg = DECLARED["algebraic"]
    rows = []

    st1, st2 = alg.stencil(1, dt), alg.stencil(2, dt)
    d1, d2 = (_centred(*st.taps(0.0)) for st in (st1, st2))

    def ours_channel():  # the same dense correlation AlgDiff uses, with our centred stencils
        return np.correlate(x, d1, "same"), np.correlate(x, d2, "same")

    v, _ = ours_channel()
    rows.append(dict(method=f"ours algebraic ({alg.describe()}), vel+acc", s=_best_time(ours_channel, repeat), vel_rms=_rms(v, v_true, margin)))
    kin = differentiate_poses(poses, alg)
    rows.append(
        dict(
            method="ours differentiate_poses (6 channels, SO(3)), per channel",
            s=_best_time(lambda: differentiate_poses(poses, alg), repeat) / 6,
            vel_rms=_rms(kin.vel[:, 2], v_true, margin),
        )
    )
    for name in ("central", "gaussian"):
        cfg = DECLARED[name]
        rows.append(
            dict(
                method=f"ours differentiate_poses {name} ({cfg.describe()}), per channel",
                s=_best_time(lambda cfg=cfg: differentiate_poses(poses, cfg), repeat) / 6,
                vel_rms=_rms(differentiate_poses(poses, cfg).vel[:, 2], v_true, margin),
            )
        )

    rows.append(_algdiff_row(alg, st1, x, dt, v_true, margin, repeat))
    rows += _pynumdiff_rows(alg, x, dt, v_true, margin, repeat)
    return rows


def _algdiff_row(alg, st1, x: np.ndarray, dt: float, v_true: np.ndarray, margin: int, repeat: int) -> dict:
    """The AlgDiff package's algebraic differentiator on the same channel (its row)."""
    try:
        from AlgDiff import AlgebraicDifferentiator  # lazy: optional peer
    except ImportError:
        return dict(method="AlgDiff (not installed)", s=float("nan"), vel_rms=float("nan"))
    else:
        L = alg.window_frames
        T = L * dt
        while int(T / dt) != L:
            T = np.nextafter(T, np.inf)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d1 = AlgebraicDifferentiator(ts=dt, alpha=alg.kappa + 1, beta=alg.mu + 1, N=0, T=T, display=False)
            d2 = AlgebraicDifferentiator(ts=dt, alpha=alg.kappa + 2, beta=alg.mu + 2, N=0, T=T, display=False)

            def algdiff_channel():
                return d1.estimateDer(1, x, method="analytic"), d2.estimateDer(2, x, method="analytic")

            v_ad, _ = algdiff_channel()
            shift = int(round(st1.delay_s / dt))  # AlgDiff's output is causal: re-centre it
            v_ad = np.concatenate([v_ad[shift:], np.zeros(shift)])
            return dict(method="AlgDiff analytic, vel+acc", s=_best_time(algdiff_channel, repeat), vel_rms=_rms(v_ad, v_true, margin))



def _pynumdiff_rows(alg, x: np.ndarray, dt: float, v_true: np.ndarray, margin: int, repeat: int) -> list:
    """pynumdiff's differentiators on the same channel (their rows)."""
    rows = []
    try:
        import pynumdiff  # lazy: optional peer
    except ImportError:
        return [dict(method="pynumdiff (not installed)", s=float("nan"), vel_rms=float("nan"))]
    else:
        sigma = DECLARED["gaussian"].sigma_frames
        peers = {
            "pynumdiff finitediff (order 2), vel": lambda: pynumdiff.finitediff(x, dt, order=2)[1],
            f"pynumdiff kerneldiff gaussian (window {alg.window_frames}), vel": lambda: pynumdiff.kerneldiff(
                x, dt, kernel="gaussian", window_size=alg.window_frames
            )[1],
            f"pynumdiff savgoldiff (deg 2, window {alg.window_frames}), vel": lambda: pynumdiff.savgoldiff(
                x, dt, degree=2, window_size=alg.window_frames, smoothing_win=max(3, int(2 * sigma) | 1)
            )[1],
            "pynumdiff rtsdiff (order 2, log q/r = 0), vel": lambda: pynumdiff.rtsdiff(x, dt, 2, 0.0, forwardbackward=False)[1],
        }
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for name, fn in peers.items():
                rows.append(dict(method=name, s=_best_time(fn, max(5, repeat // 10)), vel_rms=_rms(fn(), v_true, margin)))
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="lift")
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=200)
    args = parser.parse_args(argv)
    rows = run(args.task, args.noise, args.seed, args.repeat)
    ref = next((r["s"] for r in rows if r["method"].startswith("AlgDiff analytic")), float("nan"))
    print(f"{'method':<78} {'ms/channel':>10} {'vs AlgDiff':>10} {'vel RMS [m/s]':>14}")
    for r in rows:
        print(f"{r['method']:<78} {r['s'] * 1e3:>10.4f} {r['s'] / ref:>10.2f} {r['vel_rms']:>14.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
