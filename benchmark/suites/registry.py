"""The registered suites."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from benchmark.suites.splits import split_scenarios
from benchmark.suites.suite import Gate, Suite
from benchmark.world.scenario import GRIP_CONTROLS, HAND_SURFACES, Scenario

SMOKE = Suite(
    name="smoke",
    version=9,  # 9: a guarded set-down, grasp trials on light boxes; 8: drawn margins, the tail's gate
    scenarios=(
        Scenario(task="lift", user=0, grasp=0, mass=0, seed=11, duration_s=4.0),
        Scenario(task="place", user=2, grasp=2, mass=1, seed=12, duration_s=4.0),
        Scenario(task="rotate", user=3, grasp=3, mass=2, seed=13, duration_s=4.0),
        Scenario(task="release", user=1, grasp=1, mass=0, seed=14, duration_s=4.0),
    ),
    # A regression gate for CI, measured by the reference method on this machine (the named users'
    # own hands, the shipped models trained on the training split, the blind protocol, lab
    # knowledge), and set so that the trivial baseline of each stage (fsv.method.baselines) fails
    # its stage's gates: the static box (no vision) the tracker's, zero kinematics the acceleration
    # gate, gravity-only forces the net-force gates, no internal forces the learned-force gate. Each
    # gate's `measured` gives the reference's value on this version's world and the baseline's; why
    # a version moved a gate is in the CHANGELOG (version 9: the acceleration gate 0.8 -> 0.6 m/s^2,
    # as the guarded set-down leaves zero kinematics at 0.80, which the old gate let pass).
    gates=(
        Gate("box_pos_err_mm", "<=", 8.0, measured="median 4.12 mm (1.60-4.96), lab knowledge; "
                                                   "the static box 132 mm"),
        Gate("contact_err_mm_std", "<=", 5.0, measured="median 2.02 mm (1.27-3.15)"),
        Gate("contact_recall", ">=", 0.85, measured="median 0.978; the static box 0"),
        Gate("contact_precision", ">=", 0.85, measured="median 0.943"),
        Gate("acc_err_rms", "<=", 0.6, measured="median 0.37 m/s^2 (0.21-0.80: release's box let go on the "
                                            "table); zero kinematics 0.80"),
        Gate("net_force_err_n_rms", "<=", 0.3, measured="median 0.15 N (0.08-0.21); gravity-only forces 0.47"),
        Gate("net_force_err_n_rms", "<=", 0.5, statistic="p90",
             measured="largest 0.21 N; gravity-only forces' 0.87 N"),
        Gate("least_violation_frac", "<=", 0.25, statistic="mean", measured="mean 0 (no frame on any task)"),
        Gate("learned_rel_err_pct", "<=", 50.0,
             measured="median 37.9 % over every contact frame, blind; no internal forces 65.1 %"),
    ),
    description=(
        "For CI: four 4 s episodes of the named cohort, one per task family (lift, place, rotate, release), "
        "each with another user, grasp and mass, seeds 11-14 (never used for tuning). The whole method from "
        "1 cm depth noise on the ds325 sensor, under the blind protocol and lab knowledge; gates on the medians over the four "
        "episodes: a regression gate, not a measure."
    ),
)

STANDARD_TASKS = ("lift", "place", "release", "rotate", "free", "shake", "excite-tx", "excite-ty", "excite-tz", "excite-rx",
                  "excite-ry", "excite-rz")
STANDARD_DRAW_SEED = 2026  # seeds the masses of the standard suite


def _grid_scenarios(first_seed: int, draw_seed: int, count: int = 48) -> tuple:
    """``count`` ten-second episodes: task i mod 12, user i mod 5, grasp (i div 5) mod 4, a mass
    drawn uniformly from the six by a generator seeded with ``draw_seed``, seed ``first_seed + i``."""

    masses = np.random.default_rng(draw_seed).integers(0, 6, count)
    return tuple(Scenario(task=STANDARD_TASKS[i % 12], user=i % 5, grasp=(i // 5) % 4, mass=int(masses[i]),
                          seed=first_seed + i) for i in range(count))


STANDARD_FIRST_SEED = 300  # the standard suite's scenario seeds: 300-347
DEV_FIRST_SEED = 500  # the dev suite's: 500-547
MASS_COUNT = 6  # the masses of sim_assets/masses.yaml the suites draw from


STANDARD_GATES = (  # the bar a method should reach away from the default lift (not tuned to pass)
    # version 5 (lab knowledge): version 3's 1.5 mm bar for the tracker plus the median box shift
    # that the lab's calibration alone predicts at the paper's view (a 1.5 px principal-point error
    # per axis at 212 px focal length and 0.55 m: 3.9 mm per image axis, median norm 4.6 mm), set
    # from that error model before standard v5 was measured
    Gate("box_pos_err_mm", "<=", 6.0),
    Gate("contact_err_mm_std", "<=", 4.0),
    Gate("contact_recall", ">=", 0.9),
    Gate("contact_precision", ">=", 0.9),
    Gate("acc_err_rms", "<=", 0.45),  # set on version 3 after measuring, so that zero kinematics fails its stage
    Gate("net_force_err_n_rms", "<=", 0.3),
    # the tail (standard v7, dev v6, cohort v4): one episode in ten may miss the net force by more than
    # 0.75 N (2.5 times the median's bar), set from dev (the tuning split: 0.45 N, bootstrap 0.31-0.72,
    # with the method's tail mends) before standard was measured; more than one episode in ten over
    # it fails (standard v6's reference: 1.07 N)
    Gate("net_force_err_n_rms", "<=", 0.75, statistic="p90"),
    Gate("least_violation_frac", "<=", 0.01, statistic="mean"),
    Gate("learned_rel_err_pct", "<=", 15.0),
)
"""The gates of ``standard``, ``dev`` and ``cohort``: version 3's, kept for version 4 before measuring
it; version 5 widened the box's for the lab's calibration (above), before measuring; version 7 (dev 6,
cohort 4) added the tail's."""

