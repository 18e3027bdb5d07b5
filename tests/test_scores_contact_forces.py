"""The finger forces in newtons in the peers' forms: per-contact MAE/RMSE, normal and tangential
parts, the peak hand force; every number computed by hand."""

from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.scores.aggregate import aggregate_all
from benchmark.scores.contact_forces import contact_force_errors
from benchmark.scores.episode import newton_errors
from benchmark.scores.metrics import FORCE_METRICS, METRICS, NOMINAL_FORCE_METRICS, WORST
from fsv.forces import FrameStatus


def _truth():
    """Two frames, two fingers. Finger 0's normal (0, 0, 1), finger 1's (1, 0, 0) (into the box).
    Frame 0: both in contact, F0 = (0, 0, 5), F1 = (4, 1, 0); frame 1: finger 0 alone, F0 = (1, 0, 6)."""
    normal = np.array([[[0, 0, 1.0], [1.0, 0, 0]]] * 2)
    force = np.array([[[0, 0, 5.0], [4.0, 1.0, 0]], [[1.0, 0, 6.0], [0, 0, 0]]])
    return SimpleNamespace(contact_force=force, contact_normal=normal,
                           contact_active=np.array([[True, True], [True, False]]))


def _solution(force, active, status):
    return SimpleNamespace(force=np.asarray(force, float), active=np.asarray(active, bool),
                           status=np.asarray([int(s) for s in status], np.int8))


def test_each_metric_against_a_hand_computation():
    # frame 0: e0 = (0, 2, 0) (|e| 2: tangential 2), e1 = (-3, 0, 0) (|e| 3: normal 3);
    # frame 1: finger 0 missed by the method (F̂ = 0): e0 = (-1, 0, -6) (|e| √37, normal 6, tangential 1);
    # finger 1 pushes 2 N where the truth has no contact: not a per-contact pair, in the peak
    sol = _solution(force=[[[0, 2.0, 5.0], [1.0, 1.0, 0]], [[0, 0, 0], [2.0, 0, 0]]],
                    active=[[1, 1], [0, 1]], status=[FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION])
    out = contact_force_errors(sol, _truth())
    assert out["pairs"] == 3
    assert out["mae_n"] == pytest.approx((2.0 + 3.0 + np.sqrt(37.0)) / 3)
    assert out["rmse_n"] == pytest.approx(np.sqrt((4.0 + 9.0 + 37.0) / 3))
    assert out["normal_mae_n"] == pytest.approx((0.0 + 3.0 + 6.0) / 3)
    assert out["tangential_mae_n"] == pytest.approx((2.0 + 0.0 + 1.0) / 3)
    # hand force ||Σ_k F_k||: truth (4, 1, 5) then (1, 0, 6), peak √42; estimate (1, 3, 5) then (2, 0, 0), peak √35
    assert out["peak_err_n"] == pytest.approx(np.sqrt(42.0) - np.sqrt(35.0))


@pytest.mark.parametrize("status", [FrameStatus.NO_KINEMATICS, FrameStatus.FAILED, FrameStatus.LEAST_VIOLATION,
                                    FrameStatus.IMPLAUSIBLE])
def test_an_unsolved_frame_counts_as_no_force(status):
    # frame 0 exact; frame 1 unsolved with a 100 N force (or NaN): scored as 0 N, a failure, and out of the peak
    truth = _truth()
    f1 = np.nan if status in (FrameStatus.NO_KINEMATICS, FrameStatus.FAILED) else 100.0
    sol = _solution(force=[truth.contact_force[0], [[1.0, 0, f1], [0, 0, 0]]], active=np.ones((2, 2)),
                    status=[FrameStatus.OPTIMAL, status])
    out = contact_force_errors(sol, truth)
    assert out["pairs"] == 3
    assert out["mae_n"] == pytest.approx(np.sqrt(37.0) / 3)
    assert out["rmse_n"] == pytest.approx(np.sqrt(37.0 / 3))
    assert out["normal_mae_n"] == pytest.approx(2.0) and out["tangential_mae_n"] == pytest.approx(1.0 / 3)
    assert out["peak_err_n"] == 0.0  # the estimate's peak is frame 0's, exact


def test_no_true_contact_leaves_the_per_contact_errors_undefined_but_not_the_peak():
    truth = _truth()
    truth = SimpleNamespace(contact_force=truth.contact_force, contact_normal=truth.contact_normal,
                            contact_active=np.zeros((2, 2), bool))
    sol = _solution(force=np.zeros((2, 2, 3)) + [3.0, 0, 4.0], active=np.ones((2, 2)), status=[FrameStatus.OPTIMAL] * 2)
    out = contact_force_errors(sol, truth)
    assert out["pairs"] == 0 and np.isnan(out["mae_n"]) and np.isnan(out["tangential_mae_n"])
    assert out["peak_err_n"] == pytest.approx(10.0)  # two fingers of (3, 0, 4): ||(6, 0, 8)||, against 0


def test_an_episode_without_forces_counts_at_its_worst():
    truth = _truth()
    sol = _solution(force=truth.contact_force, active=truth.contact_active, status=[FrameStatus.OPTIMAL] * 2)
    row = newton_errors(SimpleNamespace(forces=None, nominal=sol), truth)
    assert all(np.isnan(row[m]) for m in FORCE_METRICS)  # no final forces: nothing to score
    assert all(row[m] == 0.0 for m in NOMINAL_FORCE_METRICS)  # the nominal forces are the truth's here
    assert set(FORCE_METRICS) | set(NOMINAL_FORCE_METRICS) <= set(METRICS) and WORST["force_mae_n"] == np.inf
    agg = aggregate_all([{"force_mae_n": 1.0}, {"force_mae_n": 2.0}, {"force_mae_n": row["force_mae_n"]}],
                        ["force_mae_n"])["force_mae_n"]
    assert agg["median"]["value"] == 2.0 and agg["median"]["n"] == 3 and agg["median"]["at_worst"] == 1  # not 1.5
    assert agg["mean"]["value"] == np.inf
