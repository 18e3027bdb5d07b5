"""``fsv-bench sweep``: one suite evaluated along one axis, each error plotted against it.

    fsv-bench sweep --suite smoke --axis noise --values 0.005,0.01,0.02 --out DIR [--workers N]
                    [--cache DIR] [--quiet] [--method/--tracker/--differentiator/... M]

Axes (:data:`AXES`): ``noise`` (depth noise standard deviation, m), ``mass`` (index into
sim_assets/masses.yaml), ``fps`` (camera frame rate, Hz), ``init`` (scale of the seeded first-frame
perturbation handed to the method, ``benchmark.method.init.INIT_PERTURBATION``), ``sensor`` (depth
sensor preset: ``ds325``, ``kinect-v1``, ``ideal``), ``hand_surface`` (``capsules``, the collision
primitives, ``skin``, ``benchmark.world.skin``, or ``skin-rigid``), ``grip_control`` (``whole-hand``
or ``per-digit``, ``benchmark.world.grip``), ``knowledge`` and ``protocol`` (what the method
is told). Every scenario of the
suite is run at every value (the rest of the scenario unchanged). ``DIR`` receives ``sweep.json``
(aggregates with 95 % intervals per value, provenance), ``sweep.md`` and ``sweep.png`` (median and
interval of each metric against the axis). The world has no friction axis.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import pathlib

import numpy as np

from benchmark.atomic import OUT_AS_IT_WAS_EPISODES_CACHED, check_out, save_figure, staged_folder
from benchmark.errors import ScenarioError
from benchmark.limits import MAX_EPISODES, MAX_INIT_SCALE, check_grid
from benchmark.suites import Suite, get_suite
from benchmark.world.scenario import GRIP_CONTROLS, HAND_SURFACES, MAX_FPS, MAX_NOISE_M, Scenario

INTERRUPTED = OUT_AS_IT_WAS_EPISODES_CACHED
"""What Ctrl-C leaves, as the interrupted command says it (`fsv-bench <sub-command>: interrupted; ...`)."""

AXES = {
    "noise": ("noise_m", float, "depth noise std [m]"),
    "mass": ("mass", int, "mass index (sim_assets/masses.yaml)"),
    "fps": ("fps", float, "frame rate [Hz]"),
    "init": (None, float, "first-frame perturbation scale"),
    "sensor": ("sensor", str, "depth sensor preset"),
    "hand_surface": ("hand_surface", str, "what the camera sees of the hand"),
    "grip_control": ("grip_control", str, "how the people control the grip"),
    "knowledge": (None, str, "what the method is told (benchmark.method.knowledge)"),
    "protocol": (None, str, "what the method is told of the person (benchmark.method.protocol)"),
}
"""Axis name -> (Scenario field, or None for what the method is given: its initialisation, its
knowledge or its protocol, type, label)."""

PLOTTED = ("box_pos_err_mm", "contact_err_mm_std", "acc_err_rms", "net_force_err_n_rms", "least_violation_frac",
           "learned_rel_err_pct")
"""The metrics drawn in ``sweep.png`` (every metric is in ``sweep.json``)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    from benchmark.suites.evaluate import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        add_method_arguments,
    )
    from benchmark.suites.options import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        add_suite_arguments,
    )

    add_suite_arguments(p, out_help="output folder (sweep.json, sweep.md, sweep.png)", sensor=False)
    p.add_argument("--axis", required=True, help=f"one of {', '.join(AXES)}")
    p.add_argument("--values", required=True,
                   help=f"comma-separated values along the axis, at least two distinct ones: noise 0 to {MAX_NOISE_M:g} "
                        f"m, fps {MIN_SWEEP_FPS:g} to {MAX_FPS:g} Hz, init 0 to {MAX_INIT_SCALE:g}, mass an index of "
                        "sim_assets/masses.yaml, the others one of their names; at most "
                        f"{MAX_EPISODES:,} episodes in all (suite x values)")
    add_method_arguments(p)


MIN_SWEEP_FPS = 10.0
"""Lowest frame rate of the ``fps`` axis [Hz]: the paper's camera runs at 30 Hz, and at 10 Hz the
differentiators' widest window (13 frames) already spans more than a second of a task's motion."""

RANGES = {"noise": (0.0, MAX_NOISE_M, "m"), "fps": (MIN_SWEEP_FPS, MAX_FPS, "Hz"), "init": (0.0, MAX_INIT_SCALE, "")}
"""The numeric axes' accepted values: (lowest, highest, unit), both included."""