STANDARD = Suite(
    name="standard",
    version=8,  # 8: a guarded set-down, grasp trials on light boxes; 7: drawn margins, the tail's gate
    scenarios=split_scenarios("test", STANDARD_TASKS, 4, seed=STANDARD_FIRST_SEED, masses=MASS_COUNT),
    gates=STANDARD_GATES,
    description=(
        "The headline: 48 ten-second episodes over every task (the six manipulations and the six "
        "excitations, four each), each with its own person, grasp and camera view from the test split "
        "(people, grasps and views 500-547: never used for training or for choosing anything), masses "
        "drawn at random, seeds 300-347; the whole method from 1 cm depth noise, under the blind protocol "
        "(the calibrated one beside it on the leaderboard) and lab knowledge (exact knowledge beside it). "
        "Its gates are the bar a method should reach (box 6 mm with the lab's calibration, contact std 4 mm, "
        "net force 0.3 N (0.75 N for one episode in ten), 1 % least-violation frames, learned forces 15 %), set before measuring, not to "
        "make the reference pass."
    ),
)

COHORT = Suite(
    name="cohort",
    version=5,  # 5: a guarded set-down, grasp trials on light boxes; 4: drawn margins, the tail's gate
    scenarios=_grid_scenarios(STANDARD_FIRST_SEED, STANDARD_DRAW_SEED),
    gates=STANDARD_GATES,
    description=(
        "Within the named cohort (standard version 3): 48 ten-second episodes over every task, every "
        "named user (0-4) and grasp (0-3) on the paper's view, masses drawn at random, seeds 300-347. "
        "The shipped model never trains on these people; the suite asks how the method does on "
        "people it may have been tuned for, beside `standard`, which asks it on people never met."
    ),
)

DEV = Suite(
    name="dev",
    version=7,  # 7: a guarded set-down, grasp trials on light boxes; 6: drawn margins, the tail's gate
    scenarios=split_scenarios("dev", STANDARD_TASKS, 4, seed=DEV_FIRST_SEED, masses=MASS_COUNT),
    gates=STANDARD_GATES,
    description=(
        "For tuning and choosing methods: the standard suite's design (48 ten-second episodes, every task, "
        "each with its own person, grasp and view) on the dev split (people, grasps and views 100-147), "
        "seeds 500-547, with its gates. Choose parameters and models on `dev`, report them on `standard`, "
        "whose people, grasps, views and seeds no choice has seen."
    ),
)

TABLE1_TASKS = tuple(f"excite-{a}" for a in ("tx", "ty", "tz", "rx", "ry", "rz"))
TABLE1_SEEDS = (0, 1, 2)

