"""Fingerprints of the source behind a result: code counts, comments and docstrings do not."""

from benchmark.fingerprint import RESULTS_MODULES, WORLD_MODULES, results_fingerprint, world_fingerprint


def test_results_fingerprint_ignores_docstrings_and_comments_not_code(tmp_path):
    for d in ("fsv/data", "sim_assets", "benchmark/world/tasks", "benchmark/scores", "benchmark/suites",
              "benchmark/world", "benchmark/camera", "benchmark/paper", "benchmark/method"):
        (tmp_path / d).mkdir(parents=True, exist_ok=True)
    for m in RESULTS_MODULES:
        (tmp_path / "benchmark" / f"{m}.py").write_text("")
    mod = tmp_path / "fsv" / "track.py"
    mod.write_text('def f(x):\n    """Doc."""\n    return x + 1  # add one\n')
    (tmp_path / "sim_assets" / "box.yaml").write_text("size: 1\n")
    base = results_fingerprint(tmp_path)
    mod.write_text('def f(x):\n    """Other words."""\n    # reworded\n    return x + 1\n')
    assert results_fingerprint(tmp_path) == base
    mod.write_text('def f(x):\n    return x + 2\n')
    assert results_fingerprint(tmp_path) != base
    mod.write_text('def f(x):\n    return x + 1\n')
    assert results_fingerprint(tmp_path) == base
    (tmp_path / "sim_assets" / "box.yaml").write_text("size: 2\n")
    assert results_fingerprint(tmp_path) != base


def test_the_world_fingerprint_ignores_the_method_but_not_the_world(tmp_path):
    for d in ("fsv", "sim_assets", "benchmark/world/tasks", "benchmark/camera", "benchmark/paper", "benchmark/method"):
        (tmp_path / d).mkdir(parents=True, exist_ok=True)
    for m in RESULTS_MODULES:
        (tmp_path / "benchmark" / f"{m}.py").write_text("x = 1\n")
    base = world_fingerprint(tmp_path)
    (tmp_path / "fsv" / "track.py").write_text("y = 2\n")
    (tmp_path / "benchmark" / "paper" / "table1.py").write_text("x = 2\n")
    assert world_fingerprint(tmp_path) == base and "paper/table1" not in WORLD_MODULES
    (tmp_path / "benchmark" / "world" / "simulate.py").write_text("x = 2\n")
    assert world_fingerprint(tmp_path) != base
