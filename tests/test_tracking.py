"""The tracker against the simulated truth: the issue's accuracy gates, the scores, init and overlay."""

import numpy as np
import pytest

from benchmark.commands.pictures.overlay import overlay_figure, plot_overlay
from benchmark.method.init import INIT_PERTURBATION, tracker_init
from benchmark.scores.forces import score_forces
from benchmark.scores.tracking import GATES, gate_report, score_tracking
from benchmark.world.contact_error import contacts_from_truth
from fsv import Poses
from fsv.rotation import angle_between, log_so3, quat_to_rot
from fsv.track.tracker import Tracking


def test_box_gates_hold_on_lift_with_1cm_noise(tracked_lift):
    """Measured 1.30 mm and 1.23 deg (medians; seeds 1-2: 1.00 / 0.91 and 1.21 / 1.40; the tracker
    gives the same bits under the Haswell and Sandybridge OpenBLAS kernels); gates 2 mm and 2 deg,
    as on the smoke suite (the ds325's multipath and edge jitter cost ~0.5 mm)."""
    ep, est = tracked_lift
    s = score_tracking(est.tracking, ep.truth)
    assert s["box_pos_err_mm"] <= 2.0, s
    assert s["box_rot_err_deg"] <= 2.0, s


def test_end_to_end_net_force_error_on_the_short_lift(tracked_lift):
    """Measured 0.122 N RMS against the frame-mean truth on this 2.5 s human-speed lift (seeds 1-2:
    0.152, 0.151 N; against the instant 0.345 / 0.207 / 0.390 N; identical under the Haswell and
    Sandybridge kernels); gate 0.4 N. The statistics over 10 s lifts are gated below."""
    ep, est = tracked_lift
    assert est.oracle == ()  # tracked contacts, kinematics from tracked poses
    block = score_forces(est.nominal, ep.truth, est.kinematics.rot)
    assert block["net_force_err_n_rms"] <= 0.4, block


def _hand_errors(ep, est):
    """Median palm-origin error and median error of the observed fingertips, [m]."""
    palm_err = np.linalg.norm(est.tracking.hand_qpos[:, :3] - ep.truth.hand_qpos[:, :3], axis=1)
    seen = est.tracking.observed
    tip_err = np.linalg.norm(est.tracking.fingertips - ep.truth.fingertip_pos, axis=-1)
    assert seen.sum() > 50
    return float(np.median(palm_err)), float(np.median(tip_err[seen]))


def test_the_hand_is_tracked_where_the_camera_sees_it(lift_episode):
    """The tracker against a hand made of its own primitives (``hand_surface="capsules"``).
    Measured: palm 1.7 mm, observed fingertips 3.3 mm (medians; seeds 1-2: palm 2.1 / 2.0 mm,
    fingertips 3.8 / 3.5 mm; gates 8 and 10 mm)."""
    import dataclasses

    from benchmark.camera.render import render
    from benchmark.method.init import tracker_init
    from fsv import run_pipeline

    sim = lift_episode[0]
    ep = render(dataclasses.replace(sim, scenario=dataclasses.replace(sim.scenario, hand_surface="capsules")))
    est = run_pipeline(ep.depth, ep.calib, ep.object_model, ep.hand_model, tracker_init(ep.truth, ep.scenario, ep.hand_model),
                       gravity=ep.truth.gravity, rng=ep.scenario.rng("tracker"))
    palm, tips = _hand_errors(ep, est)
    assert palm < 0.008 and tips < 0.010, (palm, tips)


def test_the_skin_moves_the_fitted_palm_across_the_hand(tracked_lift):
    """The same lift seen as the person's skin: the primitive palm is fitted over the skin's palm
    with its eminences and moves across the hand. Measured: palm 11.3 mm (9.4 mm across the hand,
    3.6 mm along it), observed fingertips 5.6 mm (seeds 1-2: palm 4.7 / 6.3 mm, fingertips 4.2 /
    4.5 mm); bars 16 and 10 mm."""
    ep, est = tracked_lift
    assert ep.scenario.hand_surface == "skin"
    palm, tips = _hand_errors(ep, est)
    assert palm < 0.016 and tips < 0.010, (palm, tips)


def test_contacts_are_found_where_they_are_on_lift_with_1cm_noise(tracked_lift):
    """One short lift: the median contact point error (Euclidean) <= 4 mm, recall and precision
    >= 0.85. Measured on this 2.5 s lift, seed 0: 2.31 mm, recall 0.996, precision 0.953 (seeds 1-2:
    2.29 / 1.97 mm, precision 0.988 / 0.980; the same bits under the Haswell and Sandybridge kernels).
    The per-axis spread and bias are not gated on a single lift: over seeds 0-2 the std is 1.92 /
    2.33 / 1.28 mm and the mean -0.14 / -0.30 / +0.36 mm (a few frames of one contact carry them).
    The issue's 4 mm std and 0.9 recall and precision are gated as statistics over four 10 s lifts
    below."""
    ep, est = tracked_lift
    s = score_tracking(est.tracking, ep.truth)
    assert s["contact_pairs"] > 200
    assert s["contact_err_mm_median_euclid"] <= 4.0, s
    assert s["contact_recall"] >= 0.85 and s["contact_precision"] >= 0.85, s
    report = dict(zip((g.metric for g in GATES), gate_report(s)))
    assert len(report) == len(GATES) and report["contact_err_mm_std"].passed == (s["contact_err_mm_std"] <= 4.0)


