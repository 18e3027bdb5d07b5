"""Pictures of a method on a suite's episodes: where it fails, seen (``fsv-bench eval`` / ``score --pictures``)."""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

from benchmark.commands.pictures.fig5 import plot_fig5
from benchmark.commands.pictures.overlay import plot_overlay
from benchmark.world.scenario import episode_name

PICTURES = ("worst", "all")
"""``--pictures``: every episode's, or those of the episodes that score worst on some gate's metric."""


@dataclass(frozen=True)
class EpisodePictures:
    """Draws an estimate's tracking overlay (with the truth) and Fig. 5 into ``folder``, per episode:
    ``<episode>-overlay.png`` and ``<episode>-forces.png`` (an evaluation's observer; picklable)."""

    folder: str

    def __call__(self, episode, estimate, index: int = 0) -> None:
        name = episode_name(episode.scenario) + (f"-method{index}" if index else "")
        folder = pathlib.Path(self.folder)
        plot_overlay(episode.depth, episode.calib, estimate.tracking, episode.object_model, episode.hand_model,
                     folder / f"{name}-overlay.png", truth=episode.truth)
        if estimate.nominal is not None:
            plot_fig5(estimate.nominal, episode.truth, estimate.kinematics.rot, folder / f"{name}-forces.png",
                      title=f"{name}: forces", learned=estimate.forces)

    def files(self, episodes) -> list:
        """The pictures drawn of ``episodes`` (names), in order."""
        folder = pathlib.Path(self.folder)
        return [p for e in episodes for p in sorted(folder.glob(f"{e}-*.png"))]


def worst_episodes(scores: dict, gates) -> list:
    """For each gate, the episode whose value of the gate's metric is worst (largest for ``<=``,
    smallest for ``>=``; an episode with nothing scored is worst of all); each episode once."""
    out = []
    for g in gates:
        def badness(row):
            v = row.get(g.metric)
            if v is None or (isinstance(v, float) and math.isnan(v)):
                return math.inf
            return v if g.op == "<=" else -v

        worst = max(scores["episodes"], key=badness)["episode"]
        if worst not in out:
            out.append(worst)
    return out


def chosen(writer: EpisodePictures, which: str):
    """``pictures(scores, gates)`` for the suite commands: the files of every episode or of the worst."""
    def pick(scores: dict, gates) -> list:
        episodes = [r["episode"] for r in scores["episodes"]] if which == "all" else worst_episodes(scores, gates)
        return writer.files(episodes)

    return pick
