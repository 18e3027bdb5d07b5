"""Shared pytest fixtures."""

import gc
import json
import os
import pathlib
import shutil
import sys

import benchmark  # noqa: F401  (NumPy at its baseline instructions: set before NumPy is imported)
from benchmark.parallel import ONE_CORE_ENV


def one_worker_per_core() -> bool:
    """Whether this process is an xdist worker of as many as the machine has cores (``-n auto``)."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "0"))
    return bool(os.environ.get("PYTEST_XDIST_WORKER")) and workers >= (os.cpu_count() or 1)


def one_core_each() -> dict:
    """The settings of :data:`benchmark.parallel.ONE_CORE_ENV` that this test process takes, and what it
    starts: all of them (those the environment does not set) in an xdist worker of one per core
    (:func:`one_worker_per_core`), as a pool's worker takes them; none otherwise. Each library would
    otherwise start a thread per core in each worker: OpenBLAS's threads, waiting for work, took the other
    worker's core (measured on the whole suite, 2 workers on 2 cores: 8-9 s of 265 s of CPU, 4 s of its
    wall time)."""
    if not one_worker_per_core():
        return {}
    return {k: v for k, v in ONE_CORE_ENV.items() if k not in os.environ}


os.environ.update(one_core_each())  # before NumPy (and OpenBLAS) is loaded: they read it once

# Headless rendering on the CPU, set before any test module imports mujoco or pyrender.
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from kernel_python import KernelPythons  # noqa: E402

from benchmark import collector  # noqa: E402
from benchmark.atomic import write_text  # noqa: E402
from benchmark.interrupt import _release_multiprocessing  # noqa: E402

# Ray, when a test starts a local cluster, stays on the loopback interface (it otherwise swaps
# 127.0.0.1 for the machine's outward address); Ray reads this when it is imported.
os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] = "0"

# --- kinematics: an analytic box trajectory with exact derivatives -------------------


def _min_jerk(t, t0, dur):
    tau = np.clip((t - t0) / dur, 0, 1)
    inside = ((t >= t0) & (t <= t0 + dur)).astype(float)
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    ds = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / dur * inside
    dds = (60 * tau - 180 * tau**2 + 120 * tau**3) / dur**2 * inside
    return s, ds, dds


def make_analytic_truth(duration_s=4.0, fps=30.0, K=4):
    """A Truth whose box lifts, slides and turns on min-jerk profiles; derivatives are analytic.

    Orientation R(t) = Rz(a(t)) Rx(b(t)), so the body rate is (b', a' sin b, a' cos b). Contact
    fields are zero (no fingers touch).
    """
    from benchmark.world.truth import Truth
    from fsv.kinematics import so3
    from fsv.rotation import quat_to_rot

    t = np.arange(int(round(duration_s * fps))) / fps
    g = np.array([0, 0, -9.81])
    z, dz, ddz = _min_jerk(t, 0.5, 1.0)
    x, dx, ddx = _min_jerk(t, 1.5, 1.2)
    pos = np.stack([0.1 + 0.3 * x, 0 * t, 0.03 + 0.2 * z], 1)
    vel = np.stack([0.3 * dx, 0 * t, 0.2 * dz], 1)
    acc = np.stack([0.3 * ddx, 0 * t, 0.2 * ddz], 1)
    a, da, dda = (1.2 * v for v in _min_jerk(t, 1.0, 1.5))
    b, db, ddb = (-0.8 * v for v in _min_jerk(t, 2.0, 1.0))
    q = so3.quat_mul(so3.quat_exp(a[:, None] * [0, 0, 1]), so3.quat_exp(b[:, None] * [1, 0, 0]))
    R = quat_to_rot(q)
    w_body = np.stack([db, da * np.sin(b), da * np.cos(b)], 1)
    w_dot = np.stack([ddb, dda * np.sin(b) + da * np.cos(b) * db, dda * np.cos(b) - da * np.sin(b) * db], 1)
    T = t.size
    z3, zk = np.zeros((T, 3)), np.zeros((T, K, 3))
    return Truth(
        t=t, box_pos=pos, box_quat=q, box_vel=vel, box_omega=np.einsum("tij,tj->ti", R, w_body),
        box_acc=acc, box_alpha=np.einsum("tij,tj->ti", R, w_dot),
        imu_acc=np.einsum("tji,tj->ti", R, acc - g), imu_gyro=w_body,
        finger_names=np.array(["thumb", "index", "middle", "ring"][:K]),
        contact_active=np.zeros((T, K), bool), contact_sliding=np.zeros((T, K), bool),
        contact_point=zk, contact_normal=zk, contact_force=zk, env_force=z3, env_torque=z3,
        fingertip_pos=zk, hand_qpos=np.zeros((T, 12)), mass=0.3, inertia=np.eye(3) * 1e-3, gravity=g,
        net_wrench_mean=np.concatenate([0.3 * (acc - g), z3], axis=1),  # a smooth motion: its instantaneous force
    )


@pytest.fixture(scope="session")
def analytic_truth():
    return make_analytic_truth()


@pytest.fixture(scope="session")
def analytic_truth_factory():
    return make_analytic_truth


# --- world: short simulated episodes, simulated once per session ----------------------


@pytest.fixture(scope="session")
def tiny_episode_folder(tmp_path_factory):
    """A cache folder holding the tiny suite's episode, made once per test process (it is read, never
    written: :func:`tiny_cache` hands out copies)."""
    from tiny_suite import TINY

    from benchmark.suites.evaluate import cached_episode

    folder = tmp_path_factory.mktemp("tiny-cache")
    cached_episode(TINY, TINY.scenarios[0], folder)
    return folder


@pytest.fixture
def tiny_cache(tiny_episode_folder, tmp_path):
    """A cache that holds the tiny suite's episode, this test's own copy (``tmp_path / "tiny-cache"``):
    seventeen tests and fixtures evaluate, export, sweep or score the tiny suite, and each simulated, rendered and
    saved the same episode again (0.35 s of CPU a test). A test that checks what a cold cache does
    keeps an empty one of its own."""
    return shutil.copytree(tiny_episode_folder, tmp_path / "tiny-cache")


@pytest.fixture(scope="session")
def lift_episode():
    """A 2.5 s lift (user 0, grasp 0, mass 0, seed 0) with its simulation statistics."""
    from benchmark.world.scenario import Scenario
    from benchmark.world.simulate import run

    return run(Scenario(task="lift", duration_s=2.5))


@pytest.fixture(scope="session")
def episode_factory():
    """simulate(Scenario(**kw)), cached per keyword set for the session."""
    from benchmark.world.scenario import Scenario
    from benchmark.world.simulate import simulate

    cache = {}

    def make(**kw):
        key = tuple(sorted(kw.items()))
        if key not in cache:
            cache[key] = simulate(Scenario(**kw))
        return cache[key]

    return make


# --- render: the 2.5 s lift rendered once per session -----------------------------------


@pytest.fixture(scope="session")
def rendered_lift_episode(lift_episode):
    """``lift_episode`` with its noisy depth (σ = 0.01 m), calibration and labels."""
    from benchmark.camera.render import render

    return render(lift_episode[0])


# --- learning: a small dataset of short, simulated episodes -------------------------


@pytest.fixture(scope="session")
def learn_oracle_dataset(tmp_path_factory):
    """Two 3 s lift episodes (seeds 0, 1) with oracle kinematics, oracle contacts and noise-free
    tactile sensors: ``(spec, folder, manifest)``."""
    from benchmark.paper.dataset import DatasetSpec, generate

    out = tmp_path_factory.mktemp("learn-oracle")
    spec = DatasetSpec(tasks=("lift",), seeds=(0, 1), duration_s=3.0, kinematics="oracle", contacts="oracle",
                       tactile_noise_n=0.0)
    return spec, out, generate(spec, out, workers=1, progress=False)


@pytest.fixture(scope="session")
def direct_dataset(tmp_path_factory):
    """Two 2 s lift episodes (seeds 0, 1) with every frame (``rows="all"``), the truth's kinematics
    and contacts: ``(spec, folder)``; and ``folder / "model.npz"``, a tiny end-to-end network
    (hidden 16, 16; 3 epochs) trained on it by ``fsv-bench train-direct``."""
    from benchmark.commands.entry import run
    from benchmark.paper.dataset import DatasetSpec, generate

    out = tmp_path_factory.mktemp("direct")
    spec = DatasetSpec(tasks=("lift",), seeds=(0, 1), duration_s=2.0, kinematics="oracle", contacts="oracle",
                       rows="all")
    generate(spec, out / "data", workers=1, progress=False)
    assert run(["train-direct", "--data", str(out / "data"), "--out", str(out / "model.npz"), "--epochs", "3",
                "--hidden", "16,16", "--quiet"]) == 0
    return spec, out


# --- tracking: the whole method on the rendered 2.5 s lift, once per session ------------


@pytest.fixture(scope="session")
def tracked_lift(rendered_lift_episode):
    """``(episode, estimate)``: ``fsv.run_pipeline`` (tracking, kinematics, nominal forces) on
    ``rendered_lift_episode`` from the benchmark's seeded first-frame initialisation."""
    from benchmark.method.init import tracker_init
    from fsv import run_pipeline

    ep = rendered_lift_episode
    init = tracker_init(ep.truth, ep.scenario, ep.hand_model)
    est = run_pipeline(ep.depth, ep.calib, ep.object_model, ep.hand_model, init, gravity=ep.truth.gravity,
                       rng=ep.scenario.rng("tracker"))
    return ep, est


