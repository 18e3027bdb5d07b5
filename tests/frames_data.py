"""A tiny frames dataset for the tests of ``generate --frames``, its shards, Dataset and card:
two 1 s lifts (seeds 0 and 1), depth and colour, each simulated and rendered once per process."""

from benchmark.camera.render import render
from benchmark.paper.dataset import DatasetSpec
from benchmark.paper.dataset.frames import FramesSpec, generate_frames
from benchmark.world.simulate import simulate

_EPISODES = {}
CALLS = []


def cached_episode(scenario, streams):
    """simulate + render, once per (scenario, streams) in this process; counts the calls."""
    CALLS.append((scenario.seed, tuple(streams)))
    key = (scenario, tuple(streams))
    if key not in _EPISODES:
        _EPISODES[key] = render(simulate(scenario), streams=streams)
    return _EPISODES[key]


def tiny_spec(streams=("depth", "colour"), encoding="raw", seeds=(0, 1)) -> FramesSpec:
    return FramesSpec(grid=DatasetSpec(tasks=("lift",), seeds=seeds, duration_s=1.0), streams=streams,
                      colour_encoding=encoding)


def make_tiny(out, **kw):
    """The tiny dataset in ``out``: ``(spec, index)``."""
    spec = tiny_spec(**kw)
    return spec, generate_frames(spec, out, workers=1, progress=False, make=cached_episode)
