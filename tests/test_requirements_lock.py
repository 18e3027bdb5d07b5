"""requirements.lock pins every package of the test install, within pyproject.toml's ranges."""

import pathlib
import re

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = pathlib.Path(__file__).resolve().parents[1]
TEST_COMMAND = ("python3 -m venv .venv && .venv/bin/pip install -q -c requirements.lock torch==2.13.0 -e '.[test]' "
                "&& .venv/bin/python -m pytest -q -n auto")


def _toml(path):
    try:
        import tomllib
    except ImportError:  # Python 3.10
        tomllib = pytest.importorskip("tomli")
    return tomllib.loads(path.read_text())


def lock() -> dict:
    pins = {}
    for n, line in enumerate((ROOT / "requirements.lock").read_text().splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        assert re.fullmatch(r"[a-z0-9][a-z0-9.-]*==[0-9][0-9A-Za-z.+!-]*", line), f"line {n}: {line!r}"
        name, version = line.split("==")
        assert name == canonicalize_name(name), f"line {n}: {name!r} is not in canonical form"
        assert name not in pins, f"line {n}: {name} pinned twice"
        pins[name] = Version(version)
    return pins


def test_every_line_is_an_exact_pin_and_the_header_says_how_to_regenerate():
    text = (ROOT / "requirements.lock").read_text()
    assert text.startswith("# requirements.lock") and "pip freeze" in text
    pins = lock()
    assert len(pins) > 30
    assert pins["torch"] == Version("2.13.0") and not pins["torch"].local
    assert "fsv-bench" not in pins


def test_every_dependency_and_test_extra_is_pinned_within_its_range():
    project = _toml(ROOT / "pyproject.toml")["project"]
    pins = lock()
    required = project["dependencies"] + project["optional-dependencies"]["test"]
    assert any(Requirement(r).name == "threadpoolctl" for r in required)
    for spec in required:
        req = Requirement(spec)
        name = canonicalize_name(req.name)
        assert name in pins, f"{spec} is not pinned"
        assert req.specifier.contains(pins[name], prereleases=True), f"{name}=={pins[name]} is outside {spec}"
    for extra in project["optional-dependencies"].values():  # pinned extras (e.g. ray) respect their ranges too
        for spec in extra:
            req = Requirement(spec)
            if canonicalize_name(req.name) in pins:
                assert req.specifier.contains(pins[canonicalize_name(req.name)], prereleases=True), spec
    assert "ray" in pins


def test_the_readme_and_ci_install_with_the_lock():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    assert TEST_COMMAND in readme
    assert [line for line in ci.splitlines() if "pip install" in line] == [TEST_COMMAND]
    assert ".venv/bin/pip install -c requirements.lock torch==2.13.0 -e . && .venv/bin/fsv-bench" in readme