# --- the whole method on several default (10 s) lifts: accuracy gates as statistics over episodes ---

GATE_SEEDS = (1, 2, 3, 4)
"""Seeds of the multi-episode accuracy gates: the four seeds after seed 0, the one the tracker was tuned on."""


@pytest.fixture(scope="session")
def tracked_lifts():
    """``[(episode, estimate, tracking scores, force scores, learned-force block)]`` for
    ``fsv-bench --task lift --noise 0.01 --seed S`` with S in :data:`GATE_SEEDS`: the whole method
    from depth (tracker, algebraic kinematics, nominal forces, the shipped internal-force model with
    user 0's grip calibration)."""
    from benchmark.camera.render import render
    from benchmark.method.grip_file import user_grip
    from benchmark.method.init import tracker_init
    from benchmark.scores.forces import score_forces
    from benchmark.scores.learned import score_episode
    from benchmark.scores.tracking import score_tracking
    from benchmark.world.scenario import Scenario
    from benchmark.world.simulate import simulate
    from fsv import run_pipeline
    from fsv.learn import default_model

    out = []
    for seed in GATE_SEEDS:
        ep = render(simulate(Scenario(task="lift", seed=seed)))
        init = tracker_init(ep.truth, ep.scenario, ep.hand_model)
        est = run_pipeline(ep.depth, ep.calib, ep.object_model, ep.hand_model, init, gravity=ep.truth.gravity,
                           internal_model=default_model(), rng=ep.scenario.rng("tracker"),
                           grip=user_grip(ep.scenario.user))
        tracking = score_tracking(est.tracking, ep.truth)
        forces = score_forces(est.nominal, ep.truth, est.kinematics.rot)
        learned = score_episode(ep, est.forces, est.kinematics, est.contacts)
        out.append((ep, est, tracking, forces, learned))
    return out


