"""benchmark.paper.table1: the Table 1 scorer, the tuning protocol and the Fig. 4 plot."""

import numpy as np
import pytest
from pictures import assert_figure

from benchmark.commands.table1 import write_outputs
from benchmark.errors import ScenarioError
from benchmark.paper.table1 import PAPER, Table1, error_stats, score_table1, tune
from benchmark.world.motion import DECLARED, oracle_kinematics
from benchmark.world.pose_error import tracker_like_poses
from benchmark.world.scenario import Scenario
from fsv import Kinematics, Poses
from fsv.kinematics import AlgebraicConfig, CentralConfig, GaussianConfig


def _biased(truth, acc_bias_body, gyro_bias_body):
    """Oracle kinematics plus constant box-frame biases of the AHRS readings."""
    k = oracle_kinematics(truth)
    R = truth.box_rot
    return Kinematics(
        t=k.t, pos=k.pos, rot=k.rot, vel=k.vel,
        acc=k.acc + np.einsum("tij,j->ti", R, acc_bias_body),
        omega=k.omega + np.einsum("tij,j->ti", R, gyro_bias_body),
        alpha=k.alpha, valid=k.valid, method="biased",
    )


def test_error_stats_pool_axes_and_frames(analytic_truth):
    kin = _biased(analytic_truth, np.array([0.1, -0.2, 0.4]), np.array([0.0, 0.3, 0.0]))
    window = np.zeros(len(analytic_truth.t), bool)
    window[10:50] = True
    s = error_stats(kin, analytic_truth, window)
    assert s["acc_mean"] == pytest.approx(0.1, abs=1e-12)
    assert s["acc_std"] == pytest.approx(np.std([0.1, -0.2, 0.4]), abs=1e-12)
    assert s["gyro_mean"] == pytest.approx(0.1, abs=1e-12)
    assert s["gyro_std"] == pytest.approx(np.std([0.0, 0.3, 0.0]), abs=1e-12)
    with pytest.raises(ScenarioError, match="empty"):
        error_stats(kin, analytic_truth, np.zeros_like(window))


def test_oracle_kinematics_reproduce_the_ahrs(analytic_truth):
    s = error_stats(oracle_kinematics(analytic_truth), analytic_truth, np.ones(len(analytic_truth.t), bool))
    assert max(abs(v) for v in s.values()) < 1e-12


def test_noiseless_poses_score_only_the_smoothing_bias(analytic_truth):
    poses = Poses(t=analytic_truth.t, pos=analytic_truth.box_pos, rot=analytic_truth.box_rot)
    table, kins = score_table1(analytic_truth, poses)
    for m in ("central", "gaussian", "algebraic"):
        assert table.stats[m]["acc_std"] < 0.2, m  # min-jerk peaks are 1.15 m/s^2 and 1.8 rad/s
        assert table.stats[m]["gyro_std"] < 0.06, m
    assert table.stats["central"]["acc_std"] < table.stats["algebraic"]["acc_std"]  # no noise: the shortest stencil wins


