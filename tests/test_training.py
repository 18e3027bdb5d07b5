"""fsv-bench train: trains on a generated dataset, saves a loadable model, checks --folds before work."""

from benchmark.commands.cli import main
from fsv.learn import load


def test_train_writes_a_model_that_predicts_on_its_data(learn_oracle_dataset, tmp_path, capsys):
    _, folder, _ = learn_oracle_dataset
    out = tmp_path / "model.npz"
    code = main(["train", "--data", str(folder), "--out", str(out), "--folds", "2", "--epochs", "60", "--members", "1"])
    assert code == 0, capsys.readouterr().err
    text = capsys.readouterr().out
    assert "2-fold CV" in text and "from 2 episodes" in text
    model = load(out)
    assert model.metadata["episodes"] == 2 and model.metadata["cross_validation"]["folds"] == 2
    assert model.metadata["dataset"]["contacts"] == "oracle"
    assert model.config.epochs == 60 and model.config.members == 1


def test_train_refuses_more_folds_than_episodes_before_training(learn_oracle_dataset, tmp_path, capsys):
    _, folder, _ = learn_oracle_dataset
    out = tmp_path / "model.npz"
    assert main(["train", "--data", str(folder), "--out", str(out)]) == 2  # default 5 folds, 2 episodes
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--folds 5 needs between 2 and the dataset's 2 episodes" in err
    assert not out.exists()


def test_train_refuses_dev_and_test_people_naming_them_and_what_is_accepted():
    import pytest

    from benchmark.paper.training import check_training_people
    from fsv.errors import InputError

    check_training_people([0, 4, 1000, 5123])  # the named cohort and the training split
    with pytest.raises(InputError, match=r"the dataset holds test people \(500\.\.\.\), who never train a model; "
                                         r"accepted: training people \(1000 and above"):
        check_training_people([1000, 500, 999])
    with pytest.raises(InputError, match=r"dev people \(123\)"):
        check_training_people([123])
