"""fsv-bench leaderboard: the reference and its variants on one suite, sharing episodes and tracking."""

import json

import pytest
from tiny_suite import TINY

from benchmark.commands.cli import main
from benchmark.suites import SUITES
from benchmark.suites.leaderboard import VARIANTS


@pytest.fixture
def tiny(monkeypatch):
    monkeypatch.setitem(SUITES, "tiny", TINY)
    return TINY


def test_the_leaderboard_scores_every_variant_and_the_oracles_score_as_truth(tiny, tmp_path, capsys):
    out = tmp_path / "board"
    assert main(["leaderboard", "--suite", "tiny", "--out", str(out), "--cache", str(tmp_path / "c"), "--quiet"]) == 0
    table, skills = (out / "leaderboard.md").read_text().split("Skill against the best baseline")
    assert sum(line.startswith(f"| {name} |") for name in VARIANTS for line in table.splitlines()) == len(VARIANTS)
    assert "| best baseline |" in skills and "| reference |" in skills and "| baseline-static |" not in skills
    s = {name: json.loads((out / name / "scores.json").read_text())["episodes"][0] for name in VARIANTS}
    assert s["reference"]["rendered"] and not s["central"]["rendered"]  # rendered once for all
    lab = [n for n in VARIANTS if n != "baseline-static" and not n.endswith("-knowledge")]
    assert len({s[n]["box_pos_err_mm"] for n in lab}) == 1  # one tracking run shared
    assert s["exact-knowledge"]["box_pos_err_mm"] != s["reference"]["box_pos_err_mm"]  # the camera told without errors
    assert s["exact-knowledge"]["knowledge"]["knowledge"] == "exact" and s["reference"]["knowledge"]["knowledge"] == "lab"
    assert s["baseline-static"]["box_pos_err_mm"] > 10 * s["reference"]["box_pos_err_mm"]  # no vision at all
    assert s["oracle-kinematics"]["acc_err_rms"] < 1e-9 < 0.05 < s["reference"]["acc_err_rms"]
    assert s["oracle-contacts"]["contact_err_mm_std"] == 0.0 and s["oracle-contacts"]["contact_recall"] == 1.0
    assert s["central"]["acc_err_rms"] > s["reference"]["acc_err_rms"]  # measured 3.3 vs 0.29 m/s^2
    labels = json.loads((out / "oracle-contacts-kinematics" / "scores.json").read_text())["method"]
    assert "contacts: oracle" in labels and "differentiator: oracle" in labels
    # the two protocols side by side: the same tracking, the calibrated one told user 0's grip line
    assert s["reference"]["protocol"] == "blind" and s["calibrated"]["protocol"] == "calibrated"
    assert s["baseline-grip-line"]["protocol"] == "calibrated" and s["baseline-no-internal"]["protocol"] == "blind"
    assert s["calibrated"]["learned_rel_err_pct"] != s["reference"]["learned_rel_err_pct"]
    assert s["calibrated"]["net_force_err_n_rms"] == s["reference"]["net_force_err_n_rms"]  # forces before learning
    assert "protocol: calibrated" in json.loads((out / "calibrated" / "scores.json").read_text())["method"]
    # the spread over grasp families: the tiny suite's one episode, grasp 0 of the width-four family
    # the peers' metrics in newtons (means over the episodes), final forces: the reference's finite
    head = next(line for line in table.splitlines() if line.startswith("| method |"))
    for header in ("per-contact MAE [N] (mean)", "per-contact RMSE [N] (mean)", "normal MAE [N] (mean)",
                   "tangential MAE [N] (mean)", "peak-force MAE [N] (mean)"):
        assert header in head
    ref = s["reference"]
    assert 0 < ref["force_normal_mae_n"] <= ref["force_mae_n"] <= ref["force_rmse_n"] < 20
    assert ref["force_tangential_mae_n"] <= ref["force_mae_n"] and 0 <= ref["peak_force_err_n"] < 20
    none = s["baseline-no-internal"]  # its final forces are its nominal ones
    assert none["force_mae_n"] == pytest.approx(none["nominal_force_mae_n"]) and none["force_mae_n"] > 0
    # the grip is learned: 1.21 vs 1.84 N (1.7 vs 5.7 N when the people squeezed as one pattern)
    assert ref["force_normal_mae_n"] < 0.8 * ref["nominal_force_normal_mae_n"]
    spread = table.split("Spread of **reference**")[1] if "Spread of" in table else skills.split("Spread of **reference**")[1]
    assert "| width-four | 1 |" in spread and "the worst person 0" in spread


def test_skill_is_measured_against_the_baseline_of_the_metrics_stage():
    from benchmark.scores.leaderboard import skill, skill_table

    assert skill(0.25, 1.0, "acc_err_rms") == 0.75 and skill(1.5, 1.0, "acc_err_rms") == -0.5
    assert skill(0.9, 0.5, "contact_recall") == pytest.approx(0.8) and skill(0.9, 1.0, "contact_recall") is None
    assert skill(None, 1.0, "acc_err_rms") is None

    def scores(**medians):
        from benchmark.scores.metrics import METRICS

        agg = {m: {s: {"value": medians.get(m, 1.0)} for s in ("median", "mean")} for m in METRICS}
        return {"aggregate": agg}

    entries = [("reference", scores(acc_err_rms=0.3)),
               ("baseline-zero-kinematics", scores(acc_err_rms=0.6)),
               ("baseline-gravity-forces", scores(acc_err_rms=0.3))]  # the reference's kinematics: not the acc's baseline
    lines = skill_table(entries, {"zero-kinematics": "differentiator", "gravity-forces": "forces"})
    best = next(line for line in lines if line.startswith("| best baseline"))
    assert "0.6 (zero-kinematics)" in best
    row = next(line for line in lines if line.startswith("| reference")).split(" | ")
    assert row[4] == "0.50"  # 1 - 0.3 / 0.6