def test_table_on_tracker_like_poses(analytic_truth):
    poses = tracker_like_poses(analytic_truth, Scenario(seed=0))
    table, kins = score_table1(analytic_truth, poses)
    window = np.logical_and.reduce([k.valid for k in kins.values()])
    assert table.frames == window.sum() == len(analytic_truth.t) - 2 * (DECLARED["gaussian"].kernel().size // 2 + 1)
    for m, k in kins.items():
        assert table.stats[m] == error_stats(k, analytic_truth, window)
    assert table.stats["algebraic"]["acc_std"] < 0.5 * table.stats["central"]["acc_std"]
    assert table.stats["algebraic"]["gyro_std"] < 0.6 * table.stats["central"]["gyro_std"]
    md = table.markdown()
    for m in PAPER:
        assert f"{PAPER[m]['acc_std']:.3f}" in md and DECLARED[m].describe() in md
    assert "declared in advance" in md and "tuned on calibration seeds" in md
    assert set(table.summary()) == {"central", "gaussian", "algebraic"}
    assert set(table.summary()["algebraic"]) == {"acc_mean", "acc_std", "gyro_mean", "gyro_std"}
    assert table.csv().count("\n") == 4


def test_tuning_prefers_the_window_that_wins_on_calibration_episodes(analytic_truth):
    cal = [(analytic_truth, tracker_like_poses(analytic_truth, Scenario(seed=s))) for s in (1000, 1001)]
    grids = {
        "algebraic": (AlgebraicConfig(window_frames=5), AlgebraicConfig(window_frames=19)),
        "gaussian": (GaussianConfig(sigma_frames=0.5), GaussianConfig(sigma_frames=3.0)),
    }
    best, scores = tune(cal, grids)
    assert best["algebraic"] == AlgebraicConfig(window_frames=19)
    assert best["gaussian"] == GaussianConfig(sigma_frames=3.0)
    # The objective is normalised by central differences: 2 for the reference itself, less when better.
    assert tune(cal, {"central": (CentralConfig(),)})[1]["central"][0][1] == pytest.approx(2.0)
    assert all(j < 2.0 for _, j in scores["algebraic"])
    with pytest.raises(ScenarioError, match="calibration"):
        tune([])


def test_write_outputs_writes_table_and_png(analytic_truth, tmp_path):
    table, kins = score_table1(analytic_truth, tracker_like_poses(analytic_truth, Scenario(seed=0)))
    paths = write_outputs(table, analytic_truth, kins, tmp_path / "out")
    assert_figure(paths["plot"], min_width=1000, colours={"algebraic (tab:blue)": (31, 119, 180), "central (tab:red)": (214, 39, 40), "truth (black)": (0, 0, 0)})
    assert "Algebraic (ours / paper)" in paths["markdown"].read_text()
    assert paths["csv"].read_text().startswith("method,acc_mean")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["fig4_kinematics.png", "table1.csv", "table1.md"]


def test_table1_record_is_frozen():
    t = Table1({}, {}, {}, 0, "x")
    with pytest.raises(Exception):
        t.frames = 3


def test_on_the_default_lift_algebraic_is_no_worse_than_central(lift_episode):
    episode = lift_episode[0]
    table, _ = score_table1(episode.truth, tracker_like_poses(episode.truth, episode.scenario))
    alg, cen = table.stats["algebraic"], table.stats["central"]
    assert alg["acc_std"] <= cen["acc_std"] and alg["gyro_std"] <= cen["gyro_std"]
    assert abs(alg["acc_mean"]) < 0.2 and abs(alg["gyro_mean"]) < 0.05


@pytest.mark.parametrize("choice", ["algebraic", "oracle"])
def test_cli_stage_prints_and_writes_table1_and_labels_the_oracle(lift_episode, tmp_path, choice):
    from argparse import Namespace

    from benchmark.commands.stage import Run, complete
    from benchmark.commands.stages import kinematics

    episode = lift_episode[0]
    record = Run(scenario=episode.scenario, out=tmp_path, method_spec=None, episode=episode)
    result = kinematics.STAGE(record, Namespace(kinematics=choice, contacts="vision", no_pictures=False))
    complete(result, tmp_path)
    summary = dict(result.blocks)
    block = summary["kinematics"]
    assert set(block) == {"central", "gaussian", "algebraic"}
    assert all(set(v) == {"acc_mean", "acc_std", "gyro_mean", "gyro_std"} for v in block.values())
    info = summary["kinematics_info"]
    assert info["selected"] == choice and info["oracle"] == (choice == "oracle")
    text = "\n".join(result.lines)
    assert "1.686" in text and "Algebraic (ours / paper)" in text
    assert ("ORACLE" in text) == (choice == "oracle")
    assert_figure(tmp_path / "fig4_kinematics.png", min_width=1000, colours={"algebraic (tab:blue)": (31, 119, 180), "central (tab:red)": (214, 39, 40), "truth (black)": (0, 0, 0)})
    assert (tmp_path / "table1.md").read_text().startswith("| | Central")


def test_cli_parser_offers_the_kinematics_choices():
    from benchmark.commands.cli import build_parser

    args = build_parser().parse_args(["--kinematics", "oracle"])
    assert args.kinematics == "oracle"
    assert build_parser().parse_args([]).kinematics == "algebraic"
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--kinematics", "kalman"])


def test_pose_error_stats_recover_the_error_model(analytic_truth_factory):
    from benchmark.paper.table1 import pose_error_stats
    from benchmark.world.pose_error import PoseErrorModel

    truth = analytic_truth_factory(duration_s=60.0)
    model = PoseErrorModel(pos_std_m=0.002, rot_std_rad=np.radians(2.0), corr_time_s=0.1)
    episodes = [(truth, model.corrupt(truth.t, truth.box_pos, truth.box_rot, np.random.default_rng(s))) for s in (0, 1)]
    s = pose_error_stats(episodes)
    assert s["pos_std_mm"] == pytest.approx(2.0, rel=0.1)
    assert s["rot_std_deg"] == pytest.approx(2.0, rel=0.1)
    assert s["pos_lag1_corr"] == pytest.approx(np.exp(-1 / 3), abs=0.05)
    assert s["rot_lag1_corr"] == pytest.approx(np.exp(-1 / 3), abs=0.05)