# --- what an xdist worker is handed; one interpreter per OpenBLAS kernel --------------------

SHARED_ON_ONE_WORKER = {"kernel_python": "openblas-kernels", "ray_cluster": "ray"}
"""Fixtures that start costly processes, and the xdist group of the tests that use them."""


UNIT_SECONDS_FILE = pathlib.Path(__file__).parent / "unit_seconds.json"

UNIT_SECONDS = json.loads(UNIT_SECONDS_FILE.read_text())
"""Wall seconds of each unit that takes 1 s or more (tests/unit_seconds.json: a whole ``-n auto`` run on
the 2-core Xeon, load about 2, 2026-11-29, per-test times summed by unit; ``pytest -n auto
--write-unit-seconds`` writes it again from a run's reports): :func:`pytest_collection_modifyitems`
hands out the longest first. Only their order matters; a unit not listed counts :data:`UNLISTED_SECONDS`."""

_SEEN_SECONDS: dict = {}
"""Each unit's summed test durations in this run (setup, call, teardown), as the reports arrive."""


def pytest_addoption(parser):
    parser.addoption("--write-unit-seconds", action="store_true",
                     help="write tests/unit_seconds.json from this run's test durations, summed by xdist unit "
                          "(run the whole suite, with -n auto)")


def pytest_runtest_logreport(report):
    """Adds a report's duration to its unit's: with xdist the controller hears every worker's
    reports, whose ids end in ``@<unit>``."""
    unit = report_unit(report.nodeid)
    if unit is not None:
        _SEEN_SECONDS[unit] = _SEEN_SECONDS.get(unit, 0.0) + report.duration


