"""fsv.method.direct: the end-to-end network as the method's force stage, whose forces are the final ones."""

import json

import numpy as np
from test_direct import random_model
from test_direct_inputs import G, frames, model

from fsv.forces import FrameStatus, required_wrench, to_object_frame
from fsv.method import DirectForces


def test_the_solution_holds_the_prediction_and_what_it_leaves_of_the_required_wrench():
    m = random_model()
    valid = np.array([False, True, True, True, True])
    kin, con = frames(valid=valid)
    sol = DirectForces(m, source="test")(kin, con, model(), G)
    pred = m.predict(kin, con, model(), G)
    assert sol.kind == "direct" and list(sol.status) == [FrameStatus.NO_KINEMATICS] + [FrameStatus.OPTIMAL] * 4
    np.testing.assert_array_equal(sol.force[1:], pred.force[1:])
    np.testing.assert_array_equal(sol.nominal[1:], sol.force[1:])
    assert (sol.internal[1:] == 0).all() and np.isnan(sol.force[0]).all()
    np.testing.assert_array_equal(sol.env_wrench[1:], pred.table[1:])
    assert (sol.env_active[1:] == 4).all()  # resting flat on its face: four corners
    required = to_object_frame(kin.rot, required_wrench(kin, model(), G))
    np.testing.assert_allclose((sol.net_wrench + sol.residual)[1:], required[1:], atol=1e-12)
    np.testing.assert_allclose(sol.normal_force[1:, 0], -pred.force[1:, 0, 0])  # normal -x: the thumb's push
    assert (sol.normal_force[1:, 1] == 0).all() and not sol.active[0].any()
    assert DirectForces(m, source="test").name == "direct network from the tracker's outputs (test, 508 parameters)"


def test_a_final_force_stage_gives_the_final_forces_and_no_other_internal_stage_runs(rendered_lift_episode,
                                                                                     direct_dataset):
    """Through Method.after_tracking with the truth's contacts and kinematics (the oracle ablations)."""
    from benchmark.method import MethodSpec
    from benchmark.method.run import run_method
    from benchmark.scores.episode import score_episode
    from benchmark.world.contact_error import contacts_from_truth
    from fsv import Poses
    from fsv.method import TrackOutput

    ep = rendered_lift_episode
    truth_box = TrackOutput(box=Poses(t=ep.truth.t, pos=ep.truth.box_pos, rot=ep.truth.box_rot),
                            contacts=contacts_from_truth(ep.truth))
    spec = MethodSpec(method="direct", direct_model=str(direct_dataset[1] / "model.npz"), oracle=("contacts", "kinematics"))
    assert spec.tracking_key == MethodSpec().tracking_key  # shares the reference tracker's output
    est = run_method(spec, ep, tracking=truth_box)
    assert est.forces is est.nominal and est.forces.kind == "direct" and est.oracle == ("contacts", "kinematics")
    assert est.labels["internal"] == "none" and est.labels["forces"].startswith("direct network")
    assert est.labels["differentiator"] == est.labels["contacts"] == "oracle"
    scores = score_episode(ep, est)
    for metric in ("net_force_err_n_rms", "learned_rel_err_pct", "learned_mae_n", "force_mae_n", "force_rmse_n",
                   "peak_force_err_n", "nominal_force_mae_n"):
        assert np.isfinite(scores[metric]), metric
    assert scores["force_mae_n"] == scores["nominal_force_mae_n"]  # one solution scored as both
    assert scores["least_violation_frac"] == 0


def test_fsv_bench_runs_the_direct_method_and_scores_its_forces_as_both_stages(direct_dataset, tmp_path, capsys):
    from benchmark.commands.cli import main

    model_file = direct_dataset[1] / "model.npz"
    code = main(["--task", "lift", "--duration", "2", "--method", "direct", "--direct-model", str(model_file),
                 "--no-pictures", "--quiet", "--out", str(tmp_path / "run")])
    assert code in (0, 1)  # 1: a gate of the tiny model failed, not the run
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    f, learning = summary["forces"], summary["learning"]
    assert f["program"].startswith("direct network") and np.isfinite(f["net_force_err_n_rms"])
    assert learning["program"] == f["program"] and np.isfinite(learning["rel_err_pct_mean"])
    assert learning["direct_model"] == str(model_file) and learning["scored"] > 100
    assert f["status"]["optimal"] + f["status"]["no_kinematics"] == 61
    assert "learning [no oracle input]" in capsys.readouterr().out
