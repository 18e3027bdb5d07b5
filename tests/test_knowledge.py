"""What the method is told (benchmark.method.knowledge): exact values, or a lab's measurements with their errors."""

from types import SimpleNamespace

import numpy as np
import pytest

from benchmark.camera.camera import camera_calibration
from benchmark.method import knowledge as K
from benchmark.scores.frames import rot_in_true_world, tracking_in_true_world
from benchmark.world.assets import hand_model, object_model
from benchmark.world.scenario import Scenario
from fsv.types import Poses


def _episode(seed=0, user=0, mass=0):
    sc = Scenario(task="lift", user=user, mass=mass, seed=seed)
    return SimpleNamespace(scenario=sc, object_model=object_model(sc), hand_model=hand_model(sc),
                           calib=camera_calibration())


def test_exact_knowledge_is_the_simulations_own_and_maps_nothing():
    ep = _episode()
    hand, obj, calib, known = K.given(ep, "exact")
    assert hand is ep.hand_model and obj is ep.object_model and calib is ep.calib
    np.testing.assert_array_equal(known.world_from_method, np.eye(4))
    assert all(v["error"] == 0.0 for v in known.record().values() if isinstance(v, dict))
    assert known.given_record()["measurement_sd"]["hand_length_m"] == 0.0


def test_lab_knowledge_is_drawn_from_the_scenario_and_differs_by_seed():
    a, b, c = (K.given(_episode(seed=s), "lab")[3].record() for s in (3, 3, 4))
    assert a == b  # the same scenario, the same errors
    assert a["mass_kg"]["error"] != c["mass_kg"]["error"]
    assert a["knowledge"] == "lab"


def test_lab_errors_have_the_stated_sizes():
    """Over 400 scenarios, each error's spread is its stated standard deviation (within 15 %)."""
    recs = [K.given(_episode(seed=s), "lab")[3].record() for s in range(400)]
    err = {k: np.array([r[k]["error"] for r in recs]) for k in ("hand_length_m", "hand_breadth_m", "mass_kg",
                                                                  "cx_px", "cy_px")}
    assert np.std(err["hand_length_m"]) == pytest.approx(K.RULER_SD_M, rel=0.15)
    assert np.std(err["hand_breadth_m"]) == pytest.approx(K.RULER_SD_M, rel=0.15)
    assert np.std(err["mass_kg"]) == pytest.approx(K.SCALE_SD_KG, rel=0.15)
    assert np.std(err["cx_px"]) == pytest.approx(K.PRINCIPAL_SD_PX, rel=0.15)
    fx = np.array([r["fx_px"]["error"] / r["fx_px"]["true"] for r in recs])
    assert np.std(fx) == pytest.approx(K.FOCAL_SD_REL, rel=0.15)
    # the tilt test: mu = tan(theta), theta's error 1.5 deg -> mu's error about (1 + mu^2) * 0.026 at mu = 0.8
    mu = np.array([r["friction"]["error"] for r in recs])
    assert np.std(mu) == pytest.approx((1 + 0.8**2) * K.TILT_SD_RAD, rel=0.15)
    # the extrinsics: the angle of a 3-axis normal error with 0.2 deg per axis has an RMS of 0.2 * sqrt(3)
    rot = np.array([r["camera_rot_err_deg"] for r in recs])
    assert np.sqrt(np.mean(rot**2)) == pytest.approx(np.degrees(K.EXTRINSIC_ROT_SD_RAD) * np.sqrt(3), rel=0.15)


