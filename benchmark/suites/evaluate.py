"""``fsv-bench eval``: score the method on a suite and give a verdict for CI.

    fsv-bench eval --suite smoke --out DIR [--gates FILE] [--cache DIR] [--workers N] [--quiet]
                   [--method M | --tracker M --differentiator M --forces M --internal M] [--oracle LIST]

Every episode of the suite is simulated and rendered once and cached (``--cache``, default
``$XDG_CACHE_HOME/fsv-bench/episodes`` or ``~/.cache/fsv-bench/episodes``), keyed by the scenario,
the suite's name and version and the fingerprint of the world's code
(:func:`benchmark.fingerprint.world_fingerprint`); a second evaluation on the same suite renders
nothing. The method (the reference, or the one ``--method``/``--tracker``/... name as
``module:attribute``, see :class:`benchmark.method.MethodSpec`) runs on each episode's camera inputs
through :func:`benchmark.method.run_method`, every stage is scored
(:mod:`benchmark.scores.episode`), the medians and means get 95 % bootstrap intervals, and the
suite's gates (or ``--gates FILE``, a JSON list of ``{"metric", "op", "limit", "statistic"}``) give
the verdict. ``DIR`` receives ``scores.json`` (per episode and aggregate, strict JSON, with
provenance), ``report.md`` and ``junit.xml`` (one test case per gate); it is written into a
temporary folder and moved into place when complete. Exit status: 0 when every gate holds, 1 when
one fails (named on the console), 2 on bad input (before any work).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import pathlib
import shutil
import sys
import time
from dataclasses import asdict

from benchmark.atomic import (
    check_cache,
    check_out,
    claim_folder,
    is_owned,
    remove_stale_temporaries,
    staged_folder,
    user_cache,
)
from benchmark.errors import BenchmarkError, EpisodeFileError
from benchmark.fingerprint import world_fingerprint
from benchmark.limits import checked
from benchmark.method import DIFFERENTIATORS, ORACLE_STAGES, MethodSpec, method_label, run_method
from benchmark.method.knowledge import DEFAULT_KNOWLEDGE, KNOWLEDGE, check_knowledge
from benchmark.method.protocol import DEFAULT_PROTOCOL, PROTOCOLS, check_people, check_protocol
from benchmark.method.run import camera_input_and_knowledge
from benchmark.parallel import check_ray_address, run_jobs
from benchmark.scores.aggregate import FEW_EPISODES, aggregate_all
from benchmark.scores.metrics import METRICS
from benchmark.scores.verdict import GateResult, check_gates, junit_xml, report_markdown
from benchmark.suites import Gate, Suite
from benchmark.suites.options import add_baseline_argument, add_streams_argument, add_suite_arguments, suite_of
from benchmark.world.scenario import Scenario, episode_name
from fsv.method.baselines import BASELINE_STAGE, BASELINES
from fsv.provenance import provenance
from fsv.types import check_streams


class GateFailure(BenchmarkError):
    """At least one gate of the evaluated suite does not hold."""


def default_cache() -> pathlib.Path:
    return user_cache() / "episodes"


def episode_cache(cache: str | os.PathLike | None = None) -> pathlib.Path:
    """The episode cache ``cache`` (default :func:`default_cache`), made fsv-bench's
    (:func:`benchmark.atomic.claim_folder`) when it is new or empty, or when it is the default
    cache (fsv-bench's own folder under the user's cache) of an earlier version. A user's folder
    with other files is used as it is, but no file in it is ever removed
    (:func:`benchmark.atomic.remove_stale_temporaries` needs the marker)."""
    cache = pathlib.Path(cache or default_cache())
    if not is_owned(cache) and (not cache.exists() or (cache.is_dir() and not any(cache.iterdir()))
                                or cache == default_cache()):
        claim_folder(cache, "--cache", adopt=True)
    return cache


def check_cache_args(args: argparse.Namespace) -> None:
    """Refuses ``--cache`` before any work: a file, or the same folder as ``--out`` or one inside
    the other (:func:`benchmark.atomic.check_cache`)."""
    check_cache(args.cache or default_cache(), {"--out": args.out})


def episode_identity(suite: Suite, scenario: Scenario) -> dict:
    """What a cached episode is: its scenario, the suite's name and version, the world's fingerprint."""

    return {"scenario": asdict(scenario), "suite": suite.name, "version": suite.version, "world": world_fingerprint()}


def episode_key(suite: Suite, scenario: Scenario) -> str:
    """Cache key of a rendered episode: a digest of its :func:`episode_identity`."""
    return hashlib.sha256(json.dumps(episode_identity(suite, scenario), sort_keys=True).encode()).hexdigest()[:20]


def cached_episode(suite: Suite, scenario: Scenario, cache: pathlib.Path, streams: tuple = ("depth",)):
    """The rendered episode from the cache, simulated and rendered (and cached) if missing or damaged.

    Args:
        streams: The streams it must hold (:data:`fsv.types.STREAMS`): a cached episode without one
            of them gets it rendered and is cached again (each stream has its own random stream,
            so the bits are those of rendering all at once).

    Returns:
        ``(episode, rendered)``: ``rendered`` is True when it had to be made.
    """
    from benchmark.camera.episode_file import (  # lazy: MuJoCo (0.25 s) off `fsv-bench eval`'s start-up
        load_episode,
        save_episode,
    )
    from benchmark.camera.render import render  # lazy: MuJoCo (0.25 s) off `fsv-bench eval`'s start-up
    from benchmark.world.simulate import simulate  # lazy: MuJoCo (0.25 s) off `fsv-bench eval`'s start-up

    path = cache / suite.name / f"{episode_name(scenario)}-{episode_key(suite, scenario)}.npz"
    if path.parent.is_dir():
        remove_stale_temporaries(path.parent, owner=cache)  # a killed run's half-written episodes
    identity = episode_identity(suite, scenario)
    if path.exists():
        try:
            episode = load_episode(path, scenario=scenario, identity=identity)
            if set(streams) <= set(episode.streams):
                return episode, False
            episode = render(episode, streams=streams)  # the missing streams, added to the cached ones
            save_episode(episode, path, identity=identity)
            return episode, True
        except EpisodeFileError as e:
            print(f"fsv-bench eval: rebuilding a damaged or foreign cached episode: {e}", file=sys.stderr)
    episode = render(simulate(scenario), streams=streams)
    save_episode(episode, path, identity=identity)
    return episode, True


def _episode_rows(job) -> list:
    """One episode: cached or made, every method run on it, every metric (a worker's unit of work).

    Methods whose stages differ only after the tracker share one tracking run of the episode.
    """
    from benchmark.scores.episode import episode_row  # lazy: MuJoCo (0.25 s) off `fsv-bench eval`'s start-up

    suite, sc, cache, specs, init_scale, observer, streams = job
    t0 = time.perf_counter()
    episode, made = cached_episode(suite, sc, cache, streams)
    given = {}  # (knowledge, protocol) -> (camera inputs, what the method was told)
    rows, tracked = [], {}
    for spec in specs:
        t1 = time.perf_counter()
        if (spec.knowledge, spec.protocol) not in given:
            given[spec.knowledge, spec.protocol] = camera_input_and_knowledge(episode, init_scale, spec.knowledge,
                                                                              spec.protocol)
        inputs, known = given[spec.knowledge, spec.protocol]
        key = spec.tracking_key
        shared = None if key is None else tracked.get(key)
        estimate = run_method(spec, episode, inputs=inputs, tracking=shared)
        if key is not None:
            tracked.setdefault(key, estimate.tracking)
        row = episode_row(episode, estimate, known, spec.protocol, seconds=time.perf_counter() - (t0 if not rows else t1),
                          rendered=made and not rows)
        if observer is not None:
            observer(episode, estimate, len(rows))
        rows.append(row)
    return rows


def evaluate(suite: Suite, *, spec=None, gates=None, cache: pathlib.Path | None = None, progress: bool = True,
             workers: int = 1, init_scale: float = 1.0, ray_address: str | None = None, observer=None,
             streams: tuple = ("depth",)) -> dict:
    """Scores one method (default: the reference) on every episode of ``suite``.

    Episodes run in ``workers`` local processes (1: in this process); the scores do not depend on it.

    Returns:
        The content of ``scores.json`` (``episodes``, ``aggregate``, ``per_task``, ``gates``,
        ``verdict``, ``rendered`` episodes, ``method`` and ``stages``, ``provenance``).
    """

    return evaluate_many(suite, [spec or MethodSpec()], gates=gates, cache=cache, progress=progress,
                         workers=workers, init_scale=init_scale, ray_address=ray_address, observer=observer,
                         streams=streams)[0]


def evaluate_many(suite: Suite, specs, *, gates=None, cache: pathlib.Path | None = None, progress: bool = True,
                  workers: int = 1, init_scale: float = 1.0, ray_address: str | None = None, observer=None,
                  streams: tuple = ("depth",)) -> list:
    """Scores several methods on every episode of ``suite``, each episode rendered (or read) once.

    Episodes run in this process, ``workers`` local processes, or as tasks on the Ray cluster at
    ``ray_address`` (:mod:`benchmark.parallel`); the scores do not depend on where.
    ``init_scale`` scales the seeded first-frame perturbation handed to the methods
    (``benchmark.method.init.INIT_PERTURBATION``; 1 = the suites' protocol). ``observer``, a
    picklable callable ``(episode, estimate, method index)``, sees every method's estimate on every
    episode where it is made (e.g. to draw pictures; a floor above provides it). The episodes are
    rendered with the streams the methods read (their ``streams``) and ``streams`` (more, e.g. the
    colour for a depth-only method, ``--streams``); the methods are handed every stream rendered.

    Returns:
        One ``scores.json`` content per method, in the order of ``specs``.
    """

    specs = list(specs)
    for spec in specs:
        spec.check()
    cache = episode_cache(cache)
    gates = suite.gates if gates is None else gates
    t0 = time.perf_counter()
    bar = None
    if progress:
        from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench`'s start-up

        bar = tqdm(total=len(suite.scenarios), desc=f"eval {suite.name}", unit="episode", leave=False)
    streams = check_streams([*streams, *(s for spec in specs for s in spec.streams)])
    jobs = [(suite, sc, cache, specs, init_scale, observer, streams) for sc in suite.scenarios]

    per_episode = [None] * len(jobs)
    for i, rows in run_jobs(_episode_rows, jobs, workers=workers, ray_address=ray_address):
        per_episode[i] = rows
        if bar is not None:
            bar.update(1)
    if bar is not None:
        bar.close()
    seconds = time.perf_counter() - t0
    return [scores_document(suite, [ep_rows[m] for ep_rows in per_episode], gates, method=method_label(spec),
                            stages=dict(getattr(spec.build(), "labels", None) or {}), method_spec=asdict(spec),
                            seconds=seconds)
            for m, spec in enumerate(specs)]


def baseline_specs(knowledge: str | None = None, protocol: str | None = None) -> dict:
    """``{name: MethodSpec}`` of every stage's trivial baseline (:mod:`fsv.method.baselines`), told
    what ``knowledge`` and ``protocol`` say (default: the defaults). Under the ``blind`` protocol
    the grip line, which is a person's calibration and nothing else, is left out."""

    extra = {} if knowledge is None else {"knowledge": knowledge}
    protocol = DEFAULT_PROTOCOL if protocol is None else protocol
    return {name: MethodSpec(method=name, protocol=protocol, **extra) for name in BASELINES
            if not (name == "grip-line" and protocol == "blind")}


def baselines_block(names, documents) -> dict:
    """The ``baselines`` entry of ``scores.json``: per baseline, the stage it stands in for and its
    aggregates on the same episodes (what :func:`benchmark.scores.leaderboard.skill_table` measures
    a method's skill against)."""

    return {name: {"stage": BASELINE_STAGE[name], "aggregate": doc["aggregate"]} for name, doc in zip(names, documents)}


def scores_document(suite: Suite, rows: list, gates, *, method: str, stages: dict, method_spec, seconds: float) -> dict:
    """The content of ``scores.json`` for one method's per-episode rows: aggregates, gates, verdict.

    Args:
        suite: The suite scored.
        rows: One dict per episode (``episode``, ``task``, ``scenario``, every metric, ``seconds``, ``rendered``).
        gates: The gates that decide the verdict.
        method: One line naming the method.
        stages: The name of each stage.
        method_spec: How the method was named (a ``MethodSpec`` as a dict), or None for estimates from files.
        seconds: Wall time of the whole evaluation.
    """

    aggregates = aggregate_all(rows, METRICS)
    results = check_gates(gates, aggregates)
    return {
        "suite": {"name": suite.name, "version": suite.version, "description": suite.description},
        "method": method, "method_spec": method_spec, "stages": stages,
        "metrics": list(METRICS), "n": len(rows), "episodes": rows, "aggregate": aggregates,
        "per_task": aggregate_all(rows, METRICS, by="task"),
        "gates": [asdict(r) for r in results], "verdict": "pass" if all(r.passed for r in results) else "fail",
        "rendered": sum(r["rendered"] for r in rows), "seconds": seconds, "provenance": provenance(),
    }


def strict(obj):
    """``obj`` with NaN and infinities replaced by None (strict JSON)."""
    if isinstance(obj, dict):
        return {k: strict(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [strict(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def write_outputs(scores: dict, suite: Suite, out: pathlib.Path, pictures=()) -> None:
    """Writes ``scores.json``, ``report.md`` and ``junit.xml`` (and ``pictures/``: the given files)
    into a temporary folder, then swaps it in."""

    results = [GateResult(**{**g, "ci": tuple(g["ci"]) if g["ci"] is not None else None}) for g in scores["gates"]]
    out = pathlib.Path(out)
    with staged_folder(out) as tmp:
        (tmp / "scores.json").write_text(json.dumps(strict(scores), indent=1, allow_nan=False) + "\n")
        (tmp / "report.md").write_text(report_markdown(suite, scores["method"], scores["episodes"], scores["aggregate"],
                                                       scores["per_task"], results, METRICS,
                                                       baselines=scores.get("baselines")))
        (tmp / "junit.xml").write_bytes(junit_xml(suite.name, results, scores["seconds"]))
        if pictures:
            (tmp / "pictures").mkdir()
            for path in pictures:
                shutil.copyfile(path, tmp / "pictures" / pathlib.Path(path).name)


GATE_KEYS = {"metric": str, "op": str, "limit": (int, float), "statistic": str}
"""A gates file's entries: these keys (``statistic`` optional, "median" by default) and no others."""


def load_gates(path) -> tuple:
    """Gates from a JSON file: a non-empty list of ``{"metric", "op", "limit"[, "statistic"]}``.

    Raises:
        ValueError: One line naming the file, the entry and what is wrong (unreadable, not a
            non-empty list, an unknown or missing key, a value of the wrong type, a non-finite
            limit, an unknown metric, operator or statistic).
    """

    what = 'a non-empty JSON list of {"metric", "op", "limit"[, "statistic"]}'
    try:
        data = json.loads(pathlib.Path(path).read_text(), parse_constant=float)
    except (OSError, ValueError) as e:
        raise ValueError(f"--gates {path}: not {what}: {e}") from e
    if not isinstance(data, list) or not data:
        raise ValueError(f"--gates {path}: not {what}: got {json.dumps(data)[:60]}")
    gates = []
    for i, g in enumerate(data):
        where = f"--gates {path}: entry {i}"
        if not isinstance(g, dict):
            raise ValueError(f"{where} is not an object: {json.dumps(g)[:60]}")
        unknown = sorted(set(g) - set(GATE_KEYS))
        if unknown:
            raise ValueError(f"{where}: unknown key {unknown[0]!r}; accepted: {', '.join(GATE_KEYS)}")
        missing = [k for k in ("metric", "op", "limit") if k not in g]
        if missing:
            raise ValueError(f"{where}: missing key {missing[0]!r}")
        for k, v in g.items():
            if isinstance(v, bool) or not isinstance(v, GATE_KEYS[k]):
                raise ValueError(f"{where}: {k} must be a {'number' if k == 'limit' else 'string'}, got {v!r}")
        if not math.isfinite(g["limit"]):
            raise ValueError(f"{where}: limit must be a finite number, got {g['limit']!r}")
        if g["metric"] not in METRICS:
            raise ValueError(f"{where}: unknown metric {g['metric']!r}; accepted: {', '.join(METRICS)}")
        try:
            gates.append(Gate(metric=g["metric"], op=g["op"], limit=float(g["limit"]),
                              statistic=g.get("statistic", "median")))
        except ValueError as e:
            raise ValueError(f"{where}: {e}") from e
    return tuple(gates)


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_suite_arguments(p, out_help="output folder (scores.json, report.md, junit.xml)")
    add_baseline_argument(p)
    add_streams_argument(p)
    p.add_argument("--gates", default=None, help="JSON file of gates replacing the suite's defaults")
    p.add_argument("--ray-address", default=None,
                   help="run the episodes as tasks on this Ray cluster ('auto', host:port or ray://host:port; needs the ray extra)")
    add_method_arguments(p)


def add_method_arguments(p: argparse.ArgumentParser, oracle: bool = True, internal_model: bool = True) -> None:
    """``--method``, ``--tracker``, ``--differentiator``, ``--forces``, ``--internal``, ``--internal-model`` [, ``--oracle``]."""

    g = p.add_argument_group("the method (default: the reference; replace a stage by module:attribute)")
    g.add_argument("--method", default=None, metavar="NAME|MODULE:ATTR",
                   help="a whole method: an fsv.method.Method (or a factory of one) or a callable (inputs, rng) -> Estimate; "
                        "or a stage's trivial baseline: static, zero-kinematics, gravity-forces, no-internal, grip-line; "
                        "or direct: an end-to-end network from the tracker's outputs to each finger's force")
    g.add_argument("--tracker", default=None, metavar="MODULE:ATTR", help="(inputs, rng) -> tracking with .box and .contacts")
    g.add_argument("--differentiator", default=None, metavar="NAME|MODULE:ATTR",
                   help=f"(poses) -> Kinematics, or one of {', '.join(DIFFERENTIATORS)}")
    g.add_argument("--forces", default=None, metavar="MODULE:ATTR",
                   help="(kinematics, contacts, object_model, gravity) -> ForceSolution")
    g.add_argument("--internal", default=None, metavar="none|MODULE:ATTR",
                   help="(kinematics, contacts, object_model, gravity) -> (ForceSolution, predicted); none: nominal forces only")
    if internal_model:  # the main command's learning stage has its own
        g.add_argument("--internal-model", default=None, metavar="FILE",
                       help="a model file of `fsv-bench train` for the reference internal-force stage (default: the shipped one)")
    g.add_argument("--direct-model", default=None, metavar="FILE",
                   help="with --method direct: a model file of `fsv-bench train-direct` (default: the shipped "
                        "fsv/data/direct_forces.npz)")
    if oracle:
        g.add_argument("--oracle", default="", metavar="LIST",
                       help=f"inputs replaced by the truth, labelled oracle ({', '.join(ORACLE_STAGES)}; comma-separated)")
    add_knowledge_argument(g)
    add_protocol_argument(g)


def add_protocol_argument(p) -> None:
    """``--protocol blind|calibrated``: what the method is told of the person."""

    p.add_argument("--protocol", default=DEFAULT_PROTOCOL, metavar="|".join(PROTOCOLS), type=checked(check_protocol),
                   help="what the method is told of the person: blind (nothing, the paper's protocol) or "
                        "calibrated (the person's grip line from a calibration recording of their own); "
                        f"default {DEFAULT_PROTOCOL}")


def add_knowledge_argument(p) -> None:
    """``--knowledge lab|exact|...``: what the method is told of the hand, the box and the camera."""

    p.add_argument("--knowledge", default=DEFAULT_KNOWLEDGE, metavar="|".join(KNOWLEDGE), type=checked(check_knowledge),
                   help="what the method is told of the hand, the box and the camera: lab (measured with a ruler, "
                        "a scale, a tilt test and a camera calibration, with their errors; lab-hand, lab-box, "
                        "lab-camera: one source's alone; NAME:FACTOR scales the errors, e.g. lab:2) or exact (the "
                        f"simulation's own values, an ablation); default {DEFAULT_KNOWLEDGE}")


def spec_from_args(args: argparse.Namespace):
    """The :class:`benchmark.method.MethodSpec` of the command line, loaded and checked (raises ValueError)."""

    spec = MethodSpec(method=args.method, tracker=args.tracker, differentiator=args.differentiator,
                      forces=args.forces, internal=args.internal, internal_model=getattr(args, "internal_model", None),
                      direct_model=getattr(args, "direct_model", None),
                      oracle=tuple(o for o in getattr(args, "oracle", "").split(",") if o),
                      knowledge=getattr(args, "knowledge", DEFAULT_KNOWLEDGE),
                      protocol=getattr(args, "protocol", DEFAULT_PROTOCOL))
    spec.check()
    return spec


def run(args: argparse.Namespace, *, observer=None, pictures=None) -> dict:
    """Runs ``fsv-bench eval``: checks every input, evaluates, writes, prints; raises GateFailure on a failed gate.

    ``observer`` sees every estimate (:func:`evaluate_many`); ``pictures(scores, gates)`` returns
    files to write into ``DIR/pictures/`` (the commands' ``--pictures``).
    """

    suite = suite_of(args)
    gates = load_gates(args.gates) if args.gates else None
    if args.workers < 1:
        raise ValueError(f"--workers {args.workers}: need at least 1 worker process")
    check_out(args.out)
    check_cache_args(args)
    spec = spec_from_args(args)

    check_people((sc.user for sc in suite.scenarios), spec.protocol)
    if args.ray_address is not None:
        check_ray_address(args.ray_address)
    extra = {} if args.no_baselines else baseline_specs(spec.knowledge, spec.protocol)
    documents = evaluate_many(suite, [spec, *extra.values()], gates=gates, cache=args.cache, progress=not args.quiet,
                              workers=args.workers, ray_address=args.ray_address, streams=getattr(args, "streams", ("depth",)),
                              observer=None if observer is None else _first_method_only(observer))
    scores = documents[0]
    if extra:
        scores["baselines"] = baselines_block(extra, documents[1:])
    write_outputs(scores, suite, args.out, () if pictures is None else pictures(scores, gates or suite.gates))
    print_verdict(scores, args.out, "eval")
    return scores


class _first_method_only:
    """An observer that sees only the first method's estimates (not the baselines run beside it)."""

    def __init__(self, observer):
        self.observer = observer

    def __call__(self, episode, estimate, index):
        if index == 0:
            self.observer(episode, estimate, index)


def print_verdict(scores: dict, out, command: str) -> None:
    """Prints the gates of ``scores`` and raises GateFailure naming the failed ones."""
    suite = scores["suite"]
    n = len(scores["episodes"])
    print(f"fsv-bench {command}: suite {suite['name']} v{suite['version']}, n = {n} episodes "
          f"({scores['rendered']} rendered, the rest from the cache), {scores['seconds']:.0f} s\n  method: {scores['method']}"
          + (f"\n  95 % intervals over {n} episodes are little more than the values' range" if n < FEW_EPISODES else ""))
    for g in scores["gates"]:
        ci = "" if g["ci"] is None else f" 95 % CI [{g['ci'][0]:.4g}, {g['ci'][1]:.4g}]"
        value = "nothing scored" if g["value"] is None else f"{g['value']:.4g}"
        print(f"  {'pass' if g['passed'] else 'FAIL'}  {g['name']}: {value}{ci}")
    print(f"written to {out}/ (scores.json, report.md, junit.xml)")
    failed = [g["name"] for g in scores["gates"] if not g["passed"]]
    if failed:
        raise GateFailure(f"{len(failed)} gate(s) failed: {'; '.join(failed)}")