TABLE1 = Suite(
    name="table1",
    version=3,  # 3: the camera sees the person's skin (benchmark.world.skin), not the primitives
    scenarios=tuple(Scenario(task=t, seed=s) for t in TABLE1_TASKS for s in TABLE1_SEEDS),
    gates=(  # the paper's Table 1, algebraic row (real AHRS, real tracker): standard deviations of the errors
        Gate("acc_err_rms", "<=", 0.904),
        Gate("gyro_err_rms", "<=", 1.241),
    ),
    description=(
        "The paper's Table 1 protocol: the six one-axis excitations (translation and rotation along x, y, "
        "z), 10 s each, seeds 0-2, 1 cm depth noise; the box's acceleration and angular velocity in the "
        "frame of an AHRS fixed to it, against the simulated AHRS. The same episodes as "
        "`python -m benchmark.commands.table1 --score --seeds 0,1,2` (results/table1), which compares the three "
        "differentiators on them. Gates: the paper's algebraic errors (0.904 m/s^2, 1.241 rad/s)."
    ),
)

TABLE2 = Suite(
    name="table2",
    version=4,  # 4: the camera sees the person's skin (benchmark.world.skin), not the primitives
    scenarios=tuple(Scenario(task="lift", user=u, grasp=g, mass=m, seed=s)
                    for u in (0, 4) for g in (0, 1) for m in (1, 4) for s in range(6)),
    gates=(  # the paper's Table 2 with full training: 9.7-10.9 %, under its sample rule
        Gate("learned_rel_err_pct_paper", "<=", 10.9),
    ),
    description=(
        "The paper's Table 2 cohort: lifts by users 0 and 4 with grasps 0-1, masses 1 and 4, seeds 0-5 "
        "(the episodes of `fsv-bench table2`'s dataset, which trains and tests by cross-validation). Here "
        "the method's own internal-force model is scored on them (the shipped one was trained on other "
        "users, masses and seeds). Gate: the paper's full-training error, 10.9 %, on the frames the paper's "
        "sample rule keeps (its protocol)."
    ),
)

SUITES = {s.name: s for s in (SMOKE, STANDARD, DEV, COHORT, TABLE1, TABLE2)}
"""Every registered suite by name."""


def get_suite(name: str, sensor: str | None = None, hand_surface: str | None = None,
              grip_control: str | None = None) -> Suite:
    """The suite registered as ``name``, seen by the depth sensor ``sensor``, with the hand drawn as
    ``hand_surface`` and the grip controlled by ``grip_control``, where given.

    Args:
        name: A key of :data:`SUITES`.
        sensor: A preset of ``benchmark.camera.sensor.SENSORS`` replacing every scenario's
            sensor; the suite is then named ``<name>-<sensor>`` (its own cache and scores).
        hand_surface: One of ``benchmark.world.scenario.HAND_SURFACES`` replacing every
            scenario's; the suite is then named ``<name>-<hand_surface>`` (after the sensor).
        grip_control: One of ``benchmark.world.scenario.GRIP_CONTROLS`` replacing every
            scenario's; the suite is then named ``<name>-<grip_control>`` (after the above).

    Raises:
        ValueError: Naming the accepted suites, sensors, hand surfaces or grip controls.
    """
    if name not in SUITES:
        raise ValueError(f"--suite {name!r}: no such suite; accepted: {', '.join(SUITES)}")

    from benchmark.camera.sensor import SENSORS  # lazy: numba (0.2 s) off `fsv-bench sweep`'s start-up

    overrides = (("sensor", "--sensor", sensor, SENSORS, "Seen by the {} sensor preset."),
                 ("hand_surface", "--hand-surface", hand_surface, HAND_SURFACES, "The hand drawn as its {}."),
                 ("grip_control", "--grip-control", grip_control, GRIP_CONTROLS, "The grip controlled {}."))
    for _, flag, value, accepted, _ in overrides:
        if value is not None and value not in accepted:
            what = "no such sensor; " if flag == "--sensor" else ""
            raise ValueError(f"{flag} {value!r}: {what}accepted: {', '.join(accepted)}")
    suite = SUITES[name]
    for field, _, value, _, sentence in overrides:
        if value is not None and not all(getattr(sc, field) == value for sc in suite.scenarios):
            suite = Suite(name=f"{suite.name}-{value}", version=suite.version,
                          scenarios=tuple(replace(sc, **{field: value}) for sc in suite.scenarios), gates=suite.gates,
                          description=f"{suite.description} {sentence.format(value)}")
    return suite
