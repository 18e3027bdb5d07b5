"""One kind of stage for the main command: a function of a frozen record that returns a frozen result.

The main command (:mod:`benchmark.commands.cli`) runs its stages in order. A stage reads the
:class:`Run` (the scenario, the method, and what earlier stages made: the episode, the estimate)
and the options it declares, and returns a :class:`StageResult`: its blocks of ``summary.json``,
its printed lines, its files, the pictures to draw beside the next stages, and what it makes for the later
stages. The command builds the next :class:`Run` from it (``dataclasses.replace``); no stage writes
into another's state or reads an option it did not declare.

A stage may leave part of its work to finish beside the later stages when none of them needs it
(the colour stream of a method that reads only depth): it starts that work on the command's
:class:`benchmark.background.Background` (``Run.background``) and returns its
:class:`benchmark.background.Job` in ``StageResult.later``; the job's result, a
:class:`StageResult` of its own, takes its place after the stage's own blocks and lines when the
command ends, and its episode replaces the run's.
"""

from __future__ import annotations

import types
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from benchmark.atomic import write_bytes
from benchmark.world.episode import Episode
from benchmark.world.scenario import Scenario


@dataclass(frozen=True)
class Picture:
    """A picture (or other file) a stage asks for; the command draws it beside the later stages.

    Attributes:
        name: What it is, for an error message ("tracking overlay").
        draw: A module-level function that writes it.
        args: Positional arguments of ``draw``.
        kwargs: Keyword arguments of ``draw``.
        in_thread: Draw it in a thread (work that releases the interpreter lock, e.g. compressing
            the episode archive) instead of a forked process (matplotlib figures).
    """

    name: str
    draw: Callable
    args: tuple = ()
    kwargs: Mapping = field(default_factory=dict)
    in_thread: bool = False


@dataclass(frozen=True)
class Run:
    """What the stages of one command share, as it stands before a stage.

    Attributes:
        scenario: The scenario being run.
        out: The folder the stages write into (a temporary sibling of ``--out`` until the end).
        method_spec: The method the command runs (``benchmark.method.MethodSpec``), checked before any work.
        quiet: No progress bars.
        episode: The episode, once simulated (rendered after the render stage).
        estimate: The method's ``fsv.method.Estimate`` on the episode, once the track stage ran it.
        knowledge: What the method was told (``benchmark.method.knowledge.Knowledge``), from the
            track stage on.
        inputs: What the method was handed (``fsv.method.CameraInput``: calibration, models, the
            person's grip calibration or None), from the track stage on.
        learned: The estimate's final forces scored against the truth
            (:func:`benchmark.scores.learned.score_episode`), from the learn stage on (None before,
            or for a method without them): the verdict takes its metrics from it.
        background: The command's :class:`benchmark.background.Background`, where a stage may
            start work that finishes beside the later stages (``StageResult.later``); None (a stage
            run on its own) does all its work before it returns.
    """

    scenario: Scenario
    out: Any
    method_spec: Any
    quiet: bool = False
    episode: Episode | None = None
    estimate: Any = None
    knowledge: Any = None
    inputs: Any = None
    learned: dict | None = None
    background: Any = None


@dataclass(frozen=True)
class StageResult:
    """What one stage made.

    Attributes:
        blocks: ``((key, block), ...)``: blocks of ``summary.json``, in order.
        lines: Lines printed at the end of the command.
        files: ``((file name, bytes), ...)``: small files the command writes into its output folder.
        pictures: Pictures to draw beside the later stages.
        episode: The stage's new episode (the rendered one), or None to keep the run's.
        estimate: The method's estimate, if this stage ran the method, else None.
        knowledge: What the method was told, if this stage ran it, else None.
        inputs: What the method was handed, if this stage ran it, else None.
        learned: The final forces' scores, if this stage scored them, else None.
        later: Jobs (:class:`benchmark.background.Job`) of this stage's still running beside the
            later stages; each one's result is a :class:`StageResult` that completes this one at the end.
        digests: ``((name, digest), ...)``: digests of :data:`benchmark.commands.digests.STAGES`
            already computed off the command's critical path (a later job's).
    """

    blocks: tuple = ()
    lines: tuple = ()
    files: tuple = ()
    pictures: tuple = ()
    episode: Episode | None = None
    estimate: Any = None
    knowledge: Any = None
    inputs: Any = None
    learned: dict | None = None
    later: tuple = ()
    digests: tuple = ()

    def __post_init__(self):
        for name in ("blocks", "lines", "files", "pictures", "later", "digests"):
            if not isinstance(getattr(self, name), tuple):
                raise TypeError(f"StageResult.{name} must be a tuple, got {type(getattr(self, name)).__name__}")

    def updates(self) -> dict:
        """The fields of :class:`Run` this result replaces."""
        return {k: v for k, v in (("episode", self.episode), ("estimate", self.estimate), ("knowledge", self.knowledge),
                                  ("inputs", self.inputs), ("learned", self.learned)) if v is not None}


def _no_arguments(parser) -> None:
    return None


@dataclass(frozen=True)
class Stage:
    """One step of the main command.

    Attributes:
        name: Its entry in ``timing_s``.
        run: ``run(record, options) -> StageResult``; raises a BenchmarkError/FsvError on failure.
        options: The names (``argparse`` destinations) of the options it reads; it gets exactly those.
        add_arguments: Adds the options it owns to the parser (an option may be read by several
            stages and is added by one).
    """

    name: str
    run: Callable[[Run, Mapping], StageResult]
    options: tuple = ()
    add_arguments: Callable = _no_arguments

    def __call__(self, record: Run, args) -> StageResult:
        """Runs the stage on ``record`` with its declared options taken from ``args`` (an argparse namespace)."""
        options = types.MappingProxyType({name: getattr(args, name) for name in self.options})
        result = self.run(record, options)
        if not isinstance(result, StageResult):
            raise TypeError(f"stage {self.name} returned {type(result).__name__}, not a StageResult")
        return result


def complete(result: StageResult, out, background=None) -> None:
    """Writes a result's files into ``out`` and draws its pictures: on ``background``
    (:class:`benchmark.background.Background`, beside the later stages), or at once without one
    (a stage run on its own)."""

    for name, data in result.files:
        write_bytes(out / name, data)
    for picture in result.pictures:
        if background is None:
            picture.draw(*picture.args, **dict(picture.kwargs))
        else:
            start = background.thread if picture.in_thread else background.process
            start(picture.name, picture.draw, *picture.args, **dict(picture.kwargs))