def test_lab_hand_and_box_are_the_measured_ones():
    ep = _episode(seed=7, user=2)
    hand, obj, calib, known = K.given(ep, "lab")
    r = known.record()
    ratio = np.sqrt(r["hand_length_m"]["given"] / r["hand_length_m"]["true"]
                    * r["hand_breadth_m"]["given"] / r["hand_breadth_m"]["true"])
    assert r["hand_scale"]["given"] == pytest.approx(1.08 * ratio)  # user 2's hand scale is 1.08
    # the given hand is the template (none of user 2's proportions) stretched to the measured length
    # along the hand and the measured breadth across it: its radii scale with the breadth alone
    from benchmark.world.anatomy import Anatomy
    from benchmark.world.hand import hand_model

    template = hand_model(Anatomy.template(1.0))
    np.testing.assert_allclose(hand.geom_radius, template.geom_radius * r["hand_breadth_m"]["given"] / 0.085, rtol=1e-12)
    assert not np.allclose(hand.geom_radius, ep.hand_model.geom_radius * r["hand_scale"]["given"] / 1.08, rtol=1e-3)
    flat = hand_model(Anatomy(length_scale=r["hand_length_m"]["given"] / 0.190,
                              breadth_scale=r["hand_breadth_m"]["given"] / 0.085))
    np.testing.assert_array_equal(hand.geom_radius, flat.geom_radius)
    assert obj.mass_kg == r["mass_kg"]["given"] and obj.friction == r["friction"]["given"]
    np.testing.assert_allclose(obj.inertia, obj.solid_box_inertia(obj.size_m, obj.mass_kg))


def test_world_from_method_carries_the_given_camera_onto_the_true_one():
    ep = _episode(seed=5)
    _, _, calib, known = K.given(ep, "lab")
    np.testing.assert_allclose(known.world_from_method @ calib.T_world_cam, ep.calib.T_world_cam, atol=1e-12)
    # a box the method sees exactly (in the camera frame) lands on the truth once carried over
    T_true, T_given = ep.calib.T_world_cam, calib.T_world_cam
    p_cam = np.array([[0.02, -0.01, 0.55]])
    R_cam = np.eye(3)[None]
    truth = Poses(t=np.zeros(1), pos=p_cam @ T_true[:3, :3].T + T_true[:3, 3], rot=T_true[:3, :3] @ R_cam)
    seen = Poses(t=np.zeros(1), pos=p_cam @ T_given[:3, :3].T + T_given[:3, 3], rot=T_given[:3, :3] @ R_cam)
    mapped = tracking_in_true_world(SimpleNamespace(box=seen, contacts=None), known.world_from_method)
    np.testing.assert_allclose(mapped.box.pos, truth.pos, atol=1e-12)
    np.testing.assert_allclose(mapped.box.rot, truth.rot, atol=1e-12)
    np.testing.assert_allclose(rot_in_true_world(seen.rot, known.world_from_method), truth.rot, atol=1e-12)
    same = SimpleNamespace(box=seen, contacts=None)
    assert tracking_in_true_world(same, np.eye(4)) is same and rot_in_true_world(seen.rot, None) is seen.rot


def test_what_a_method_may_read_holds_no_truth():
    ep = _episode(seed=2)
    known = K.given(ep, "lab")[3]
    r = known.given_record()
    assert set(r) == {"knowledge", "hand_length_m", "hand_breadth_m", "hand_scale", "mass_kg", "friction",
                      "measurement_sd"}
    true = known.record()
    for key in ("hand_length_m", "hand_breadth_m", "hand_scale", "mass_kg", "friction"):
        assert r[key] == true[key]["given"] != true[key]["true"]
    assert r["measurement_sd"]["mass_kg"] == K.SCALE_SD_KG


def test_one_source_alone_takes_the_same_draws_as_lab_and_leaves_the_others_exact():
    ep = _episode(seed=11)
    lab = K.given(ep, "lab")[3].record()
    for source, keys in (("hand", ("hand_length_m", "hand_breadth_m")), ("box", ("mass_kg", "friction")),
                         ("camera", ("fx_px", "fy_px", "cx_px", "cy_px"))):
        hand, obj, calib, known = K.given(ep, f"lab-{source}")
        r = known.record()
        for key in ("hand_length_m", "hand_breadth_m", "mass_kg", "friction", "fx_px", "fy_px", "cx_px", "cy_px"):
            assert r[key]["error"] == (lab[key]["error"] if key in keys else 0.0), (source, key)
        assert (calib is ep.calib) == (source != "camera")
        assert np.array_equal(known.world_from_method, np.eye(4)) == (source != "camera")


