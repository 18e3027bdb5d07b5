"""End-to-end gate on a simulated lift: oracle contacts and kinematics, nominal forces against the truth."""

import json
import types

import numpy as np
import pytest
from pictures import assert_figure

from benchmark.commands.stage import Run, complete
from benchmark.commands.stages.forces import STAGE, add_arguments, estimate_inputs
from benchmark.scores.forces import score_forces, true_net_wrench_instant
from benchmark.world.contact_error import contacts_from_truth
from benchmark.world.motion import oracle_kinematics
from fsv.forces import FrameStatus, decompose_forces, nominal_forces, to_world_frame


@pytest.fixture(scope="module")
def lift(lift_episode):
    episode = lift_episode[0] if isinstance(lift_episode, tuple) else lift_episode
    kin = oracle_kinematics(episode.truth)
    contacts = contacts_from_truth(episode.truth)
    sol = nominal_forces(kin, contacts, episode.object_model, gravity=episode.truth.gravity)
    return episode, kin, contacts, sol


def test_the_nominal_resultant_is_the_true_resultant(lift):
    episode, kin, contacts, sol = lift
    tr = episode.truth
    # every frame solved exactly; measured: 75 of 76 optimal, one (0.43 s, the thumb alone touching
    # and sliding while the hand closes) held by static friction, which still explains the motion
    solved = np.isin(sol.status, (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION))
    assert solved.all() and np.mean(sol.status == FrameStatus.OPTIMAL) >= 0.95
    err = to_world_frame(kin.rot, sol.net_wrench) - true_net_wrench_instant(tr)  # the oracle kinematics are instantaneous
    assert np.sqrt(np.mean(np.sum(err[:, :3] ** 2, axis=1))) < 0.05  # measured 6.9e-12 N
    # The box must actually have been lifted and held for the gate to mean something.
    held = (sol.env_active == 0) & contacts.active.any(axis=1)
    assert held.sum() >= 10 and tr.box_pos[held, 2].max() > tr.box_pos[0, 2] + 0.01


def test_the_true_sum_of_squares_is_never_below_the_nominal_one(lift):
    episode, kin, contacts, sol = lift
    tr = episode.truth
    free = (sol.env_active == 0) & (np.linalg.norm(tr.env_force, axis=1) == 0) & contacts.active.any(axis=1)
    sos_true = np.einsum("tki,tki->t", tr.contact_force, tr.contact_force)
    assert free.sum() >= 10
    assert np.all(sos_true[free] >= sol.sum_of_squares[free] - 1e-6 * (1 + sos_true[free]))
    s = score_forces(sol, tr, kin.rot)
    assert s["sos_true_not_below_nominal_frac"] == 1.0 and s["solver_failures"] == 0
    assert s["nominal_normal_err_n_mean"] < 0  # people over-grip (the paper's Fig. 5)


def test_the_decomposition_recovers_the_true_normal_forces(lift):
    """Tactile readings of the truth are consistent with the motion: eq. 9 fits them almost exactly."""
    episode, kin, contacts, sol = lift
    tr = episode.truth
    measured = np.where(contacts.active, np.einsum("tki,tki->tk", tr.contact_force, tr.contact_normal), np.nan)
    dec = decompose_forces(kin, contacts, episode.object_model, measured, gravity=tr.gravity)
    # Measured on this 2.5 s lift: 75 of 76 frames optimal, the other (0.43 s: the thumb alone,
    # sliding, while the hand closes) held by static friction; on the frames without a sliding
    # contact (74 of 76) internal wrench and normal-force misfit within the gates (1e-9, 5e-3 N; the
    # frame after, 0.47 s, with the thumb still sliding and the box on the table, misfits by 0.05 N).
    ok = (dec.status == FrameStatus.OPTIMAL) & ~tr.contact_sliding.any(axis=1)
    assert np.isin(dec.status, (FrameStatus.OPTIMAL, FrameStatus.STATIC_FRICTION)).all() and ok.mean() >= 0.95
    assert np.abs(dec.internal_wrench[ok]).max() < 1e-9
    assert np.abs((dec.normal_force - np.nan_to_num(measured))[contacts.active & ok[:, None]]).max() < 5e-3