def test_scores_of_a_perfect_tracker_are_zero_and_one(lift_episode):
    tr = lift_episode[0].truth
    T = len(tr.t)
    perfect = Tracking(box=Poses(tr.t, tr.box_pos, tr.box_rot), hand_qpos=tr.hand_qpos, fingertips=tr.fingertip_pos,
                       observed=np.ones(tr.contact_active.shape, bool), box_inliers=np.ones(T), hand_explained=np.ones(T),
                       contacts=contacts_from_truth(tr), timing_s={})
    s = score_tracking(perfect, tr)
    assert s["contact_pairs"] == tr.contact_active.sum() > 0
    for key in ("box_pos_err_mm", "box_rot_err_deg", "fingertip_err_mm",
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
    assert len(gate_report(s)) == len(GATES) and all(r.passed for r in gate_report(s))
    far = type(c)(c.finger_names, c.active, c.sliding, c.point + np.array([0.0105, 0.0, 0.0]), c.normal, c.slide_dir)
    report = gate_report(score_tracking(perfect, tr, far))  # per-axis mean 3.5 mm, std 4.95 mm
    assert [g.metric for g, r in zip(GATES, report) if not r.passed] == ["contact_err_mm_mean_abs", "contact_err_mm_std"]


def test_a_camera_from_a_lab_calibration_widens_only_the_box_gates(lift_episode, rendered_lift_episode):
    from benchmark.method.knowledge import given
    from benchmark.scores.tracking import CALIBRATED_GATES, gates_for

    told = {name: given(rendered_lift_episode, name)[3].camera_from_lab
            for name in ("exact", "lab", "lab-hand", "lab-box", "lab-camera", "lab:0.5")}
    assert told == {"exact": False, "lab": True, "lab-hand": False, "lab-box": False, "lab-camera": True, "lab:0.5": True}
    assert gates_for(False) == GATES and gates_for(True) == CALIBRATED_GATES
    assert [g.metric for g in CALIBRATED_GATES] == [g.metric for g in GATES] and CALIBRATED_GATES[2:] == GATES[2:]
    tr = lift_episode[0].truth
    T = len(tr.t)
    shifted = Tracking(box=Poses(tr.t, tr.box_pos + np.array([0.004, 0.0, 0.0]), tr.box_rot), hand_qpos=tr.hand_qpos,
                       fingertips=tr.fingertip_pos, observed=np.ones(tr.contact_active.shape, bool),
                       box_inliers=np.ones(T), hand_explained=np.ones(T), contacts=contacts_from_truth(tr), timing_s={})
    s = score_tracking(shifted, tr)  # the box 4 mm off, as a principal point 1.5 px off moves it at 0.55 m
    assert abs(s["box_pos_err_mm"] - 4.0) < 1e-9
    assert not gate_report(s)[0].passed and gate_report(s, True)[0].passed


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
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    from PIL import Image

    img = np.asarray(Image.open(path).convert("RGB")).astype(int)
    assert img.shape[1] >= 3 * 450 and img.shape[0] >= 2 * 200  # four panels, three to a row, each ~500 px wide

    def share(rgb, tol=40):
        return float(np.mean(np.all(np.abs(img - np.array(rgb)) <= tol, axis=-1)))

    # the tracked box's edges (lime), the fingertips seen (red) and the contacts (cyan) are drawn
    assert share((0, 255, 0)) > 1e-4 and share((255, 0, 0)) > 1e-5 and share((0, 255, 255), tol=60) > 1e-5
    assert [p.name for p in tmp_path.iterdir()] == ["o.png"]  # written atomically, no temp file left
    without = share((255, 215, 0), tol=30)  # no truth asked for
    with_truth = plot_overlay(ep.depth, ep.calib, est.tracking, ep.object_model, ep.hand_model, tmp_path / "t.png",
                              frames=4, truth=ep.truth)
    img = np.asarray(Image.open(with_truth).convert("RGB")).astype(int)
    # the true box and hand in gold, plain on the grey where they show beside the tracked ones (measured
    # 3.1e-4 of the pixels with the truth, 0 without)
    assert without == 0.0 and share((255, 215, 0), tol=30) > 1e-4


@pytest.mark.parametrize("frames", [6, 4, 1])
def test_the_overlays_fixed_layout_keeps_its_times_and_legend_inside_and_apart(tracked_lift, frames):
    """Every panel with its time, and the legend, inside the figure; no two panels, and no panel and
    the legend, on each other (the layout is fixed in inches, never measured)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from test_layout import check_layout

    ep, est = tracked_lift
    fig = overlay_figure(ep.depth, ep.calib, est.tracking, ep.object_model, ep.hand_model, frames=frames,
                         truth=ep.truth)
    assert len(fig.axes) == frames and all(len(ax.texts) == 1 for ax in fig.axes)
    check_layout(fig)
    renderer = FigureCanvasAgg(fig).get_renderer()
    legend = fig.legends[0].get_window_extent(renderer)
    assert legend.y0 >= 0 and legend.x0 >= 0 and legend.x1 <= fig.bbox.width
    assert all(ax.get_tightbbox(renderer).y0 >= legend.y1 for ax in fig.axes)


@pytest.mark.accuracy
def test_tracking_gates_hold_as_statistics_over_four_default_lifts(tracked_lifts):
    """The contact and box gates of ``benchmark.scores.tracking.GATES`` as statistics over the 10 s lifts of
    seeds 1-4 (never used for tuning), ds325 sensor. Measured (issue 45's contacts, seen-off evidence
    spanning the hold): contact std 1.11 / 1.16 / 1.64 / 1.03 mm, median 1.135 mm (gate 3 mm on the
    median; the issue's 4 mm per episode holds on all four); mean -0.23 / +0.17 / +0.27 / +0.05 mm;
    recall 1.000 / 0.995 / 0.954 / 0.995; precision 0.988 / 0.985 / 0.981 / 0.995; box 0.95-1.17 mm
    (median 1.13), 0.91-1.38 deg (median 1.27). The box gates are 2 mm and 2 deg, as on the smoke
    suite."""
    scores = [t for _, _, t, _, _ in tracked_lifts]

    def med(key):
        return float(np.median([s[key] for s in scores]))

    assert all(s["contact_pairs"] > 800 for s in scores), [s["contact_pairs"] for s in scores]
    assert med("contact_err_mm_std") <= 3.0 and max(s["contact_err_mm_std"] for s in scores) <= 4.0, scores
    assert abs(np.mean([s["contact_err_mm_mean"] for s in scores])) <= 2.0, [s["contact_err_mm_mean"] for s in scores]
    assert med("contact_recall") >= 0.9 and med("contact_precision") >= 0.9, scores
    assert med("box_pos_err_mm") <= 2.0 and med("box_rot_err_deg") <= 2.0, scores


@pytest.mark.accuracy
def test_net_force_from_depth_over_four_default_lifts(tracked_lifts):
    """Net force of the nominal forces against the truth's frame-mean resultant, whole method from
    depth. Measured RMS 0.077 / 0.072 / 0.055 / 0.064 N, median 0.068 N (gate 0.15 N on the median,
    0.3 N on the worst; the instantaneous resultant, which a 30 fps camera cannot resolve, is not the
    reference). Least-violation frames (the programs were infeasible on the tracked contacts): 0 of
    1172 (gate 40)."""
    rms = [f["net_force_err_n_rms"] for _, _, _, f, _ in tracked_lifts]
    assert np.median(rms) <= 0.15 and max(rms) <= 0.3, rms
    least_violation = [f["solver_failures"] for _, _, _, f, _ in tracked_lifts]
    assert sum(least_violation) <= 40, least_violation


@pytest.mark.accuracy
def test_learned_forces_from_depth_over_four_default_lifts(tracked_lifts):
    """The shipped model (trained on 40 people of the training split, never on user 0) on tracked
    contacts and kinematics with user 0's grip calibration: the relative error of Table 2 per
    episode over every contact frame (unsolved frames at the differentiator's ends count as 0 N).
    Measured 30.6 / 28.5 / 42.8 / 29.8 %, median 30.2 % (gate 50 %) on the world whose people grip
    at their margins, where less of the force is squeeze (21.7 % when they squeezed as one pattern,
    gate 30 %). Under the paper's sample rule 29.7 / 27.6 / 25.1 / 28.8 %, median 28.2 % (the
    paper's Table 2: 9.7-10.9 % on its own cohort)."""
    err = [b["rel_err_pct_mean"] for _, _, _, _, b in tracked_lifts]
    assert np.median(err) <= 50.0, err
    paper = [b["paper_rule"]["rel_err_pct_mean"] for _, _, _, _, b in tracked_lifts]
    assert np.median(paper) <= 50.0, paper
    scored = [(b["scored"], b["paper_rule"]["scored"]) for _, _, _, _, b in tracked_lifts]
    # every contact frame is scored; the paper's sample rule keeps > 600 frames (measured 987 / 970,
    # 948 / 933, 932 / 783, 973 / 955: all four; the third kept 30 of 716, learned error 160.8 %, while
    # the out-of-grasp evidence dropped its true ring finger on one window of a stray hand fit)
    assert all(every > 600 and every >= paper for every, paper in scored), scored
    assert all(paper > 600 for _, paper in scored), scored
    unsolved = [b["unsolved_frac"] for _, _, _, _, b in tracked_lifts]
    assert all(u < 0.05 for u in unsolved), unsolved  # measured 0.011-0.012
