"""benchmark.paper.ahrs: a lab's Xsens MTi-300 on the box, and Table 1 against it."""

import csv
import dataclasses
import json
import math
import pathlib
import re

import numpy as np
import pytest

from benchmark.errors import ScenarioError
from benchmark.paper import ahrs
from benchmark.paper.ahrs import (
    IDEAL,
    MTI_300,
    AhrsParams,
    draw,
    lab_readings,
    read,
    resample,
    sample_instants,
    shift_resolved,
)
from benchmark.paper.table1 import PAPER, score_episodes
from benchmark.world.pose_error import tracker_like_poses
from benchmark.world.scenario import Scenario

ROOT = pathlib.Path(__file__).resolve().parents[1]
G0 = 9.80665


def _rng(seed=0):
    return np.random.default_rng(seed)


def test_the_datasheet_values_in_si_units():
    p = MTI_300
    assert p.acc_noise_density_mps2_rthz == pytest.approx(5.884e-4, rel=1e-3)  # 60 ug/sqrt(Hz)
    assert p.gyro_noise_density_radps_rthz == pytest.approx(1.7453e-4, rel=1e-4)  # 0.01 deg/s/sqrt(Hz)
    assert (p.acc_bandwidth_hz, p.gyro_bandwidth_hz) == (375.0, 415.0)
    assert p.acc_bias_instability_mps2 == pytest.approx(1.471e-4, rel=1e-3)  # 15 ug
    assert p.gyro_bias_instability_radps == pytest.approx(4.848e-5, rel=1e-3)  # 10 deg/h
    assert p.gyro_range_radps == pytest.approx(7.854, rel=1e-3) and p.acc_range_mps2 == pytest.approx(196.13, rel=1e-4)


@pytest.mark.parametrize("field, value", [("acc_noise_density_mps2_rthz", -1.0), ("lever_arm_m", math.inf),
                                          ("time_offset_s", math.nan), ("output_rate_hz", 0.0), ("gyro_range_radps", "1"), ("acc_bandwidth_hz", math.inf),
                                          ("mounting_misalignment_rad", 2.0), ("acc_scale_factor_error", True)])
def test_bad_parameters_are_refused_by_name(field, value):
    with pytest.raises(ScenarioError, match=re.escape(f"AhrsParams.{field}")):
        AhrsParams(**{field: value})


def test_only_keeps_one_source_and_names_the_accepted_ones():
    p = MTI_300.only("timing")
    assert p.time_offset_s == MTI_300.time_offset_s and p.output_rate_hz == 100.0
    assert p.lever_arm_m == 0 and p.acc_noise_density_mps2_rthz == 0 and p.mounting_misalignment_rad == 0
    assert IDEAL.output_rate_hz == math.inf and IDEAL.describe()["output_rate_hz"] == "inf"
    with pytest.raises(ScenarioError, match="accepted: noise, bias"):
        MTI_300.only("drift")


def test_the_ideal_ahrs_reads_the_truth_bit_for_bit(analytic_truth):
    r = read(analytic_truth, 30.0, _rng(), IDEAL)
    assert np.array_equal(r.acc, analytic_truth.imu_acc) and np.array_equal(r.gyro, analytic_truth.imu_gyro)
    with pytest.raises(ScenarioError, match="not k / 25 s"):
        read(analytic_truth, 25.0, _rng())
    with pytest.raises(ScenarioError, match="fps must be"):
        read(analytic_truth, math.nan, _rng())


