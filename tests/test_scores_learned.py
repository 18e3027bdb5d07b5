"""The learned-force scores: every contact frame counted, unsolved frames as failures."""

from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.scores.learned import MIN_FORCE_N, contact_frame_errors
from fsv.forces import FrameStatus


def _case(f_true, f_est, status, est_active, true_active):
    """Truth with forces along the normal (0, 0, 1): T frames, K fingers."""
    f_true = np.asarray(f_true, float)
    T, K = f_true.shape
    normal = np.zeros((T, K, 3))
    normal[..., 2] = 1.0
    truth = SimpleNamespace(contact_force=normal * f_true[..., None], contact_normal=normal,
                            contact_active=np.asarray(true_active, bool))
    sol = SimpleNamespace(normal_force=np.asarray(f_est, float), status=np.asarray([int(s) for s in status], np.int8))
    return sol, SimpleNamespace(active=np.asarray(est_active, bool)), truth


def test_every_pair_in_contact_for_both_is_scored_by_hand():
    # frame 0 solved: errors |4-5|/5 = 20 %, |3-2|/2 = 50 %; frame 1 solved, finger 2 off for the
    # estimate (not scored), finger 1 at 0.5 N true (MAE only, under MIN_FORCE_N)
    sol, con, tr = _case(f_true=[[5.0, 2.0], [0.5, 4.0]], f_est=[[4.0, 3.0], [0.7, 9.0]],
                         status=[FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION],
                         est_active=[[1, 1], [1, 0]], true_active=[[1, 1], [1, 1]])
    out = contact_frame_errors(sol, con, tr)
    assert out["scored"] == 2 and out["pairs"] == 3
    assert out["rel_err_pct_mean"] == pytest.approx(35.0)
    assert out["rel_err_pct_std"] == pytest.approx(15.0)
    assert out["mae_n"] == pytest.approx((1.0 + 1.0 + 0.2) / 3)
    assert out["unsolved_frac"] == 0.0
    assert MIN_FORCE_N == 1.0


@pytest.mark.parametrize("status", [FrameStatus.NO_KINEMATICS, FrameStatus.FAILED, FrameStatus.LEAST_VIOLATION,
                                    FrameStatus.IMPLAUSIBLE])
def test_an_unsolved_frame_is_a_failure_not_a_gap(status):
    # frame 1's forces are exact but unsolved (or NaN): it scores as 0 N, 100 %, not left out
    sol, con, tr = _case(f_true=[[5.0, 2.0], [4.0, 4.0]], f_est=[[5.0, 2.0], [4.0, np.nan]],
                         status=[FrameStatus.OPTIMAL, status], est_active=np.ones((2, 2)), true_active=np.ones((2, 2)))
    out = contact_frame_errors(sol, con, tr)
    assert out["scored"] == 4
    assert out["rel_err_pct_mean"] == pytest.approx(50.0)  # (0 + 0 + 100 + 100) / 4
    assert out["mae_n"] == pytest.approx(2.0)  # (0 + 0 + 4 + 4) / 4
    assert out["unsolved_frac"] == pytest.approx(0.5)


def test_nothing_in_contact_for_both_is_nan_not_zero():
    sol, con, tr = _case(f_true=[[5.0]], f_est=[[5.0]], status=[FrameStatus.OPTIMAL], est_active=[[0]],
                         true_active=[[1]])
    out = contact_frame_errors(sol, con, tr)
    assert out["scored"] == 0 and np.isnan(out["rel_err_pct_mean"]) and np.isnan(out["mae_n"])
