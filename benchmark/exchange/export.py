"""``fsv-bench export``: a suite's camera inputs as files, for a method in any language.

    fsv-bench export --suite smoke --out DIR [--streams depth,colour] [--knowledge exact|lab] [--cache DIR] [--quiet]

Writes ``DIR/suite.json`` (the suite, its episodes, the formats' versions, provenance) and one
camera-input file per episode, ``DIR/<episode>.npz`` (:mod:`benchmark.exchange.camera_file`): the
streams asked for (depth always; colour with ``--streams depth,colour``), each with its calibration, object and hand models (as ``--knowledge`` says, with the measurements' precision in
the meta), the coarse first-frame initialisation, and no truth. Episodes
come from the same cache as ``fsv-bench eval``. The folder is written into a temporary one and moved
into place when complete. Score the method's estimates with ``fsv-bench score``.
"""

from __future__ import annotations

import argparse
import json
import pathlib

from benchmark.atomic import OUT_AS_IT_WAS_EPISODES_CACHED, check_out, staged_folder
from benchmark.exchange import camera_file, estimates_file
from benchmark.method.knowledge import DEFAULT_KNOWLEDGE
from benchmark.method.protocol import DEFAULT_PROTOCOL, check_people
from benchmark.method.run import camera_input_and_knowledge
from benchmark.world.scenario import episode_name
from fsv.provenance import provenance

INTERRUPTED = OUT_AS_IT_WAS_EPISODES_CACHED
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench export`'s start-up
        add_knowledge_argument,
        add_protocol_argument,
    )
    from benchmark.suites.options import (  # lazy: scipy.stats (0.4 s) off `fsv-bench export`'s start-up
        add_streams_argument,
        add_suite_arguments,
    )

    add_suite_arguments(p, out_help="output folder (suite.json, <episode>.npz or .h5)", workers=False)
    add_streams_argument(p)
    add_knowledge_argument(p)
    add_protocol_argument(p)
    p.add_argument("--format", choices=FORMATS, default="npz",
                   help="the files' container: npz (NumPy) or hdf5 (for C, C++, Julia, MATLAB, R, JS; <episode>.h5)")


FORMATS = {"npz": ".npz", "hdf5": ".h5"}
"""``--format``: the container of the camera-input and estimates files, by its file suffix."""


def export_suite(suite, out: pathlib.Path, *, cache=None, progress: bool = True, container: str = "npz",
                 knowledge: str = DEFAULT_KNOWLEDGE, protocol: str = DEFAULT_PROTOCOL, streams: tuple = ("depth",)) -> dict:
    """Writes the camera inputs of every episode of ``suite`` into ``out`` (as ``<episode>.npz``, or
    ``.h5`` with ``container="hdf5"``): the ``streams`` (:data:`fsv.types.STREAMS`), the hand, box
    and camera as ``knowledge`` says and the person's grip calibration under the ``calibrated``
    protocol; returns ``suite.json``'s content."""
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench export`'s start-up
        cached_episode,
        episode_cache,
    )

    cache = episode_cache(cache)
    out = pathlib.Path(out)
    suffix = FORMATS[container]
    with staged_folder(out) as tmp:
        episodes = []
        scenarios = suite.scenarios
        if progress:
            from tqdm import tqdm  # lazy: tqdm (30 ms) off `fsv-bench export`'s start-up

            scenarios = tqdm(scenarios, desc=f"export {suite.name}", unit="episode", leave=False)
        for sc in scenarios:
            episode, _ = cached_episode(suite, sc, cache, streams)
            name = episode_name(sc)
            inputs, known = camera_input_and_knowledge(episode, knowledge=knowledge, protocol=protocol)
            camera_file.save_camera_input(inputs, tmp / f"{name}{suffix}", episode=name, suite=suite,
                                          rng_seed=sc.rng_entropy("tracker"), knowledge=known.given_record())
            episodes.append({"episode": name, "file": f"{name}{suffix}", "frames": inputs.num_frames,
                             "task": sc.task})
        index = {"suite": {"name": suite.name, "version": suite.version, "description": suite.description},
                 "knowledge": knowledge, "protocol": protocol, "streams": list(streams), "episodes": episodes,
                 "formats": {"camera": [camera_file.FORMAT, camera_file.VERSION],
                             "estimates": [estimates_file.FORMAT, estimates_file.VERSION]},
                 "estimates": f"write <episode>{suffix} per episode into one folder; fsv-bench score --suite "
                              f"{suite.name} --estimates FOLDER --out OUT --knowledge {knowledge} --protocol {protocol}"
                              + (" --format hdf5" if suffix == ".h5" else ""),
                 "provenance": provenance()}
        (tmp / "suite.json").write_text(json.dumps(index, indent=1) + "\n")
    return index


def run(args: argparse.Namespace) -> dict:
    from benchmark.suites.evaluate import (  # lazy: scipy.stats (0.4 s) off `fsv-bench export`'s start-up
        check_cache_args,
    )
    from benchmark.suites.options import suite_of  # lazy: scipy.stats (0.4 s) off `fsv-bench export`'s start-up

    suite = suite_of(args)
    check_out(args.out)
    check_cache_args(args)
    check_people((sc.user for sc in suite.scenarios), args.protocol)
    index = export_suite(suite, args.out, cache=args.cache, progress=not args.quiet, container=args.format,
                         knowledge=args.knowledge, protocol=args.protocol, streams=args.streams)
    print(f"fsv-bench export: suite {suite.name} v{suite.version}, {len(index['episodes'])} camera-input files "
          f"({', '.join(args.streams)}) in {args.out}/ (format {index['formats']['camera'][0]} v{index['formats']['camera'][1]})")
    return index