def test_noise_std_is_the_density_times_the_root_of_the_bandwidth(analytic_truth_factory):
    truth = analytic_truth_factory(duration_s=300.0)  # 9000 frames, 27000 samples per sensor
    r = read(truth, 30.0, _rng(1), MTI_300.only("noise"))
    sigma_a, sigma_g = np.std(r.acc - truth.imu_acc), np.std(r.gyro - truth.imu_gyro)
    # 60 ug/sqrt(Hz) sqrt(375 Hz) = 0.01139 m/s^2; 0.01 deg/s/sqrt(Hz) sqrt(415 Hz) = 0.003556 rad/s (measured
    # 0.01137 and 0.003529: -0.2 % and -0.7 %, the sampling error of 27000 draws)
    assert sigma_a == pytest.approx(60e-6 * G0 * math.sqrt(375.0), rel=0.02)
    assert sigma_g == pytest.approx(math.radians(0.01) * math.sqrt(415.0), rel=0.02)
    lag1 = np.mean((r.acc - truth.imu_acc)[1:] * (r.acc - truth.imu_acc)[:-1]) / sigma_a**2
    assert abs(lag1) < 0.02  # white: readings 33 ms apart are independent


def test_the_bias_is_constant_within_an_episode_and_within_its_bounds(analytic_truth):
    p = MTI_300.only("bias")
    biases = []
    for seed in range(50):
        r = read(analytic_truth, 30.0, _rng(seed), p)
        e_acc, e_gyro = r.acc - analytic_truth.imu_acc, r.gyro - analytic_truth.imu_gyro
        assert np.ptp(e_acc, axis=0).max() < 1e-13 and np.ptp(e_gyro, axis=0).max() < 1e-15
        assert np.allclose(e_acc[0], r.draw.acc_bias_mps2, atol=1e-14)
        biases.append(r.draw.gyro_bias_radps)
    b = np.abs(np.array(biases))
    assert b.max() <= math.radians(0.5) + 5 * p.gyro_bias_instability_radps
    assert b.max() > 0.8 * math.radians(0.5)  # the turn-on bound is used, not a tenth of it


def test_the_misalignment_is_a_rotation_within_its_bound():
    angles, worst_skew = [], 0.0
    for seed in range(300):
        d = draw(MTI_300, _rng(seed))
        C = d.rotation
        assert np.abs(np.einsum("ij,kj->ik", C, C) - np.eye(3)).max() < 1e-14 and np.linalg.det(C) == pytest.approx(1, abs=1e-14)
        angles.append(d.misalignment_rad)
        A = d.acc_axes / np.sqrt(np.einsum("ij,ij->i", d.acc_axes, d.acc_axes))[:, None]  # the sensitive axes
        for i, j in ((0, 1), (0, 2), (1, 2)):
            worst_skew = max(worst_skew, abs(math.degrees(math.acos(A[i] @ A[j])) - 90.0))
    angles = np.degrees(angles)
    assert angles.max() <= 1.1 + 1e-9 and angles.max() > 0.9  # mounting 1 deg plus the plate's 0.1 deg (max 1.078)
    assert np.median(angles) == pytest.approx(0.5, abs=0.1)  # a uniform angle in [0, 1 deg] (median 0.469)
    assert 0.03 < worst_skew <= 0.05 + 1e-9  # each pair of axes within 0.05 deg of orthogonal ([UM])


def test_a_misaligned_sensor_at_rest_reads_gravity_rotated_by_its_angle(analytic_truth):
    r = read(analytic_truth, 30.0, _rng(3), MTI_300.only("mounting"))
    g_true, g_read = analytic_truth.imu_acc[0], r.acc[0]  # frame 0: the box rests, the reading is -g rotated
    angle = math.acos(g_true @ g_read / (np.linalg.norm(g_true) * np.linalg.norm(g_read)))
    axis = r.draw.rotation - r.draw.rotation.T  # 2 sin(angle) [axis]x
    axis = np.array([axis[2, 1], axis[0, 2], axis[1, 0]]) / (2 * math.sin(r.draw.misalignment_rad))
    across = np.linalg.norm(np.cross(axis, g_true / np.linalg.norm(g_true)))  # sin of gravity's angle to the axis
    expected = 2 * math.asin(across * math.sin(r.draw.misalignment_rad / 2))
    assert angle == pytest.approx(expected, rel=1e-3, abs=1e-9) and 0 < angle <= r.draw.misalignment_rad
    assert np.linalg.norm(g_read) == pytest.approx(np.linalg.norm(g_true), rel=1e-12)


