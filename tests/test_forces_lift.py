"""End-to-end gate on a simulated lift: oracle contacts and kinematics, nominal forces against the truth."""

import json
import types

import numpy as np
import pytest

from benchmark.contact_error import contacts_from_truth
from benchmark.motion import oracle_kinematics
from benchmark.score_forces import add_arguments, run_stage, score_forces, true_net_wrench
from fsv.forces import FrameStatus, decompose_forces, nominal_forces, to_world_frame
from pictures import assert_figure


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
    assert np.all(sol.status == FrameStatus.OPTIMAL)
    err = to_world_frame(kin.rot, sol.net_wrench) - true_net_wrench(tr)
    assert np.sqrt(np.mean(np.sum(err[:, :3] ** 2, axis=1))) < 0.05
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
    # Measured on this 2.5 s lift: all 76 frames optimal, internal wrench 3e-15, largest normal-force
    # misfit 1.8e-4 N (gates: every frame, 1e-9, 5e-3 N).
    assert np.all(dec.status == FrameStatus.OPTIMAL), np.flatnonzero(dec.status != FrameStatus.OPTIMAL)
    assert np.abs(dec.internal_wrench).max() < 1e-9
    assert np.abs((dec.normal_force - np.nan_to_num(measured))[contacts.active]).max() < 5e-3


def test_the_forces_stage_writes_its_block_and_plot(lift, tmp_path):
    episode = lift[0]
    import argparse

    parser = argparse.ArgumentParser()
    add_arguments(parser)
    run = types.SimpleNamespace(args=parser.parse_args(["--contacts", "oracle"]), episode=episode, out=tmp_path,
                                summary={}, lines=[])
    run_stage(run)
    block = run.summary["forces"]
    for key in ("net_force_err_n_rms", "net_torque_err_nm_rms", "nominal_normal_err_n_mean", "solver_failures"):
        assert key in block
    assert block["contacts"].startswith("oracle") and "contacts" in block["oracle"]
    assert block["net_force_err_n_rms"] < 0.05
    assert_figure(tmp_path / "forces_fig5.png", min_height=800, colours={"thumb (C0)": (31, 119, 180), "index (C1)": (255, 127, 14)})
    assert "ORACLE" in run.lines[0]
    json.dumps(block)  # summary.json must be able to hold it


def test_stage_inputs_follow_the_flags_and_label_oracles(lift):
    import argparse

    from benchmark.score_forces import stage_inputs

    episode = lift[0]
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    parser.add_argument("--kinematics", default="algebraic")
    run = types.SimpleNamespace(args=parser.parse_args([]), episode=episode, out=None, summary={}, lines=[])
    kin, contacts, labels = stage_inputs(run)
    assert labels["oracle"] == [] and kin.method == "algebraic" and labels["contacts"].startswith("vision model")
    assert labels["kinematics"] == "algebraic on tracker-like poses"
    moved = np.linalg.norm(contacts.point - episode.truth.contact_point, axis=-1)[contacts.active]
    assert 1e-3 < np.median(moved) < 2e-2  # the paper's contact error, a few millimetres
    run.args = parser.parse_args(["--contacts", "oracle", "--kinematics", "oracle"])
    kin, contacts, labels = stage_inputs(run)
    assert labels["oracle"] == ["kinematics", "contacts"]
    assert np.array_equal(contacts.point[contacts.active], episode.truth.contact_point[contacts.active])
    from benchmark.motion import observed_poses

    run.tracking = types.SimpleNamespace(contacts=contacts_from_truth(episode.truth), box=observed_poses(episode))
    run.args = parser.parse_args([])
    labels = stage_inputs(run)[2]
    assert labels["contacts"] == "vision (tracker)" and labels["kinematics"] == "algebraic on tracked poses"


def test_with_the_tracker_the_stage_also_scores_its_contacts(lift, tmp_path):
    import argparse

    from benchmark.contact_error import vision_like_contacts
    from benchmark.motion import observed_poses

    episode = lift[0]
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    tracked = vision_like_contacts(contacts_from_truth(episode.truth), episode.object_model,
                                   np.random.default_rng(1), mean_m=0.0, std_m=0.01)
    run = types.SimpleNamespace(args=parser.parse_args([]), episode=episode, out=tmp_path, summary={}, lines=[],
                                tracking=types.SimpleNamespace(contacts=tracked, box=observed_poses(episode)))
    run_stage(run)
    block = run.summary["forces"]
    assert block["contacts"] == "vision (tracker)" and block["oracle"] == ["kinematics"]
    assert block["sensitivity_tracker"]["pairs"] > 0
    assert block["sensitivity_tracker"]["force_diff_n_rms"] > block["sensitivity"]["force_diff_n_rms"]  # 10 mm vs 6 mm
    assert "with the tracker's contacts" in run.lines[0]
