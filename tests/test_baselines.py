"""The trivial baselines (fsv.method.baselines): what each does, and that each fails its stage's gates on smoke."""

import numpy as np
import pytest

from fsv import Poses
from fsv.method.baselines import (
    BASELINE_STAGE,
    BASELINES,
    GripLineForces,
    ZeroKinematics,
    at_rest,
    first_frame_contacts,
)

STAGE_GATES = {"tracker": ("box_pos_err_mm", "contact_err_mm_std", "contact_recall", "contact_precision"),
               "differentiator": ("acc_err_rms",), "forces": ("net_force_err_n_rms", "least_violation_frac"),
               "internal": ("learned_rel_err_pct",)}
"""The gates each stage stands for."""


def test_zero_kinematics_is_a_box_at_rest_at_the_given_poses():
    t = np.arange(4) / 30.0
    rot = np.repeat(np.eye(3)[None], 4, 0)
    poses = Poses(t=t, pos=np.arange(12.0).reshape(4, 3), rot=rot)
    kin = ZeroKinematics()(poses)
    np.testing.assert_array_equal(kin.pos, poses.pos)
    assert not kin.vel.any() and not kin.acc.any() and not kin.omega.any() and not kin.alpha.any()
    assert kin.valid.all() and not at_rest(kin).acc.any()


def test_first_frame_contacts_find_the_pads_on_a_face():
    half = np.array([0.0855, 0.0555, 0.03])
    radius = np.array([0.01, 0.01, 0.01])
    tips = np.array([[0.02, -0.0555 - 0.01 - 0.002, 0.0],  # 2 mm off the -y face: touches
                     [0.0, 0.0555 + 0.01 + 0.05, 0.0],      # 5 cm off +y: does not
                     [0.2, 0.0555 + 0.01, 0.0]])             # beside the face: does not
    pos, rot = np.array([1.0, 2.0, 0.03]), np.eye(3)
    active, point, normal = first_frame_contacts(tips + pos, radius, half, pos, rot, 0.01)
    assert active.tolist() == [True, False, False]
    np.testing.assert_allclose(point[0], [0.02, -0.0555, 0.0])
    np.testing.assert_allclose(normal[0], [0.0, 1.0, 0.0])  # into the box


def test_the_grip_line_shares_its_amount_equally(lift_episode):
    from benchmark.world.contact_error import contacts_from_truth
    from benchmark.world.motion import oracle_kinematics
    from fsv.grip import GripCalibration

    ep = lift_episode[0]
    kin, con = oracle_kinematics(ep.truth), contacts_from_truth(ep.truth)
    _, predicted = GripLineForces()(kin, con, ep.object_model, ep.truth.gravity,
                                    grip=GripCalibration(baseline_n=6.0, gain=1.5, samples=100))
    i = int(np.flatnonzero(con.active.sum(axis=1) == 4)[0])
    shares = predicted[i][con.active[i]]
    np.testing.assert_allclose(shares, shares[0])
    assert np.linalg.norm(shares) >= 6.0  # the baseline grip at least
    _, none = GripLineForces()(kin, con, ep.object_model, ep.truth.gravity)
    assert not none.any()  # no calibration: no internal force


@pytest.fixture(scope="module")
def smoke_cache(tmp_path_factory):
    """One episode cache for this module's evaluations of ``smoke``: its episodes rendered once."""
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(scope="module")
def smoke_with_baselines(smoke_cache):
    from benchmark.method import MethodSpec
    from benchmark.suites import SUITES
    from benchmark.suites.evaluate import evaluate_many

    specs = [MethodSpec()] + [MethodSpec(method=name) for name in BASELINES]
    return dict(zip(["reference", *BASELINES], evaluate_many(SUITES["smoke"], specs, progress=False,
                                                              cache=smoke_cache)))


def test_every_baseline_fails_the_smoke_gates_of_its_stage_and_the_reference_passes(smoke_with_baselines):
    """Measured (smoke v4, medians of four episodes): the static box 127 mm and recall 0; zero
    kinematics 0.73 m/s^2 (gate 0.5); gravity alone 0.485 N (gate 0.3); no internal forces 84.5 %
    over every contact frame; the grip line alone, blind (the default protocol), is no internal
    force at all. Smoke v5 (learned-force gate 60 %): the reference 1.18 mm, 0.38 m/s^2, 0.18 N,
    47.9 % blind."""
    assert smoke_with_baselines["reference"]["verdict"] == "pass"
    for name, stage in BASELINE_STAGE.items():
        failed = [g["name"] for g in smoke_with_baselines[name]["gates"] if not g["passed"]]
        assert any(metric in g for g in failed for metric in STAGE_GATES[stage]), (name, failed)


def test_every_baseline_fails_the_standard_gates_of_its_stage_in_the_committed_results():
    """`standard` is too long for the tests: its committed scores (``fsv-bench reproduce``) are
    checked against the registered gates. Measured (standard v6, the test split, lab knowledge, the
    skin): the static box 137 mm, zero kinematics 0.582 m/s^2 (gate 0.45), gravity alone 0.472 N
    (gate 0.3), no internal forces 81.5 % and the grip line alone (calibrated) 39.3 % (gate 15); the
    reference holds every gate but the learned forces' (28.7 % [25.2, 31.6] blind, against 15, set
    before measuring), and so does it with exact knowledge (28.5 %); the mean least-violation frames
    are 0.37 % and 0.61 % (gate 1 %; v5's exact knowledge had lost one episode's hand: 1.48 %)."""
    import json
    import pathlib

    from benchmark.scores.verdict import check_gates
    from benchmark.suites import SUITES

    suite = SUITES["standard"]
    root = pathlib.Path(__file__).resolve().parents[1] / "results" / "standard"

    def failed(folder):
        scores = json.loads((root / folder / "scores.json").read_text())
        assert scores["suite"]["version"] == suite.version and scores["n"] == len(suite.scenarios)
        return [r.name for r in check_gates(suite.gates, scores["aggregate"]) if not r.passed]

    assert set(failed("reference")) == {"median learned_rel_err_pct <= 15"}
    assert set(failed("exact-knowledge")) == {"median learned_rel_err_pct <= 15"}
    for name, stage in BASELINE_STAGE.items():
        fails = failed(f"baseline-{name}")
        assert any(metric in g for g in fails for metric in STAGE_GATES[stage]), (name, fails)


def test_baselines_are_addressable_from_the_command_line(smoke_cache, tmp_path, capsys):
    from benchmark.commands.cli import main

    # the episodes rendered once (smoke_cache), the baselines' own rows (which track) left out: what is
    # tested is the name on the command line
    code = main(["eval", "--suite", "smoke", "--method", "static", "--quiet", "--no-baselines", "--out",
                 str(tmp_path / "o"), "--cache", str(smoke_cache)])
    out = capsys.readouterr()
    assert code == 1 and "FAIL  median box_pos_err_mm <= 8" in out.out
    assert "static box at its first-frame pose" in (tmp_path / "o" / "report.md").read_text()