def _estimate(episode, contacts, kinematics, oracle=()):
    """The method's estimate as the tracking stage leaves it in the run (poses observed, no learned forces)."""
    from benchmark.world.motion import observed_poses
    from fsv.method import Estimate, TrackOutput

    nominal = nominal_forces(kinematics, contacts, episode.object_model, gravity=episode.truth.gravity)
    labels = {"tracker": "a tracker", "differentiator": "algebraic differentiation", "forces": "nominal forces (eq. 4-6)",
              "internal": "none"}
    labels.update({("differentiator" if o == "kinematics" else "contacts"): "oracle" for o in oracle})
    return Estimate(tracking=TrackOutput(box=observed_poses(episode), contacts=contacts), contacts=contacts,
                    kinematics=kinematics, nominal=nominal, forces=None, internal_pred=None, oracle=tuple(oracle),
                    timing_s={}, labels=labels)


def _run(episode, estimate, out=None):
    """The forces stage on its own: its blocks as a dict, its lines; its files and pictures drawn into ``out``."""
    import argparse

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    record = Run(scenario=episode.scenario, out=out, method_spec=None, episode=episode, estimate=estimate)
    result = STAGE(record, parser.parse_args([], argparse.Namespace(no_pictures=False)))  # the command's option: drawn
    complete(result, out)
    return types.SimpleNamespace(summary=dict(result.blocks), lines=list(result.lines))


def test_the_forces_stage_writes_its_block_and_plot(lift, tmp_path):
    episode = lift[0]
    est = _estimate(episode, contacts_from_truth(episode.truth), oracle_kinematics(episode.truth),
                    oracle=("contacts", "kinematics"))
    run = _run(episode, est, tmp_path)
    block = run.summary["forces"]
    for key in ("net_force_err_n_rms", "net_torque_err_nm_rms", "nominal_normal_err_n_mean", "solver_failures"):
        assert key in block
    assert block["contacts"].startswith("oracle") and "contacts" in block["oracle"]
    # the oracle kinematics are instantaneous: they explain the instantaneous forces, not the frame means,
    # which leave out the grasp onset's transients (measured 1.1e-11 N against 0.064 N RMS on this lift,
    # whose digits close until they touch)
    assert block["net_force_err_n_rms_instant"] < 1e-6 and "sensitivity_tracker" not in block
    assert 1000 * block["net_force_err_n_rms_instant"] < block["net_force_err_n_rms"] < 1.0
    assert_figure(tmp_path / "forces_fig5.png", min_height=800, colours={"thumb (C0)": (31, 119, 180), "index (C1)": (255, 127, 14)})
    assert "ORACLE" in run.lines[0]
    json.dumps(block)  # summary.json must be able to hold it


def test_estimate_inputs_are_the_estimates_with_its_labels(lift):
    episode = lift[0]
    est = _estimate(episode, contacts_from_truth(episode.truth), oracle_kinematics(episode.truth), oracle=("kinematics",))
    kin, contacts, labels = estimate_inputs(est)
    assert kin is est.kinematics and contacts is est.contacts
    assert labels == {"kinematics": "oracle (truth)", "contacts": "vision (a tracker)", "oracle": ["kinematics"]}
    est = _estimate(episode, contacts_from_truth(episode.truth), oracle_kinematics(episode.truth), oracle=("contacts",))
    labels = estimate_inputs(est)[2]
    assert labels["kinematics"] == "algebraic differentiation on tracked poses" and labels["contacts"] == "oracle (truth)"


def test_with_the_tracker_the_stage_also_scores_its_contacts(lift, tmp_path):
    from benchmark.world.contact_error import vision_like_contacts

    episode = lift[0]
    tracked = vision_like_contacts(contacts_from_truth(episode.truth), episode.object_model,
                                   np.random.default_rng(1), mean_m=0.0, std_m=0.01)
    run = _run(episode, _estimate(episode, tracked, oracle_kinematics(episode.truth), oracle=("kinematics",)), tmp_path)
    block = run.summary["forces"]
    assert block["contacts"] == "vision (a tracker)" and block["oracle"] == ["kinematics"]
    assert block["sensitivity_tracker"]["pairs"] > 0
    assert block["sensitivity_tracker"]["force_diff_n_rms"] > block["sensitivity"]["force_diff_n_rms"]  # 10 mm vs 6 mm
    assert "with the tracker's contacts" in run.lines[0]