def test_the_lever_arm_adds_the_centripetal_and_tangential_accelerations(analytic_truth):
    T = len(analytic_truth.t)
    w = np.tile([0.0, 0.0, 3.0], (T, 1))  # spinning at 3 rad/s about the box's z axis, no angular acceleration
    spin = dataclasses.replace(analytic_truth, imu_gyro=w, box_alpha=np.zeros((T, 3)))
    r = read(spin, 30.0, _rng(4), MTI_300.only("lever arm"))
    rx, ry, _ = r.draw.lever_arm_m
    assert np.abs(r.draw.lever_arm_m).max() <= 0.005 and np.abs(r.draw.lever_arm_m).max() > 0.001
    d = r.acc - spin.imu_acc
    assert np.allclose(d, np.tile([-9.0 * rx, -9.0 * ry, 0.0], (T, 1)), atol=1e-12)  # -w^2 r in the spin plane


def test_sample_instants_pair_each_frame_with_the_nearest_output_sample():
    t = np.arange(9) / 30.0
    s = sample_instants(t, 0.004, 100.0)
    assert np.allclose(s, 0.004 + np.tile([0.0, -1 / 300, 1 / 300], 3), atol=1e-12)  # 33.3 ms reads the 30 ms sample
    assert np.array_equal(sample_instants(t, 0.004, math.inf), np.full(9, 0.004))


def test_the_time_offset_shifts_a_slow_signal_and_keeps_the_size_of_what_frames_do_not_resolve():
    t = np.arange(900) / 30.0
    slow = np.sin(2 * np.pi * 0.5 * t)[:, None]
    shift = np.full(900, 0.3)  # 10 ms later at 30 fps
    moved = shift_resolved(slow, shift)
    inner = slice(10, -10)
    assert np.abs(moved[inner, 0] - np.sin(2 * np.pi * 0.5 * (t + 0.01))[inner]).max() < 1e-4  # measured 1.7e-5
    assert np.abs(moved - slow)[inner].max() > 0.03  # and it did move (0.031 at the zero crossings)
    tremor = np.sin(2 * np.pi * 12.0 * t + 0.3)[:, None]
    rms = np.sqrt(np.mean(shift_resolved(tremor, np.full(900, 0.5))[inner] ** 2)) / np.sqrt(np.mean(tremor[inner] ** 2))
    cubic = np.sqrt(np.mean(resample(tremor, np.full(900, 0.5))[inner] ** 2)) / np.sqrt(np.mean(tremor[inner] ** 2))
    assert rms == pytest.approx(1.0, abs=0.03) and cubic < 0.5  # measured 0.984; the cubic alone: 0.449
    assert np.array_equal(shift_resolved(tremor, np.zeros(900)), tremor)


def test_the_readings_saturate_at_the_full_range(analytic_truth):
    r = read(analytic_truth, 30.0, _rng(), dataclasses.replace(IDEAL, gyro_range_radps=0.5, acc_range_mps2=9.0))
    assert np.abs(analytic_truth.imu_gyro).max() > 0.5 and np.abs(r.gyro).max() == 0.5
    assert np.abs(r.acc).max() == 9.0


def test_the_same_scenario_gives_the_same_bits_and_its_own_stream(analytic_truth):
    sc = Scenario(seed=7)
    a, b = lab_readings(analytic_truth, sc), lab_readings(analytic_truth, sc)
    assert a.acc.tobytes() == b.acc.tobytes() and a.gyro.tobytes() == b.gyro.tobytes()
    other = lab_readings(analytic_truth, Scenario(seed=8))
    assert not np.array_equal(a.acc, other.acc)
    # the "ahrs" stream: the pose errors are those drawn without it, and switching a source off moves no other draw
    before = tracker_like_poses(analytic_truth, sc)
    lab_readings(analytic_truth, sc)
    assert np.array_equal(tracker_like_poses(analytic_truth, sc).pos, before.pos)
    d, d_timing = draw(MTI_300, sc.rng("ahrs")), draw(MTI_300.only("timing"), sc.rng("ahrs"))
    assert d.time_offset_s == d_timing.time_offset_s != 0 and d_timing.misalignment_rad == 0


