"""benchmark.method: a method named by text, loaded by module:attribute, checked before any work."""

import pathlib

import pytest

from benchmark.method import MethodSpec, method_label
from benchmark.method.load import load_object

HERE = pathlib.Path(__file__).parent


def test_a_class_is_instantiated_and_a_function_used_as_it_is():
    assert type(load_object("external_stages:FrozenTracker", "--tracker")).__name__ == "FrozenTracker"
    assert load_object("external_stages:half_the_frames", "--differentiator").__name__ == "half_the_frames"
    assert type(load_object(f"{HERE / 'external_stages.py'}:FrozenTracker", "--tracker")).__name__ == "FrozenTracker"


@pytest.mark.parametrize("spec, needle", [
    ("external_stages", "--tracker 'external_stages': expected module:attribute"),
    ("no_such_module_x:Thing", "cannot import no_such_module_x: ModuleNotFoundError"),
    ("external_stages:Missing", "external_stages has no attribute 'Missing'"),
    ("external_stages:NOT_CALLABLE", "int is not callable"),
    ("missing/file.py:X", "no file missing/file.py"),
])
def test_bad_specs_fail_with_one_line(spec, needle):
    with pytest.raises(ValueError) as e:
        load_object(spec, "--tracker")
    assert needle in str(e.value) and "\n" not in str(e.value)


def test_labels_name_replaced_stages_and_oracles():
    spec = MethodSpec(tracker="external_stages:FrozenTracker", differentiator="central", oracle=("contacts",))
    label = method_label(spec)
    assert "tracker: frozen tracker (a broken example)" in label and "differentiator: central differentiation" in label
    assert "contacts: oracle" in label
    user = MethodSpec(differentiator="external_stages:half_the_frames")
    assert "differentiator: external_stages:half_the_frames" in method_label(user)


@pytest.mark.parametrize("kw, needle", [
    (dict(oracle=("forces",)), "--oracle 'forces': accepted: contacts, kinematics"),
    (dict(method="a:b", tracker="c:d"), "--method replaces every stage"),
])
def test_inconsistent_specs_are_refused(kw, needle):
    with pytest.raises(ValueError, match=needle):
        MethodSpec(**kw)


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


def test_the_direct_method_without_its_model_is_refused_before_any_work(tmp_path, monkeypatch, capsys):
    """One line naming the missing file and the command that makes it, exit 2, nothing written."""
    import benchmark.method.spec as spec_module
    from benchmark.commands.cli import main

    monkeypatch.setattr(spec_module, "default_direct_path", lambda: str(tmp_path / "absent.npz"))
    spec_module._build.cache_clear()  # a method built from the shipped model by an earlier test would be reused
    out = tmp_path / "run"
    assert main(["--method", "direct", "--out", str(out)]) == 2
    err = _one_error_line(capsys)
    assert "no model at fsv/data/direct_forces.npz" in err and "fsv-bench train-direct --data DIR" in err
    assert "--rows all" in err and "--direct-model FILE" in err
    assert main(["--method", "direct", "--direct-model", str(tmp_path / "missing.npz"), "--out", str(out)]) == 2
    assert f"no model at {tmp_path / 'missing.npz'}" in _one_error_line(capsys)
    (tmp_path / "bad.npz").write_text("not a model")
    assert main(["--method", "direct", "--direct-model", str(tmp_path / "bad.npz"), "--out", str(out)]) == 2
    assert "is not a readable direct force model" in _one_error_line(capsys)
    assert main(["--direct-model", str(tmp_path / "bad.npz"), "--out", str(out)]) == 2
    assert "--direct-model is the model of --method direct" in _one_error_line(capsys)
    assert main(["--method", "direct", "--internal", "none", "--out", str(out)]) == 2
    assert "--method replaces every stage" in _one_error_line(capsys)
    assert not out.exists()


def test_the_direct_methods_label_names_its_network_and_its_oracles(direct_dataset):
    model = str(direct_dataset[1] / "model.npz")
    label = method_label(MethodSpec(method="direct", direct_model=model, oracle=("contacts", "kinematics")))
    assert label.startswith("direct (tracker: reference tracker; differentiator: oracle; forces: direct network")
    assert f"model {model}, 1,621 parameters" in label and "internal: none; contacts: oracle" in label
