"""The tracker against the simulated truth: the issue's accuracy gates, the scores, init and overlay."""

import numpy as np
from benchmark.contact_error import contacts_from_truth
from benchmark.score_forces import score_forces
from benchmark.tracking import GATES, INIT_PERTURBATION, gate_report, plot_overlay, score_tracking, tracker_init
from fsv import Poses
from fsv.rotation import quat_to_rot
from fsv.rotation import angle_between, log_so3
from fsv.track.tracker import Tracking


def test_box_gates_hold_on_lift_with_1cm_noise(tracked_lift):
    ep, est = tracked_lift
    s = score_tracking(est.tracking, ep.truth)
    assert s["box_pos_err_mm_median"] <= 2.0, s
    assert s["box_rot_err_deg_median"] <= 1.5, s


def test_end_to_end_net_force_error_is_within_the_papers_filter_threshold(tracked_lift):
    ep, est = tracked_lift
    assert est.oracle == ()  # tracked contacts, kinematics from tracked poses
    block = score_forces(est.nominal, ep.truth, est.kinematics.rot)
    assert block["net_force_err_n_rms"] <= 1.5, block


def test_the_hand_is_tracked_where_the_camera_sees_it(tracked_lift):
    ep, est = tracked_lift
    palm_err = np.linalg.norm(est.tracking.hand_qpos[:, :3] - ep.truth.hand_qpos[:, :3], axis=1)
    assert np.median(palm_err) < 0.015, np.median(palm_err)
    seen = est.tracking.observed
    tip_err = np.linalg.norm(est.tracking.fingertips - ep.truth.fingertip_pos, axis=-1)
    assert seen.sum() > 50 and np.median(tip_err[seen]) < 0.02, np.median(tip_err[seen])


def test_contact_gates_hold_on_lift_with_1cm_noise(tracked_lift):
    """The issue's contact gates: per-axis contact point error |mean| <= 2 mm and std <= 4 mm,
    recall and precision >= 0.9 (this 2.5 s lift, seed 0: -0.1 +- 1.8 mm, 0.99 / 0.98; the README gives
    seeds 0-8, on some of which a gate misses)."""
    ep, est = tracked_lift
    s = score_tracking(est.tracking, ep.truth)
    assert s["contact_pairs"] > 200
    assert abs(s["contact_err_mm_mean"]) <= 2.0 and s["contact_err_mm_std"] <= 4.0, s
    assert s["contact_recall"] >= 0.9 and s["contact_precision"] >= 0.9, s
    assert all(g["pass"] for g in gate_report(s).values()), gate_report(s)


def test_scores_of_a_perfect_tracker_are_zero_and_one(lift_episode):
    tr = lift_episode[0].truth
    T = len(tr.t)
    perfect = Tracking(box=Poses(tr.t, tr.box_pos, tr.box_rot), hand_qpos=tr.hand_qpos, fingertips=tr.fingertip_pos,
                       observed=np.ones(tr.contact_active.shape, bool), box_inliers=np.ones(T), hand_explained=np.ones(T),
                       contacts=contacts_from_truth(tr), timing_s={})
    s = score_tracking(perfect, tr)
    assert s["contact_pairs"] == tr.contact_active.sum() > 0
    for key in ("box_pos_err_mm_median", "box_rot_err_deg_median", "fingertip_err_mm_median",
                "contact_err_mm_mean", "contact_err_mm_std", "contact_err_mm_median_euclid"):
        assert abs(s[key]) < 1e-6, key
    assert s["contact_recall"] == s["contact_precision"] == 1.0
    # a 3 mm shift of every contact along the object's x axis: per-axis pooled mean 1 mm, std sqrt(2) mm
    shifted = perfect.contacts.point + np.array([0.003, 0.0, 0.0])
    c = contacts_from_truth(tr)
    moved = type(c)(c.finger_names, c.active, c.sliding, shifted, c.normal, c.slide_dir)
    s = score_tracking(perfect, tr, moved)
    assert abs(s["contact_err_mm_mean"] - 1.0) < 1e-9 and abs(s["contact_err_mm_std"] - np.sqrt(2.0)) < 1e-9
    assert abs(s["contact_err_mm_median_euclid"] - 3.0) < 1e-9
    assert set(gate_report(s)) == set(GATES) and all(g["pass"] for g in gate_report(s).values())
    far = type(c)(c.finger_names, c.active, c.sliding, c.point + np.array([0.009, 0.0, 0.0]), c.normal, c.slide_dir)
    report = gate_report(score_tracking(perfect, tr, far))  # per-axis mean 3 mm, std 4.24 mm
    assert [k for k, g in report.items() if not g["pass"]] == ["contact_err_mm_mean_abs", "contact_err_mm_std"]