def test_table1_against_readings_scores_vision_minus_the_readings(analytic_truth):
    sc = Scenario(seed=0)
    poses = tracker_like_poses(analytic_truth, sc)
    ideal, kins = score_episodes([(analytic_truth, poses)])
    same, _ = score_episodes([(analytic_truth, poses)], readings=[read(analytic_truth, 30.0, _rng(), IDEAL)])
    assert same.stats == ideal.stats and "Compared with" not in ideal.markdown()
    offset = dataclasses.replace(IDEAL, acc_bias_instability_mps2=0.0, acc_turn_on_bias_mps2=0.5)
    r = read(analytic_truth, 30.0, _rng(2), offset)
    lab, _ = score_episodes([(analytic_truth, poses)], readings=[r], reference="a biased AHRS")
    assert lab.stats["algebraic"]["acc_mean"] == pytest.approx(ideal.stats["algebraic"]["acc_mean"] - r.draw.acc_bias_mps2.mean(), abs=1e-12)
    assert "Compared with: a biased AHRS." in lab.markdown()
    with pytest.raises(ScenarioError, match="1 AHRS recordings for 2 episodes"):
        score_episodes([(analytic_truth, poses)] * 2, readings=[r])


def test_the_committed_table_against_the_mti_300_is_quoted_in_the_docs():
    """results/table1_ahrs (``fsv-bench reproduce --only table1-ahrs``) beside the paper's, as docs/findings.md
    and docs/results.md quote it."""
    rows = {r["method"]: r for r in csv.DictReader(open(ROOT / "results/table1_ahrs/table1.csv"))}
    ideal = {r["method"]: r for r in csv.DictReader(open(ROOT / "results/table1/table1.csv"))}
    for m in ("central", "gaussian", "algebraic"):
        assert float(rows[m]["paper_acc_std"]) == PAPER[m]["acc_std"] and float(rows[m]["paper_gyro_std"]) == PAPER[m]["gyro_std"]
    findings = " ".join((ROOT / "docs/findings.md").read_text().split())
    results = (ROOT / "docs/results.md").read_text()
    cells = " | ".join(f"{float(rows[m]['acc_std']):.3f} / {PAPER[m]['acc_std']:.3f}" for m in ("central", "gaussian", "algebraic"))
    assert f"| Trans. acc. std | {cells} |" in findings
    cells = " | ".join(f"{float(rows[m]['gyro_std']):.3f} / {PAPER[m]['gyro_std']:.3f}" for m in ("central", "gaussian", "algebraic"))
    assert f"| Rot. vel. std | {cells} |" in findings
    acc = " / ".join(f"{float(rows[m]['acc_std']):.3f}" for m in ("central", "gaussian", "algebraic"))
    gyro = " / ".join(f"{float(rows[m]['gyro_std']):.3f}" for m in ("central", "gaussian", "algebraic"))
    assert f"against the MTi-300 {acc}" in results and f"against the MTi-300 {gyro}" in results
    ideal_acc = " / ".join(f"{float(ideal[m]['acc_std']):.3f}" for m in ("central", "gaussian", "algebraic"))
    assert f"| 1.686 / 1.627 / 0.904 | {ideal_acc}" in results
    report = json.loads((ROOT / "results/table1_ahrs/ahrs.json").read_text())
    assert len(report["episodes"]) == 18 and set(report["sources"]) == {*ahrs.SOURCES, "all"}
    assert report["sources"]["all"]["algebraic"]["acc_std"] == pytest.approx(float(rows["algebraic"]["acc_std"]), rel=1e-5)
