"""A scenario: which task, user, grasp and mass to simulate, the depth sensor and its noise, and the seed."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.errors import ScenarioError

MAX_NOISE_M = 0.1
"""Upper bound of the depth noise standard deviation [m] (10 cm: beyond it the box is not visible)."""
MAX_DURATION_S = 120.0
"""Upper bound of an episode's length [s] (the truth and the depth of 120 s at 30 fps fit in memory)."""
MAX_FPS = 240.0
"""Upper bound of the camera frame rate [Hz]."""
HAND_SURFACES = ("capsules", "skin", "skin-rigid")
"""How the depth camera sees the hand: its collision primitives, the person's skin
(``benchmark.world.skin``) with pulps that compress under force, or that skin with rigid pulps (an
ablation: only what would pass into the box is flattened onto it)."""
DEFAULT_HAND_SURFACE = "skin"
"""The hand surface of a scenario that names none (episodes with another are named ``...-<surface>``)."""
GRIP_CONTROLS = ("whole-hand", "per-digit")
"""How the simulated person controls the grip (``benchmark.world.grip``): "per-digit" (the world's)
presses each digit for its own load, the grasp as a whole at the person's safety margin, with
tactile feedback on the load each digit carries and the grip's overshoot at lift-off; "whole-hand"
(the world of earlier versions) scales the grasp's squeeze as one pattern until the digit closest
to slipping holds (every digit presses as hard as that one needs)."""
DEFAULT_GRIP_CONTROL = "per-digit"
"""The grip control of a scenario that names none (episodes with another are named ``...-<control>``)."""
SENSORS = ("ds325", "kinect-v1", "ideal")
"""The depth-sensor presets a scenario may name (their models: ``benchmark.camera.sensor.PRESETS``)."""


@dataclass(frozen=True)
class Scenario:
    """Everything that determines an episode; the same scenario gives bit-identical results.

    Attributes:
        task: Name of a registered task (see ``benchmark.world.tasks.TASKS``).
        user: The person: 0-4 the named cohort of ``sim_assets/users.yaml``, N >= 5 a person drawn
            with seed N (``benchmark.world.people``), the same for every scenario.
        grasp: Index into ``sim_assets/grasps.yaml``.
        mass: Index into ``sim_assets/masses.yaml``.
        noise_m: Standard deviation of the depth noise in [m].
        seed: Seed of the scenario's random generator.
        duration_s: Episode length in [s]; None takes the task's default.
        fps: Camera frame rate in [Hz].
        sensor: Name of a depth-sensor preset (:data:`SENSORS`: "ds325", the
            paper's camera, "kinect-v1" or "ideal"); ``noise_m`` is white noise added to its own.
        view: The camera's pose: 0 is ``sim_assets/camera.yaml``'s (the paper's set-up); N >= 1
            is drawn around it with seed N (``benchmark.camera.views``), the same for every scenario.
        hand_surface: What the depth camera sees of the hand (:data:`HAND_SURFACES`): "capsules",
            the simulation's collision primitives, "skin", the person's smooth skin with pulps
            that compress and flatten on the box, or "skin-rigid", that skin with rigid pulps
            (the simulation is the same).
        grip_control: How the person controls the grip (:data:`GRIP_CONTROLS`): "per-digit"
            (the default) or "whole-hand".
    """

    task: str = "lift"
    user: int = 0
    grasp: int = 0
    mass: int = 0
    noise_m: float = 0.01
    seed: int = 0
    duration_s: float | None = None
    fps: float = 30.0
    sensor: str = "ds325"
    view: int = 0
    hand_surface: str = DEFAULT_HAND_SURFACE
    grip_control: str = DEFAULT_GRIP_CONTROL

    def __post_init__(self):
        for name in ("user", "grasp", "mass", "seed", "view"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
                raise ScenarioError(f"{name} must be a non-negative integer, got {v!r}")
        if not (np.isfinite(self.noise_m) and 0 <= self.noise_m <= MAX_NOISE_M):
            raise ScenarioError(f"noise must be a standard deviation in metres in [0, {MAX_NOISE_M}], got {self.noise_m!r}")
        if self.duration_s is not None and not (np.isfinite(self.duration_s) and 0 < self.duration_s <= MAX_DURATION_S):
            raise ScenarioError(f"duration must be > 0 and <= {MAX_DURATION_S:g} seconds, got {self.duration_s!r}")
        if not (np.isfinite(self.fps) and 0 < self.fps <= MAX_FPS):
            raise ScenarioError(f"fps must be > 0 and <= {MAX_FPS:g}, got {self.fps!r}")
        if self.sensor not in SENSORS:
            raise ScenarioError(f"sensor must be one of {', '.join(SENSORS)}, got {self.sensor!r}")
        if self.hand_surface not in HAND_SURFACES:
            raise ScenarioError(f"hand surface must be one of {', '.join(HAND_SURFACES)}, got {self.hand_surface!r}")
        if self.grip_control not in GRIP_CONTROLS:
            raise ScenarioError(f"grip control must be one of {', '.join(GRIP_CONTROLS)}, got {self.grip_control!r}")

    def rng(self, stream: str) -> np.random.Generator:
        """An independent generator for one named use (e.g. "tracker-init", "depth-noise").

        Each stream is derived from the seed and the stream name, so adding draws in one stage
        never shifts the draws of another.
        """
        return np.random.default_rng(np.random.SeedSequence(self.rng_entropy(stream)))

    def rng_entropy(self, stream: str) -> list:
        """The entropy of :meth:`rng`'s generator for ``stream``: the seed, then the name's bytes."""
        return [int(self.seed), *[int(b) for b in stream.encode()]]


def episode_name(scenario: Scenario) -> str:
    """``<task>-u<user>-g<grasp>-m<mass>-s<seed>`` (and ``-v<view>`` for a view other than 0,
    ``-<surface>`` for a hand surface other than :data:`DEFAULT_HAND_SURFACE`, ``-<control>`` for a
    grip control other than :data:`DEFAULT_GRIP_CONTROL`): how
    runs, cached episodes, score rows and dataset files name a scenario."""
    name = f"{scenario.task}-u{scenario.user}-g{scenario.grasp}-m{scenario.mass}-s{scenario.seed}"
    return (name + (f"-v{scenario.view}" if scenario.view else "")
            + ("" if scenario.hand_surface == DEFAULT_HAND_SURFACE else f"-{scenario.hand_surface}")
            + ("" if scenario.grip_control == DEFAULT_GRIP_CONTROL else f"-{scenario.grip_control}"))
