"""The force scorer: net wrench errors, nominal vs true normal forces, sum of squares, sensitivity, Fig. 5."""

import dataclasses

import numpy as np
from forces_oracle import grasp_truth
from pictures import assert_figure

from benchmark.commands.pictures.fig5 import plot_fig5
from benchmark.scores.forces import score_forces, sensitivity, true_net_wrench, true_net_wrench_instant
from benchmark.world.contact_error import contacts_from_truth, vision_like_contacts
from fsv import Kinematics
from fsv.forces import FrameStatus, nominal_forces


def _kin(truth):
    return Kinematics(truth.t, truth.box_pos, truth.box_rot, truth.box_vel, truth.box_acc, truth.box_omega,
                      truth.box_alpha, np.ones(len(truth.t), bool), "oracle")


def test_scores_of_nominal_forces_on_a_consistent_truth(tmp_path):
    truth, model = grasp_truth(3, T=40, K=4)
    kin = _kin(truth)
    sol = nominal_forces(kin, contacts_from_truth(truth), model)
    s = score_forces(sol, truth, kin.rot)
    assert s["net_force_err_n_rms"] < 1e-6 and s["net_torque_err_nm_rms"] < 1e-7
    assert s["solver_failures"] == 0 and s["frames_scored"] == 40 and s["status"]["optimal"] == 40
    # The L2-minimal grasp presses less than the random (over-gripping) one, and never has a larger SoS.
    assert s["nominal_normal_err_n_mean"] < -0.5
    assert s["sos_true_not_below_nominal_frac"] == 1.0 and s["sos_frames"] == 40
    # A biased estimate shows up in the net force error: 1 N along world x at every frame.
    shifted = type(sol)(**{**sol.__dict__, "env_wrench": sol.env_wrench + np.concatenate(
        [np.einsum("tji,j->ti", kin.rot, [1.0, 0, 0]), np.zeros((40, 3))], axis=1)})
    assert abs(score_forces(shifted, truth, kin.rot)["net_force_err_n_rms"] - 1.0) < 1e-6
    png = plot_fig5(sol, truth, kin.rot, tmp_path / "fig5.png", title="test")
    assert_figure(png, min_height=800, colours={"thumb (C0)": (31, 119, 180), "index (C1)": (255, 127, 14)})


def test_the_finger_panels_legends_name_each_digit_and_each_estimate_once():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from benchmark.commands.pictures.fig5 import _finger_panel

    names = ["thumb", "index", "middle", "ring", "little"]
    t, f = np.arange(10) / 30, np.ones((10, 5))
    fig, ax = plt.subplots()
    _finger_panel(ax, t, names, f, f, f, plt.rcParams["axes.prop_cycle"].by_key()["color"])
    legends = [a for a in ax.get_children() if isinstance(a, matplotlib.legend.Legend)]
    labels = [[x.get_text() for x in leg.get_texts()] for leg in legends]
    plt.close(fig)
    assert sorted(labels) == sorted([names, ["true", "nominal", "learned"]])  # 8 entries, not 15


def test_true_net_wrench_is_what_newton_euler_requires():
    truth, model = grasp_truth(4, T=10, K=3)
    for w in (true_net_wrench(truth), true_net_wrench_instant(truth)):
        assert np.allclose(w[:, :3], model.mass_kg * (truth.box_acc - truth.gravity))


def test_net_force_is_scored_against_the_frame_mean_and_the_instant_beside_it():
    truth, model = grasp_truth(4, T=40, K=3)
    kin, c = _kin(truth), contacts_from_truth(truth)
    sol = nominal_forces(kin, c, model)
    base = score_forces(sol, truth, kin.rot)
    assert base["net_force_err_n_rms"] < 1e-6 and base["net_force_err_n_rms_instant"] < 1e-6
    # the frame mean differs from the instant by 3 N at one frame: the scored error follows the mean
    mean = true_net_wrench_instant(truth).copy()
    mean[20, :3] -= [0.0, 3.0, 0.0]
    got = score_forces(sol, dataclasses.replace(truth, net_wrench_mean=mean), kin.rot)
    assert abs(got["net_force_err_n_rms"] - 3.0 / np.sqrt(40)) < 1e-6
    assert got["net_force_err_n_rms_instant"] < 1e-6


def test_sensitivity_is_zero_without_contact_error_and_grows_with_it():
    truth, model = grasp_truth(5, T=60, K=4)
    kin, c = _kin(truth), contacts_from_truth(truth)
    none = sensitivity(kin, c, c, model)
    assert none["normal_diff_n_mean"] == 0 and none["normal_diff_n_std"] == 0 and none["pairs"] == 240
    small = sensitivity(kin, c, vision_like_contacts(c, model, np.random.default_rng(0), mean_m=0, std_m=1e-3), model)
    large = sensitivity(kin, c, vision_like_contacts(c, model, np.random.default_rng(0), mean_m=0, std_m=1e-2), model)
    assert 0 < small["force_diff_n_rms"] < large["force_diff_n_rms"]


def test_frames_without_estimate_are_not_scored():
    truth, model = grasp_truth(6, T=10, K=3)
    kin = _kin(truth)
    valid = np.ones(10, bool)
    valid[:3] = False
    kin = Kinematics(kin.t, kin.pos, kin.rot, kin.vel, kin.acc, kin.omega, kin.alpha, valid, "test")
    sol = nominal_forces(kin, contacts_from_truth(truth), model)
    s = score_forces(sol, truth, kin.rot)
    assert s["frames_scored"] == 7 and s["status"]["no_kinematics"] == 3
    assert sol.count(FrameStatus.NO_KINEMATICS) == 3 and np.isfinite(s["net_force_err_n_rms"])


def test_robust_limits_show_the_bulk_and_leave_an_outlier_to_the_edge():
    from benchmark.commands.pictures.fig5 import robust_limits

    truth = np.linspace(0.0, 10.0, 200)
    estimate = truth + 0.5
    estimate[17] = 1000.0  # one absurd frame (as a least-violation solve can give)
    lo, hi = robust_limits(truth, estimate)
    assert lo < 0 < 10.5 < hi < 12.5  # 99th percentile of the values, 10 % margin: not 1000
    lo2, hi2 = robust_limits(np.array([np.nan]), np.array([np.nan]))
    assert (lo2, hi2) == (0.0, 1.0)
