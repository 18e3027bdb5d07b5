"""Disjoint splits of the population: which people, grasps and views train, choose and test.

A scenario's person (``Scenario.user``), grasp and view are each an index; the named cohort keeps
the low ones (users 0-4 of ``users.yaml``, grasps 0-3 of ``grasps.yaml``, view 0, the paper's
set-up) and every index beyond is drawn from a generator seeded with it. The splits are index
ranges, the same for the three kinds (:data:`SPLITS`), so no person, grasp or view of one split is
ever met in another:

- ``cohort``: the named ones (Table 1 and Table 2 keep their protocols on them; today's shipped
  model was trained on them);
- ``dev``: 100-499, for choosing methods and parameters;
- ``test``: 500-999, never used for training or for choosing anything;
- ``train``: 1000 and above, for training data of any size (``fsv-bench generate --split train``).

Indices between the cohort and 100 belong to no split: free for a user's own experiments
(``fsv-bench --user 17``). A scenario is in a split when its person, grasp and view all are
(:func:`split_of`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.world.people import named_count
from benchmark.world.scenario import Scenario


@dataclass(frozen=True)
class Split:
    """One split: the index range ``[start, stop)`` of its people, grasps and views (stop None: unbounded)."""

    name: str
    start: int
    stop: int | None
    purpose: str

    def holds(self, index: int) -> bool:
        """Whether ``index`` (a person's, a grasp's or a view's) lies in this split."""
        return self.start <= int(index) and (self.stop is None or int(index) < self.stop)

    def index(self, position: int) -> int:
        """The ``position``-th index of the split (0-based); ValueError beyond its end."""
        position = int(position)
        if position < 0 or (self.stop is not None and self.start + position >= self.stop):
            size = "unbounded" if self.stop is None else f"{self.stop - self.start}"
            raise ValueError(f"position {position} is not in split {self.name!r} (size {size}); accepted: 0 to "
                             + ("any" if self.stop is None else str(self.stop - self.start - 1)))
        return self.start + position


SPLITS = {
    "cohort": Split("cohort", 0, 5, "the named users 0-4, grasps 0-3 and view 0 (Table 1, Table 2)"),
    "dev": Split("dev", 100, 500, "choosing methods and parameters"),
    "test": Split("test", 500, 1000, "scoring only: never used for training or for choosing anything"),
    "train": Split("train", 1000, None, "training data of any size"),
}
"""The splits by name. The cohort's range is that of its people; its grasps are 0-3 and its view 0."""


def split_of(scenario: Scenario) -> str | None:
    """The split holding the scenario's person, grasp and view; None if they are not all in one."""
    from benchmark.world.assets import grasps  # lazy: MuJoCo (0.25 s) off `fsv-bench eval`'s start-up

    if scenario.user < named_count() and scenario.grasp < len(grasps()) and scenario.view == 0:
        return "cohort"
    for split in SPLITS.values():
        if split.name != "cohort" and split.holds(scenario.user) and split.holds(scenario.grasp) and split.holds(scenario.view):
            return split.name
    return None


def split_scenarios(split: str, tasks, per_task: int, *, first: int = 0, seed: int, masses: int) -> tuple:
    """Scenarios of one split, each with a person, a grasp and a view met in no other scenario.

    Args:
        split: "dev", "test" or "train".
        tasks: Task names; ``per_task`` episodes each, in task order.
        per_task: Episodes per task.
        first: Position in the split of the first episode's person, grasp and view.
        seed: Seeds the masses' draw; episode ``i`` has scenario seed ``seed + i``.
        masses: How many masses to draw from (``sim_assets/masses.yaml``'s count).

    Returns:
        ``len(tasks) * per_task`` scenarios; episode ``i`` has person, grasp and view ``first + i``
        of the split.
    """
    if split not in SPLITS or split == "cohort":
        raise ValueError(f"split {split!r}: accepted: dev, test, train")
    s = SPLITS[split]
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), *b"split-masses"]))
    out = []
    for i, (task, _) in enumerate((t, k) for t in tasks for k in range(per_task)):
        j = s.index(first + i)
        out.append(Scenario(task=task, user=j, grasp=j, view=j, mass=int(rng.integers(masses)), seed=int(seed) + i))
    return tuple(out)