def parse_values(axis: str, text: str) -> list:
    """The axis values of ``--values``, each checked (ValueError naming ``--values``, the bad value
    and what the axis accepts): at least two distinct values, numbers within :data:`RANGES`, indices
    that exist, names of the axis's choices."""
    if axis not in AXES:
        raise ValueError(f"--axis {axis!r}: accepted: {', '.join(AXES)}")
    kind = AXES[axis][1]
    items = str(text).split(",")
    if len(items) > MAX_EPISODES:
        raise ValueError(f"--values: {len(items):,} values, more than the {MAX_EPISODES:,} accepted")
    values = []
    for item in items:
        try:
            values.append(kind(item))
        except ValueError:
            raise ValueError(f"--values {text!r}: {item!r} is not a{'n integer' if kind is int else ' number'}") from None
    if len(set(values)) != len(values) or len(values) < 2:
        raise ValueError(f"--values {text!r}: need at least two distinct values")
    if axis in RANGES:
        low, high, unit = RANGES[axis]
        for v in values:
            if not (math.isfinite(v) and low <= v <= high):
                raise ValueError(f"--values {text!r}: {v!r} is outside the {axis} axis's range; accepted: numbers "
                                 f"from {low:g} to {high:g}{' ' + unit if unit else ''}")
    if axis in ("hand_surface", "grip_control"):
        accepted, what = (HAND_SURFACES, "a hand surface") if axis == "hand_surface" else (GRIP_CONTROLS, "a grip control")
        for v in values:
            if v not in accepted:
                raise ValueError(f"--values {text!r}: {v!r} is not {what}; accepted: {', '.join(accepted)}")
    if axis == "mass":
        from benchmark.world.assets import validate  # lazy: MuJoCo (0.25 s) off `fsv-bench sweep`'s start-up

        for v in values:
            try:
                validate(Scenario(mass=v))
            except ScenarioError as e:
                raise ValueError(f"--values {text!r}: {v!r} is not a mass index: {e}") from None
    if axis == "knowledge":
        from benchmark.method.knowledge import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
            check_knowledge,
        )

        for v in values:
            try:
                check_knowledge(v)
            except ValueError as e:
                raise ValueError(f"--values {text!r}: {v!r} is not a knowledge: {e}") from None
    if axis == "protocol":
        from benchmark.method.protocol import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
            check_protocol,
        )

        for v in values:
            try:
                check_protocol(v)
            except ValueError as e:
                raise ValueError(f"--values {text!r}: {v!r} is not a protocol: {e}") from None
    return values


def swept_suite(suite, axis: str, value):
    """The suite with every scenario moved to ``value`` along ``axis`` (itself for the ``init`` and
    ``knowledge`` and ``protocol`` axes, which change what the method is given)."""
    from benchmark.world.assets import validate  # lazy: MuJoCo (0.25 s) off `fsv-bench sweep`'s start-up

    field = AXES[axis][0]
    if field is None:
        return suite
    scenarios = tuple(dataclasses.replace(sc, **{field: value}) for sc in suite.scenarios)
    for sc in scenarios:
        validate(sc)
    return Suite(name=f"{suite.name}-{axis}-{value}", version=suite.version, scenarios=scenarios, gates=suite.gates,
                 description=f"{suite.name} with {AXES[axis][2]} = {value}")


def plot_sweep(axis: str, values: list, results: list, path) -> pathlib.Path:
    """Median [95 % interval] of each metric of :data:`PLOTTED` against the axis, one panel each."""
    import matplotlib  # lazy: matplotlib (0.4 s) off `fsv-bench sweep`'s start-up

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # lazy: matplotlib (0.4 s) off `fsv-bench sweep`'s start-up

    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5))
    categorical = AXES[axis][1] is str
    x = np.arange(len(values), dtype=float) if categorical else np.asarray(values, dtype=float)
    for ax, metric in zip(axes.ravel(), PLOTTED):
        stat = "mean" if metric == "least_violation_frac" else "median"
        aggs = [r["aggregate"][metric][stat] for r in results]
        v = np.array([a["value"] if a["value"] is not None else np.nan for a in aggs], float)
        lo = np.array([a["ci_low"] if a["ci_low"] is not None else np.nan for a in aggs], float)
        hi = np.array([a["ci_high"] if a["ci_high"] is not None else np.nan for a in aggs], float)
        v, lo, hi, beyond = _capped(v, lo, hi)
        ax.errorbar(x, v, yerr=[v - lo, hi - v], marker="o", capsize=3, color="tab:blue", label=f"{stat} [95 % CI]")
        if beyond.any():  # an aggregate at an episode's worst value (infinite): drawn at the axis' top
            ax.plot(x[beyond], v[beyond], "^", color="tab:red", ms=8)
        ax.set_title(metric + (" (▲: infinite, an episode counted at its worst)" if beyond.any() else ""), fontsize=9)
        ax.set_xlabel(AXES[axis][2], fontsize=8)
        if categorical:
            ax.set_xticks(x, [str(v) for v in values], fontsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=7)
    fig.suptitle(f"{results[0]['suite']['name']}: errors against {AXES[axis][2]} ({len(results[0]['episodes'])} episodes per value)",
                 fontsize=10)
    fig.tight_layout()
    out = save_figure(fig, path)
    plt.close(fig)
    return out


