"""A dataset's grid of scenarios and its sources: :class:`DatasetSpec`, and the episodes' names."""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from benchmark.errors import DatasetError, ScenarioError
from benchmark.limits import MAX_EPISODES
from benchmark.world.scenario import Scenario
from fsv._check import positive

FORMAT = "fsv-bench-dataset"
VERSION = 3  # version 1 had no digests; 2 no 3D forces, table wrench, paper_rule column or rows "all"
KINEMATICS = ("algebraic", "central", "gaussian", "oracle")
DESIGNS = ("grid", "people")
CONTACTS = ("tracker", "error-model", "oracle")
ROWS = ("paper", "all")
_AX = "xyz"


@dataclass(frozen=True)
class DatasetSpec:
    """Which episodes a dataset holds and how its samples are made.

    Attributes:
        tasks: Task names (see ``benchmark.world.tasks.TASKS``).
        users, grasps, masses: People, grasps and masses: indices (people and grasps beyond the
            named ones are drawn, see ``benchmark.world.people`` and ``grasp_families``).
        views: Camera views (0: the paper's set-up; N >= 1 drawn, ``benchmark.camera.views``).
        seeds: Scenario seeds.
        design: "grid": every combination of tasks, users, grasps, masses, seeds and views;
            "people": each user holds their own grasp and camera view (the grasp's and the view's
            index is the user's; ``grasps`` and ``views`` are not used) through every task and
            seed, and the masses rotate: the user at position u, task at position t and seed at
            position s hold ``masses[(u + t + s) % len(masses)]`` (every task meets every mass,
            every person several).
        duration_s: Episode length in [s]; None takes each task's default.
        fps: Frame rate in [Hz].
        noise_m: Depth noise of the scenarios [m]; it sets the tracker-like pose errors that the
            kinematics are differentiated from (``benchmark.world.pose_error``).
        kinematics: Kinematics behind the features and the decomposition: a differentiator of
            ``benchmark.world.motion`` ("algebraic", "central", "gaussian") on the observed poses, or
            "oracle" (the truth). On tracked poses "algebraic" is the reference method's
            (``fsv.method.reference.TRACKED_POSES``).
        contacts: Source of the contacts (see the module docstring): "tracker" (render and track
            each episode: the method's contacts and poses), "error-model" (the truth's with the
            paper's contact-point errors) or "oracle" (the truth).
        tactile_noise_n: Noise of the simulated tactile sensors (``benchmark.world.tactile``), [N].
        max_gap_n: Samples whose vision and tactile net forces differ by more than this are dropped, [N].
        min_fingers: Frames with fewer fingers in contact are dropped.
        rows: Which frames become rows: "paper" (the frames the paper's sample rules keep, above,
            whose decomposition was solved) or "all" (every frame with valid kinematics; the
            column ``paper_rule`` says which of them the paper's rules keep, and ``f_nom_``/``f_int_``
            are NaN on the others: the decomposition runs on the kept frames only). The
            end-to-end networks (``fsv-bench train-direct``) learn from "all".
    """

    tasks: tuple = ("lift",)
    users: tuple = (0,)
    grasps: tuple = (0,)
    masses: tuple = (0,)
    seeds: tuple = (0,)
    views: tuple = (0,)
    design: str = "grid"
    duration_s: float | None = None
    fps: float = 30.0
    noise_m: float = 0.01
    kinematics: str = "algebraic"
    contacts: str = "tracker"
    tactile_noise_n: float = 0.1
    max_gap_n: float = 1.5
    min_fingers: int = 2
    rows: str = "paper"

    def __post_init__(self):
        object.__setattr__(self, "tasks", tuple(str(t) for t in self.tasks))
        for name in ("users", "grasps", "masses", "seeds", "views"):
            vals = tuple(getattr(self, name))
            if not vals or any(isinstance(v, bool) or int(v) != v or v < 0 for v in vals):
                raise DatasetError(f"{name} must be a non-empty list of non-negative integers, got {vals!r}")
            object.__setattr__(self, name, tuple(int(v) for v in vals))
        if not self.tasks:
            raise DatasetError("tasks must name at least one task")
        if self.size() > MAX_EPISODES:
            raise DatasetError(f"the dataset's grid holds {self.size():,} episodes, more than the {MAX_EPISODES:,} "
                               "accepted; split it into several datasets")
        for name, accepted in (("kinematics", KINEMATICS), ("contacts", CONTACTS), ("design", DESIGNS), ("rows", ROWS)):
            if getattr(self, name) not in accepted:
                raise DatasetError(f"{name} source must be one of {accepted}, got {getattr(self, name)!r}")
        if not (np.isfinite(self.tactile_noise_n) and self.tactile_noise_n >= 0):
            raise DatasetError(f"tactile_noise_n must be >= 0 N, got {self.tactile_noise_n!r}")
        if not (np.isfinite(self.noise_m) and self.noise_m >= 0):
            raise DatasetError(f"noise_m must be >= 0 m, got {self.noise_m!r}")
        positive("max_gap_n", self.max_gap_n, "> 0 N", DatasetError)
        if int(self.min_fingers) < 2:
            raise DatasetError(f"min_fingers must be >= 2 (internal forces need two fingers), got {self.min_fingers!r}")
        self._check_grid()

    def _check_grid(self) -> None:
        """Every task, user, grasp and mass exists and the duration suits every task (before any work)."""
        from benchmark.world.assets import validate  # lazy: MuJoCo (0.25 s) off `fsv-bench generate`'s start-up

        try:
            base = Scenario(noise_m=self.noise_m, duration_s=self.duration_s, fps=self.fps)
            for t in self.tasks:
                validate(replace(base, task=t))
            for name, values in (("user", self.users), ("grasp", self.grasps), ("mass", self.masses)):
                for v in values:
                    validate(replace(base, task=self.tasks[0], **{name: v}))
        except ScenarioError as e:
            raise DatasetError(str(e)) from None

    def size(self) -> int:
        """The number of episodes of the dataset (its scenarios, counted without building them)."""
        if self.design == "people":
            return len(self.users) * len(self.tasks) * len(self.seeds)
        return len(self.tasks) * len(self.users) * len(self.grasps) * len(self.masses) * len(self.seeds) * len(self.views)

    def scenarios(self) -> list[Scenario]:
        """Every scenario of the dataset, in a fixed order."""
        if self.design == "people":
            n = len(self.masses)
            return [Scenario(task=t, user=u, grasp=u, mass=self.masses[(iu + it + js) % n], seed=s, view=u,
                             noise_m=self.noise_m, duration_s=self.duration_s, fps=self.fps)
                    for iu, u in enumerate(self.users) for it, t in enumerate(self.tasks)
                    for js, s in enumerate(self.seeds)]
        return [
            Scenario(task=t, user=u, grasp=g, mass=m, seed=s, view=v, noise_m=self.noise_m, duration_s=self.duration_s,
                     fps=self.fps)
            for t in self.tasks for u in self.users for g in self.grasps for m in self.masses for s in self.seeds
            for v in self.views
        ]

    def as_dict(self) -> dict:
        """JSON of the spec (``views`` left out while it is the paper's view alone, ``design`` while
        it is the grid and ``rows`` while they are the paper's, as before any of them existed)."""
        out = {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v) for f in fields(self)}
        if self.views == (0,):
            del out["views"]
        if self.design == "grid":
            del out["design"]
        if self.rows == "paper":
            del out["rows"]
        return out



