import json

import numpy as np
import pytest

from benchmark.paper.dataset import finger_names_of, load_dataset, training_set
from benchmark.paper.table2 import PAPER, Table2Protocol, evaluate, markdown, object_models, score, write
from fsv.learn import LearnConfig


class ExactInternal:
    """A stand-in for the networks that predicts the decomposition's own internal forces."""

    def __init__(self, df):
        self.finger_names = finger_names_of(df)
        self.internal = training_set(df).internal

    def predict(self, x, active):
        return None, None, self.internal


def test_rows_follow_the_paper():
    rows = Table2Protocol(user=2, grasp=0, mass=1, other_user=3, other_grasp=1, heavier_mass=4).rows()
    assert rows == [dict(user=2, mass=1, grasp=0), dict(user=3, mass=1, grasp=0), dict(user=2, mass=4, grasp=0),
                    dict(user=2, mass=1, grasp=1), dict(user=3, mass=4, grasp=1)]
    assert [p[5] for p in PAPER] == [9.71, 10.3, 10.4, 10.9, 9.94]


def test_reconstruction_from_exact_internal_forces_gives_back_the_truth(learn_oracle_dataset):
    _, out, _ = learn_oracle_dataset
    df = load_dataset(out)
    ev = evaluate(ExactInternal(df), df, object_models(out))
    assert ev["residual_rel"] <= 1e-6  # the reconstructed forces explain the motion
    air = (df["pos_z"] > 0.035).to_numpy()
    errors_air = evaluate(ExactInternal(df[air].reset_index(drop=True)), df[air].reset_index(drop=True),
                          object_models(out))["errors"]
    assert errors_air.size > 50 and np.max(errors_air) < 0.5  # eq. 14 with eq. 9's internals = tactile forces


def test_score_writes_the_table_and_the_figure(learn_oracle_dataset, tmp_path):
    _, out, _ = learn_oracle_dataset
    same = Table2Protocol(user=0, grasp=0, mass=0, other_user=0, other_grasp=0, heavier_mass=0,
                          train_seeds=(0,), test_seeds=(1,))
    result = score(out, same, LearnConfig(epochs=200))
    rows = result["rows"]
    assert len(rows) == 5 and result["samples"]["partial"] == result["samples"]["full"]
    # one combination only: partial and full training see the same data and give the same errors
    assert rows[0]["partial_avg"] == pytest.approx(rows[0]["full_avg"]) == pytest.approx(rows[0]["same_user_avg"])
    assert 0 < rows[0]["full_avg"] < 25 and rows[0]["full_residual_rel"] <= 1e-6
    write(result, tmp_path)
    assert {p.name for p in tmp_path.iterdir()} == {"table2.md", "table2.csv", "table2.json", "fig6.png"}
    assert "| ○ | ○ | ○ |" in markdown(result)
    written = json.loads((tmp_path / "table2.json").read_text())
    assert written["sources"] == {"kinematics": "oracle", "contacts": "oracle"}
    from fsv.provenance import provenance

    assert written["provenance"]["fsv_bench"] == provenance()["fsv_bench"]
    assert written["provenance"]["dependencies"]["torch"] and written["provenance"]["cpu"] == provenance()["cpu"]


def test_user_blind_prediction_averages_the_two_users_frame_by_frame():
    import pandas as pd

    from benchmark.paper.table2 import user_blind

    def rows(user, frames, thumb, index, index_active):
        return pd.DataFrame(dict(task="lift", user=user, grasp=0, mass=1, seed=3, frame=frames,
                                 active_thumb=True, active_index=index_active, f_int_thumb=thumb, f_int_index=index))

    own = rows(0, [4, 5, 6], [10.0, 12.0, 14.0], [6.0, 6.0, 7.0], [True, True, True])
    partner = rows(1, [5, 6, 7], [20.0, 18.0, 0.0], [8.0, 0.0, 0.0], [True, False, False])
    kept, pred = user_blind(own, partner)
    assert list(kept["frame"]) == [5, 6] and list(kept["user"]) == [0, 0]  # frames both users have
    # thumb averaged; the index only where the partner's index touches too (frame 6: own value)
    np.testing.assert_allclose(pred, [[16.0, 7.0], [16.0, 7.0]])


@pytest.mark.parametrize("users", ["0,0", "4", "0,1,4"])
def test_users_option_takes_two_different_users(tmp_path, capsys, users):
    from benchmark.commands.cli import main

    code = main(["table2", "--data", str(tmp_path), "--out", str(tmp_path / "out"), "--users", users])
    err = capsys.readouterr().err
    assert code == 2 and f"--users {users!r}: expected two different user indices" in err
    assert not (tmp_path / "out").exists()


def test_object_models_come_only_from_checked_files(learn_oracle_dataset, tmp_path):
    import shutil

    from benchmark.errors import DatasetFileError

    _, out, _ = learn_oracle_dataset
    shutil.copytree(out, tmp_path / "d")
    path = tmp_path / "d" / "episodes" / "lift-u0-g0-m0-s0.parquet"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(DatasetFileError, match=str(path)):
        object_models(tmp_path / "d")