def test_init_is_the_seeded_perturbation_of_the_first_frame_only(lift_episode):
    ep = lift_episode[0]
    tr = ep.truth
    a = tracker_init(tr, ep.scenario, ep.hand_model)
    b = tracker_init(tr, ep.scenario, ep.hand_model)
    np.testing.assert_array_equal(a.box_pos, b.box_pos)
    exact = tracker_init(tr, ep.scenario, ep.hand_model, scale=0.0)
    np.testing.assert_allclose(exact.box_pos, tr.box_pos[0])
    np.testing.assert_allclose(exact.palm_rot, quat_to_rot(tr.hand_qpos[0, 3:7]), atol=1e-12)
    np.testing.assert_allclose(exact.joints, tr.hand_qpos[0, 7:])
    d = a.box_pos - tr.box_pos[0]
    assert 0 < np.linalg.norm(d) < 5 * INIT_PERTURBATION["box_pos_m"] * np.sqrt(3)
    assert 0 < np.degrees(angle_between(a.box_rot, exact.box_rot)) < 5 * np.degrees(INIT_PERTURBATION["box_rot_rad"]) * np.sqrt(3)
    assert np.linalg.norm(log_so3(a.palm_rot @ exact.palm_rot.T)) > 0
    # later frames of the truth do not enter: scrambling them leaves the init unchanged
    scrambled = type(tr)(**{**tr.as_dict(), "box_pos": np.concatenate([tr.box_pos[:1], tr.box_pos[1:] + 1.0])})
    np.testing.assert_array_equal(tracker_init(scrambled, ep.scenario, ep.hand_model).box_pos, a.box_pos)


def test_overlay_is_a_png_strip(tracked_lift, tmp_path):
    ep, est = tracked_lift
    path = plot_overlay(ep.depth, ep.calib, est.tracking, ep.object_model, ep.hand_model, tmp_path / "o.png", frames=4)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000
    assert [p.name for p in tmp_path.iterdir()] == ["o.png"]  # written atomically, no temp file left


def test_contact_gates_hold_on_the_default_ten_second_lift_of_another_seed():
    """The issue's gates on the scenario `fsv-bench --task lift --noise 0.01 --seed 3` runs (10 s, 301
    frames), a seed no tracker setting was tuned on (measured: +0.3 +- 2.3 mm, recall and precision
    1.00 / 1.00; seeds 0-4 all pass). The short test lifts above miss a gate on some seeds."""
    from benchmark.render import render
    from benchmark.scenario import Scenario
    from benchmark.simulate import simulate
    from fsv.track.tracker import track

    ep = render(simulate(Scenario(task="lift", seed=3)))
    assert ep.depth.depth_m.shape[0] == 301
    tracking = track(ep.depth, ep.calib, ep.object_model, ep.hand_model, tracker_init(ep.truth, ep.scenario, ep.hand_model),
                     rng=ep.scenario.rng("tracker"))
    s = score_tracking(tracking, ep.truth)
    assert s["box_pos_err_mm_median"] <= 2.0 and s["box_rot_err_deg_median"] <= 1.5, s
    assert all(g["pass"] for g in gate_report(s).values()), gate_report(s)
