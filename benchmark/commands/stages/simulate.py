"""The simulate stage: the scenario's truth from MuJoCo; the ``scenario`` and ``world`` blocks."""

from __future__ import annotations

from benchmark.commands.report import format_world, scenario_block, world_block
from benchmark.commands.stage import Run, Stage, StageResult
from benchmark.world.simulate import run as simulate_run


def run(record: Run, options) -> StageResult:
    episode, stats = simulate_run(record.scenario, progress=not record.quiet)
    block = world_block(episode, stats.steps_per_s)
    return StageResult(blocks=(("scenario", scenario_block(episode)), ("world", block)),
                       lines=(format_world(block),), episode=episode)


STAGE = Stage(name="simulate", run=run)
