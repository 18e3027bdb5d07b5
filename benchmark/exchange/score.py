"""``fsv-bench score``: score per-frame estimates read from files, with the suite's gates.

    fsv-bench score --suite smoke --estimates DIR --out OUT [--gates FILE] [--cache DIR] [--quiet]

``DIR`` holds one estimates file per episode of the suite, ``DIR/<episode>.npz``
(:mod:`benchmark.exchange.estimates_file`), made by any program from the camera-input files of
``fsv-bench export``. Every file must be present and its header (format, version) readable before
any episode is scored; a missing or malformed file exits 2, naming it. Scores, report, JUnit and exit status are those of
``fsv-bench eval``: the same scorers on the same episodes, so a method scored in-process and from its
files gets the same numbers.
"""

from __future__ import annotations

import argparse
import pathlib
import tempfile
import time

from benchmark.atomic import OUT_AS_IT_WAS_EPISODES_CACHED, check_out
from benchmark.commands.pictures.episodes import EpisodePictures, chosen
from benchmark.exchange.estimates_file import check_identity, load_estimate, read_estimates
from benchmark.exchange.export import FORMATS
from benchmark.fingerprint import world_fingerprint
from benchmark.method.knowledge import DEFAULT_KNOWLEDGE, given
from benchmark.method.protocol import DEFAULT_PROTOCOL, check_protocol
from benchmark.world.scenario import episode_name

INTERRUPTED = OUT_AS_IT_WAS_EPISODES_CACHED
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        add_knowledge_argument,
        add_protocol_argument,
    )
    from benchmark.suites.options import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        add_baseline_argument,
        add_suite_arguments,
    )

    add_suite_arguments(p, out_help="output folder (scores.json, report.md, junit.xml)", workers=False)
    add_baseline_argument(p)
    add_knowledge_argument(p)
    add_protocol_argument(p)
    p.add_argument("--estimates", required=True, type=pathlib.Path, help="folder of <episode>.npz estimates files")
    p.add_argument("--gates", default=None, help="JSON file of gates replacing the suite's defaults")
    p.add_argument("--format", choices=("npz", "hdf5"), default="npz",
                   help="the estimates files' container: <episode>.npz (default) or <episode>.h5")
    from benchmark.commands.eval import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        add_picture_arguments,
    )

    add_picture_arguments(p)


def estimate_paths(suite, folder: pathlib.Path, container: str = "npz") -> dict:
    """``{scenario: path}`` of every episode's estimates file (``.npz``, or ``.h5`` for ``hdf5``);
    ValueError naming the missing ones."""

    folder = pathlib.Path(folder)
    if not folder.is_dir():
        raise ValueError(f"--estimates {folder}: no such folder")
    suffix = FORMATS[container]
    paths = {sc: folder / f"{episode_name(sc)}{suffix}" for sc in suite.scenarios}
    missing = [p.name for p in paths.values() if not p.is_file()]
    if missing:
        others = [name for name, other in FORMATS.items() if other != suffix
                  and all((folder / f"{episode_name(sc)}{other}").is_file() for sc in suite.scenarios)]
        hint = f"; the folder holds every episode's <episode>{FORMATS[others[0]]}: give --format {others[0]}" if others else ""
        raise ValueError(f"--estimates {folder}: {len(missing)} of {len(paths)} episodes have no estimates file "
                         f"(first: {missing[0]}); expected one <episode>{suffix} per episode of suite {suite.name}"
                         + hint)
    return paths