def test_a_factor_scales_the_same_draws_and_zero_is_a_perfect_lab():
    ep = _episode(seed=13, user=1)
    lab, same, double, zero = (K.given(ep, n) for n in ("lab", "lab:1", "lab:2", "lab:0"))
    keys = ("hand_length_m", "hand_breadth_m", "mass_kg", "fx_px", "fy_px", "cx_px", "cy_px")
    assert same[3].record() == {**lab[3].record(), "knowledge": "lab:1"}  # the same bits as plain lab
    for key in keys:  # exactly twice the errors (a power of two: no rounding)
        assert double[3].record()[key]["error"] == pytest.approx(2 * lab[3].record()[key]["error"], rel=1e-12, abs=1e-15)
        assert zero[3].record()[key]["error"] == 0.0
    assert double[3].camera_rot_err_deg == pytest.approx(2 * lab[3].camera_rot_err_deg, rel=1e-12)
    assert double[3].given_record()["measurement_sd"]["principal_px"] == 2 * K.PRINCIPAL_SD_PX
    # a perfect ruler still gives the generic hand (the lab's way), not the simulated one
    assert zero[0] is not ep.hand_model and zero[3].hand_scale_given == pytest.approx(zero[3].hand_scale_true, rel=0.05)
    assert zero[3].camera_from_lab and K.given(ep, "lab-box:3")[3].camera_from_lab is False
    np.testing.assert_allclose(zero[3].world_from_method, np.eye(4), atol=1e-12)  # T @ inv(T), a perfect calibration


@pytest.mark.parametrize("name, needle", [
    ("lab:x", "--knowledge 'lab:x': 'x' is not a number"),
    ("lab:-1", "--knowledge 'lab:-1': factor -1 is out of range"),
    ("lab:inf", "--knowledge 'lab:inf': factor inf is out of range"),
    ("lab-camera:1000", "factor 1000 is out of range"),
    ("exact:2", "--knowledge 'exact:2': accepted: exact, lab"),
    ("lab-skin", "--knowledge 'lab-skin': accepted: exact, lab, lab-hand, lab-box, lab-camera, each lab one optionally "
                 "with :FACTOR scaling its errors (0 to 100, e.g. lab:2)"),
])
def test_a_bad_factor_or_name_is_refused_naming_it_and_what_is_accepted(name, needle):
    with pytest.raises(ValueError) as e:
        K.check_knowledge(name)
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_an_unknown_knowledge_is_refused_by_name():
    with pytest.raises(ValueError, match=r"--knowledge 'oracle': accepted: exact, lab, lab-hand, lab-box, lab-camera"):
        K.check_knowledge("oracle")


def test_the_main_command_refuses_an_unknown_knowledge_with_status_2(tmp_path, capsys):
    from benchmark.commands.cli import main

    with pytest.raises(SystemExit) as refused:  # refused while the command line is parsed
        main(["--task", "lift", "--knowledge", "guess", "--out", str(tmp_path / "o")])
    assert refused.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "--knowledge 'guess': accepted: exact, lab, lab-hand" in err and not (tmp_path / "o").exists()


def test_the_committed_ablation_on_dev_moves_what_each_source_touches():
    """``results/knowledge_ablation`` (``fsv-bench reproduce``): the box's mass and friction never
    reach the tracker, so ``lab-box`` tracks exactly as ``exact``; the calibration moves the box
    (measured 1.26 mm exact, 4.48 mm lab-camera, 5.18 mm lab, 9.23 mm at lab:2), and the generic hand alone
    leaves the box where it was (1.25 mm)."""
    import json
    import pathlib

    doc = json.loads((pathlib.Path(__file__).resolve().parents[1] / "results" / "knowledge_ablation" / "sweep.json")
                     .read_text())
    assert doc["axis"] == "knowledge" and doc["suite"]["name"] == "dev"
    box = {v: a["box_pos_err_mm"]["median"]["value"] for v, a in zip(doc["values"], doc["aggregate"])}
    std = {v: a["contact_err_mm_std"]["median"]["value"] for v, a in zip(doc["values"], doc["aggregate"])}
    assert box["lab-box"] == box["exact"] and std["lab-box"] == std["exact"]
    assert box["lab-camera"] > 3 * box["exact"] and box["lab:2"] > 1.4 * box["lab"]
    assert abs(box["lab-hand"] - box["exact"]) < 0.2