def report_unit(nodeid: str) -> str | None:
    """A test id's unit, its ``@<unit>`` suffix (xdist's group; a parameter may hold "@" too), or None
    for an id without one (a run without xdist)."""
    test = nodeid.rpartition("::")[2]
    return test.rpartition("@")[2] if "@" in test else None


def unit_seconds_json(seconds: dict) -> str:
    """The content of tests/unit_seconds.json: each unit of 1 s or more, longest first, to 0.1 s."""
    kept = sorted(((u, round(s, 1)) for u, s in seconds.items() if s >= 1.0), key=lambda us: (-us[1], us[0]))
    return json.dumps(dict(kept), indent=1) + "\n"

UNLISTED_SECONDS = 0.5
"""What a unit not in :data:`UNIT_SECONDS` is taken to cost (each measured under 1 s)."""


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups into the test ids
def pytest_collection_modifyitems(config, items):
    """The unit xdist hands a worker (``--dist loadgroup``, pyproject's addopts): a test file, as
    ``--dist loadfile`` does, so that a module's fixtures are made once; but the tests of a fixture
    of :data:`SHARED_ON_ONE_WORKER`, whatever their file, are one unit, so that its processes start once.

    The units are handed out longest first (pyproject's ``--no-loadscope-reorder`` keeps this order;
    xdist's own puts the units with most tests first): a worker that is handed a long unit last
    leaves the other core idle while it runs (measured: the two workers ended 3-8 s apart when the
    Ray and OpenBLAS-kernel units, 11 and 36 s in 3 and 8 tests, were handed out among the last)."""
    units = {}
    for item in items:
        unit = worker_unit(item)
        item.add_marker(pytest.mark.xdist_group(unit))
        units.setdefault(unit, []).append(item)
    items[:] = [item for unit in sorted(units, key=lambda u: -unit_seconds(u)) for item in units[unit]]


def pytest_collection_finish(session):
    """What the test process has made so far (the imported libraries and test modules: most of its
    objects, alive to its end) is left out of the garbage collector's full collections from here on
    (``gc.freeze``), and the collector runs at the command's thresholds (:mod:`benchmark.collector`:
    on 50 000 new objects instead of 700). Each full collection scanned every object again, about
    0.25 s, 16-19 times a worker in a run of the suite: the collector took 4.6-4.8 s of a worker's
    CPU, 1.4-2.0 s now (measured with ``gc.callbacks``)."""
    gc.freeze()
    collector.tune()


def unit_seconds(unit: str) -> float:
    """How long a unit is taken to run: :data:`UNIT_SECONDS`, else :data:`UNLISTED_SECONDS`."""
    return UNIT_SECONDS.get(unit, UNLISTED_SECONDS)


def worker_unit(item) -> str:
    """The group of the first fixture of :data:`SHARED_ON_ONE_WORKER` the test uses, else the group its
    file names with ``pytestmark = pytest.mark.xdist_group(NAME)`` (files that share a cache of their
    process: ``tests/frames_data.py``'s rendered episodes), else its file's name."""
    shared = [g for f, g in SHARED_ON_ONE_WORKER.items() if f in getattr(item, "fixturenames", ())]
    if shared:
        return shared[0]
    named = item.get_closest_marker("xdist_group")
    return named.args[0] if named is not None and named.args else item.path.stem