def _capped(v, lo, hi) -> tuple:
    """Median and interval bounds with their infinite values (episodes counted at their worst,
    docs/suites.md) replaced by a cap 15 % above the largest finite one, and which medians were
    capped: ``(v, lo, hi, beyond)``."""

    both = np.concatenate([v, lo, hi])
    finite = both[np.isfinite(both)]
    top = float(finite.max()) if finite.size else 1.0
    cap = top + 0.15 * max(abs(top), 1e-9)
    beyond = np.isposinf(v)
    return tuple(np.where(np.isposinf(a), cap, a) for a in (v, lo, hi)) + (beyond,)


def run(args: argparse.Namespace) -> dict:
    from benchmark.method.knowledge import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        DEFAULT_KNOWLEDGE,
    )
    from benchmark.method.protocol import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        DEFAULT_PROTOCOL,
    )
    from benchmark.suites.evaluate import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        check_cache_args,
        evaluate,
        spec_from_args,
        strict,
    )
    from fsv.provenance import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        provenance,
    )

    suite = get_suite(args.suite)
    values = parse_values(args.axis, args.values)
    check_grid({f"--suite {args.suite}": len(suite.scenarios), "--values": len(values)})
    try:
        suites = [swept_suite(suite, args.axis, v) for v in values]  # every scenario validated before any work
    except ScenarioError as e:
        raise ValueError(f"--values {args.values!r}: {e}") from None
    if args.workers < 1:
        raise ValueError(f"--workers {args.workers}: need at least 1 worker process")
    check_out(args.out)
    check_cache_args(args)
    spec = spec_from_args(args)
    from benchmark.method.protocol import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        check_people,
    )

    for protocol in (values if args.axis == "protocol" else [spec.protocol]):
        check_people((sc.user for sc in suite.scenarios), protocol)
    results = []
    for value, s in zip(values, suites):
        scale = value if args.axis == "init" else 1.0
        told = (dataclasses.replace(spec, **{args.axis: value}) if args.axis in ("knowledge", "protocol") else spec)
        results.append(evaluate(s, spec=told, cache=args.cache, progress=not args.quiet, workers=args.workers,
                                init_scale=scale))
        print(f"  {args.axis} = {value}: done ({results[-1]['seconds']:.0f} s)")
    from benchmark.method.run import (  # lazy: numba, clarabel, scipy.sparse, scipy.special (0.25 s) off `fsv-bench sweep`'s start-up
        method_label,
    )

    # the suite and the method swept (not the first value's: "dev", not "dev-noise-0.005"; the method
    # without the knowledge or protocol the sweep sets per value)
    base = dataclasses.replace(spec, knowledge=DEFAULT_KNOWLEDGE, protocol=DEFAULT_PROTOCOL) \
        if args.axis in ("knowledge", "protocol") else spec
    doc = {"suite": {"name": suite.name, "version": suite.version, "description": suite.description},
           "axis": args.axis, "label": AXES[args.axis][2], "values": values,
           "method": method_label(base), "stages": results[0]["stages"],
           "aggregate": [r["aggregate"] for r in results], "episodes": [r["episodes"] for r in results],
           "provenance": provenance()}
    out = pathlib.Path(args.out)
    with staged_folder(out) as tmp:
        (tmp / "sweep.json").write_text(json.dumps(strict(doc), indent=1, allow_nan=False) + "\n")
        (tmp / "sweep.md").write_text(sweep_markdown(doc))
        plot_sweep(args.axis, values, results, tmp / "sweep.png")
    print(sweep_markdown(doc))
    print(f"written to {out}/ (sweep.json, sweep.md, sweep.png)")
    return doc


def sweep_markdown(doc: dict) -> str:
    """A table: one row per axis value, the plotted metrics' medians (means for least violation) with intervals."""
    lines = [f"# Sweep of {doc['suite']['name']} along {doc['label']}", "", f"Method: {doc['method']}", "",
             f"| {doc['axis']} | " + " | ".join(PLOTTED) + " |", "|" + "---|" * (len(PLOTTED) + 1)]
    for value, agg in zip(doc["values"], doc["aggregate"]):
        cells = []
        for m in PLOTTED:
            a = agg[m]["mean" if m == "least_violation_frac" else "median"]
            cells.append("—" if a["value"] is None else f"{a['value']:.3g} [{a['ci_low']:.3g}, {a['ci_high']:.3g}]")
        lines.append(f"| {value} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