def score_files(suite, folder: pathlib.Path, *, gates=None, cache=None, progress: bool = True, observer=None,
                container: str = "npz", knowledge: str | None = None, protocol: str | None = None) -> dict:
    """Scores the estimates files in ``folder`` on ``suite``: the content of ``scores.json``
    (``observer(episode, estimate, 0)`` sees every estimate, e.g. to draw its pictures).
    ``knowledge`` is what the camera-input files told the method (``fsv-bench export --knowledge``):
    its camera calibration carries the estimates into the true world frame; ``protocol`` what they
    told it of the person (``--protocol``; recorded with every episode)."""

    from benchmark.scores.episode import episode_row  # lazy: MuJoCo (0.25 s) off `fsv-bench score`'s start-up
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        cached_episode,
        episode_cache,
        scores_document,
    )

    protocol = check_protocol(protocol or DEFAULT_PROTOCOL)
    paths = estimate_paths(suite, folder, container)
    world = world_fingerprint()

    def identity(sc):
        return lambda meta: check_identity(paths[sc], meta, episode=episode_name(sc), suite=suite, world=world,
                                           knowledge=knowledge or DEFAULT_KNOWLEDGE)

    # every header before any work
    metas = {sc: read_estimates(p, arrays=False, identity=identity(sc))[0] for sc, p in paths.items()}
    cache = episode_cache(cache)
    t0 = time.perf_counter()
    rows = []
    scenarios = suite.scenarios
    if progress:
        from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench score`'s start-up

        scenarios = tqdm(scenarios, desc=f"score {suite.name}", unit="episode", leave=False)
    for sc in scenarios:
        t1 = time.perf_counter()
        episode, made = cached_episode(suite, sc, cache)
        estimate = load_estimate(paths[sc], t=episode.truth.t, finger_names=tuple(episode.hand_model.finger_names))
        if observer is not None:
            observer(episode, estimate, 0)
        known = given(episode, knowledge or DEFAULT_KNOWLEDGE)[3]
        rows.append(episode_row(episode, estimate, known, protocol, seconds=time.perf_counter() - t1, rendered=made))
    first = metas[suite.scenarios[0]]
    return scores_document(suite, rows, suite.gates if gates is None else gates,
                           method=str(first.get("method") or f"estimates from {folder}"),
                           stages=dict(first.get("stages") or {}), method_spec=None,
                           seconds=time.perf_counter() - t0)


def with_baselines(scores: dict, suite, *, gates, cache, progress: bool, knowledge: str | None = None,
                   protocol: str | None = None) -> dict:
    """``scores`` with its ``baselines`` entry: every trivial baseline run on the same (cached)
    episodes, told what ``knowledge`` and ``protocol`` say."""
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        baseline_specs,
        baselines_block,
        evaluate_many,
    )

    specs = baseline_specs(knowledge, protocol)
    documents = evaluate_many(suite, list(specs.values()), gates=gates, cache=cache, progress=progress)
    return {**scores, "baselines": baselines_block(specs, documents)}


def run(args: argparse.Namespace) -> dict:
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up
        check_cache_args,
        load_gates,
        print_verdict,
        write_outputs,
    )
    from benchmark.suites.options import suite_of  # lazy: scipy.stats (0.4 s) off `fsv-bench score`'s start-up

    suite = suite_of(args)
    gates = load_gates(args.gates) if args.gates else None
    check_out(args.out)
    check_cache_args(args)
    check_protocol(args.protocol)
    estimate_paths(suite, args.estimates, args.format)
    if args.pictures:
        with tempfile.TemporaryDirectory(prefix="fsv-bench-pictures-") as folder:
            writer = EpisodePictures(folder)
            scores = score_files(suite, args.estimates, gates=gates, cache=args.cache, progress=not args.quiet,
                                 observer=writer, container=args.format, knowledge=args.knowledge,
                                 protocol=args.protocol)
            if not args.no_baselines:
                scores = with_baselines(scores, suite, gates=gates, cache=args.cache, progress=not args.quiet,
                                        knowledge=args.knowledge, protocol=args.protocol)
            write_outputs(scores, suite, args.out, chosen(writer, args.pictures)(scores, gates or suite.gates))
    else:
        scores = score_files(suite, args.estimates, gates=gates, cache=args.cache, progress=not args.quiet,
                             container=args.format, knowledge=args.knowledge, protocol=args.protocol)
        if not args.no_baselines:
            scores = with_baselines(scores, suite, gates=gates, cache=args.cache, progress=not args.quiet,
                                        knowledge=args.knowledge, protocol=args.protocol)
        write_outputs(scores, suite, args.out)
    print_verdict(scores, args.out, "score")
    return scores
