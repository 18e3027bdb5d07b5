"""tests/conftest.py: the Ray cluster of the tests that use it is shut down after the last of them."""

import sys
import types

import conftest


class _FakeRay(types.ModuleType):
    def __init__(self):
        super().__init__("ray")
        self.shutdowns = 0

    def shutdown(self):
        self.shutdowns += 1


def _item(*fixtures):
    return types.SimpleNamespace(fixturenames=list(fixtures))


def test_the_cluster_stops_after_the_last_of_its_tests_and_not_before(monkeypatch):
    ray = _FakeRay()
    monkeypatch.setitem(sys.modules, "ray", ray)
    monkeypatch.setattr(conftest, "_RAY_ADDRESS", {"gcs": "127.0.0.1:1"})
    conftest.pytest_runtest_teardown(_item("ray_cluster", "tmp_path"), _item("ray_cluster"))
    conftest.pytest_runtest_teardown(_item("tmp_path"), _item("ray_cluster"))  # a test without it: not its business
    assert ray.shutdowns == 0 and conftest._RAY_ADDRESS
    conftest.pytest_runtest_teardown(_item("ray_cluster"), _item("tmp_path"))
    assert ray.shutdowns == 1 and not conftest._RAY_ADDRESS
    conftest._RAY_ADDRESS["gcs"] = "127.0.0.1:1"
    conftest.pytest_runtest_teardown(_item("ray_cluster"), None)  # the worker's last test
    assert ray.shutdowns == 2


def test_a_cluster_this_process_did_not_start_is_left_alone(monkeypatch):
    ray = _FakeRay()
    monkeypatch.setitem(sys.modules, "ray", ray)
    monkeypatch.setattr(conftest, "_RAY_ADDRESS", {})
    conftest.stop_ray()
    assert ray.shutdowns == 0