@pytest.fixture(scope="session")
def kernel_python():
    """``kernel_python(code, *argv, env={"OPENBLAS_CORETYPE": kernel})``: what the script printed,
    run as ``python -c`` would in this session's interpreter for that environment
    (tests/kernel_python.py); it raises with the script's traceback."""
    pythons = KernelPythons()
    yield pythons.run
    pythons.close()


_RAY_ADDRESS = {}
"""``{"gcs": address}`` of the local Ray cluster :func:`ray_cluster` started, while it runs."""


@pytest.fixture
def ray_cluster():
    """A local Ray cluster owned by this test process (loopback only, tests/conftest.py): its address.

    Started by the first test that asks for it and shut down after the last of the tests that run
    one after another here (:func:`pytest_runtest_teardown`): an idle cluster's processes take about
    5 % of a core (measured: 1.4 s of CPU in 30 s), which the rest of the session would pay. One CPU:
    Ray starts one worker per CPU, each importing the project again, and the tests' jobs (one or
    two episodes) need no second (the three tests 11.7 -> 10.2 s, measured)."""
    assert os.environ["RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"] == "0"
    ray = pytest.importorskip("ray")
    if "gcs" not in _RAY_ADDRESS:
        _RAY_ADDRESS["gcs"] = ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False).address_info[
            "gcs_address"]
    return _RAY_ADDRESS["gcs"]


def pytest_runtest_teardown(item, nextitem):
    """Shuts the Ray cluster down once the next test does not use it (xdist hands a worker the
    cluster's tests as one unit: :func:`worker_unit`)."""
    if "ray_cluster" in item.fixturenames and (nextitem is None or "ray_cluster" not in nextitem.fixturenames):
        stop_ray()


def pytest_sessionfinish(session):
    """The Ray cluster, if a test left one running, ends with the session; with
    ``--write-unit-seconds``, the run's units' seconds are written (by the controller, which heard
    every report; not after a run that failed or was cut short)."""
    stop_ray()
    config = session.config
    if not config.getoption("write_unit_seconds") or hasattr(config, "workerinput"):
        return
    why = _why_not_whole(session)
    if why is None:
        write_text(UNIT_SECONDS_FILE, unit_seconds_json(_SEEN_SECONDS))
    else:
        config.pluginmanager.get_plugin("terminalreporter").write_line(  # after the progress line
            f"\n{UNIT_SECONDS_FILE.name} not written: {why} (it needs the whole suite, green, with -n auto)")


def _why_not_whole(session) -> str | None:
    """Why this run's seconds cannot replace tests/unit_seconds.json, or None when they can."""
    missing = sorted(set(UNIT_SECONDS) - set(_SEEN_SECONDS))
    if session.testsfailed:
        return f"{session.testsfailed} tests failed"
    if session.shouldstop:
        return "the run stopped early"
    if not _SEEN_SECONDS:
        return "no test ran under xdist (-n auto)"
    if missing:
        return f"units of the file did not run: {', '.join(missing[:5])}"
    return None


@pytest.hookimpl(tryfirst=True)
def pytest_unconfigure(config):
    """An xdist worker ends here, without the interpreter's finalisation: its results reached the
    controller at the session's end ("workerfinished"), and the controller waits for the process to
    exit (measured: 1.5-4 s for a worker of the whole suite, 0.3 s of them for unloading torch alone).
    First of the hooks: what the others do at a worker's end writes nowhere the controller reads
    (pytest's search for unraisable exceptions alone collects the worker's whole heap).
    Multiprocessing's exit step still runs (no semaphore left to its resource tracker), as in an
    interrupted command's end."""
    if not hasattr(config, "workerinput"):
        return
    _release_multiprocessing()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0 if config.workeroutput.get("exitstatus", 0) == 0 else 1)


def stop_ray() -> None:
    """Shuts down the Ray cluster :func:`ray_cluster` started, if one runs."""
    if _RAY_ADDRESS.pop("gcs", None) is not None:
        sys.modules["ray"].shutdown()
