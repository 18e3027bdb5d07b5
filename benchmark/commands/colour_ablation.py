"""The colour ablation (issue 44): ``python -m benchmark.commands.colour_ablation --suite dev``.

Does skin colour help the reference's contacts, and which source of appearance does a colour method
meet? Per episode of the suite (read from the episode cache; the colour is rendered here, never
cached):

* the reference tracker runs once, on the depth, under the default (lab) knowledge, drawing from
  the scenario's ``"tracker"`` stream: the **depth-only reference** is the rest of the reference
  method (:meth:`fsv.method.Method.after_tracking`) on that tracking;
* for each appearance variant (:data:`VARIANTS`: the world as drawn, then one source of appearance
  held fixed at a time, then all of them) the colour is rendered
  (:func:`benchmark.camera.colour.render_colour`; its noise from the scenario's ``"colour"`` stream,
  the same in every variant), and the same tracking is **skin-gated**: each contact kept only where
  the colour shows skin around it, by the example method ``examples/skin_colour.py`` itself (its
  tracker's rule on the shared tracking, then its stages after tracking, which are the reference's),
  so the drawn variant's row is what ``fsv-bench eval --method examples/skin_colour.py:method``
  scores.

Every estimate is scored by :func:`benchmark.scores.episode.score_episode` (contacts, and the
forces downstream of them: the contacts change the force programs). ``colour_ablation.md`` has one
row per method and variant (medians with 95 % bootstrap intervals over the episodes, the paired
difference from the depth-only reference with Wilcoxon's p, what the gate kept of the tracker's true
and false contacts, the worst episode) and, for the drawn variant, one row per Monk skin tone;
``colour_ablation.json`` has every value and the provenance. Choose on ``dev``; nothing here is
chosen on ``standard``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import pathlib
import time
from dataclasses import asdict, dataclass

import numpy as np

from benchmark.atomic import OutputFolderError, check_cache, check_out, write_folder
from benchmark.camera.appearance import _KRAFT, _WHITE_BOARD, appearance_of, hex_to_linear, skin_of
from benchmark.camera.colour import render_colour
from benchmark.commands.parser import OneLineParser
from benchmark.errors import BenchmarkError
from benchmark.limits import MAX_WORKERS, integer
from benchmark.method.load import load_object
from benchmark.method.run import camera_input_and_knowledge
from benchmark.method.spec import MethodSpec
from benchmark.parallel import run_jobs
from benchmark.scores.aggregate import FEW_EPISODES, aggregate, paired_test
from benchmark.scores.episode import score_episode
from benchmark.scores.metrics import WORST
from benchmark.suites import get_suite
from benchmark.suites.compare import paired_difference
from benchmark.suites.evaluate import cached_episode, default_cache, episode_cache, strict
from benchmark.world.grasp_plan import grasp_spec
from benchmark.world.scenario import episode_name
from fsv.provenance import provenance

SKIN_METHOD = "examples/skin_colour.py:method"
"""The skin-gated method, relative to the repository's root: the example's own code measured, so
the benchmark holds no second copy of its rule (and ``benchmark`` imports nothing of ``examples``)."""

SKIN_FIXED_TONE = 5
"""The Monk tone every person gets where the skin is held fixed: the middle of the scale (1..10;
5 rather than 6, a stated choice), the swatch unjittered."""


@dataclass(frozen=True)
class Variant:
    """One appearance under which the colour is rendered: the scenario's own
    (:func:`benchmark.camera.appearance.appearance_of`) with some sources held fixed
    (:meth:`benchmark.camera.appearance.Appearance.ablated`)."""

    name: str
    holds: str
    skin_tone: int | None = None
    box_print: bool = True
    table_texture: bool = True
    fixed_lighting: bool = False

    def appearance(self, drawn):
        """The variant of the scenario's drawn ``Appearance``."""
        return drawn.ablated(skin_tone=self.skin_tone, box_print=self.box_print, table_texture=self.table_texture,
                             fixed_lighting=self.fixed_lighting)


VARIANTS = (
    Variant("drawn", "nothing (the world as drawn)"),
    Variant("skin-fixed", f"skin: every person Monk {SKIN_FIXED_TONE}", skin_tone=SKIN_FIXED_TONE),
    Variant("print-off", "box: its print off (the bare board)", box_print=False),
    Variant("texture-off", "table: its grain off (its base colour)", table_texture=False),
    Variant("light-fixed", "lighting: one 4500 K key light and ambient, the same in every scenario", fixed_lighting=True),
    Variant("all-plain", "all four", skin_tone=SKIN_FIXED_TONE, box_print=False, table_texture=False,
            fixed_lighting=True),
)
"""The appearance variants, each one source of appearance difficulty held fixed so its effect is
measured alone against ``drawn``, and all of them at once (``all-plain``)."""

REFERENCE = "depth-only reference"
METRICS = ("contact_precision", "contact_recall", "net_force_err_n_rms")
"""The metrics of the table (every metric of :func:`score_episode` is in the JSON)."""
HIGHER_IS_BETTER = ("contact_precision", "contact_recall")
ALPHA = 0.05


def repository_root() -> pathlib.Path:
    """The folder holding ``benchmark/`` and ``examples/``."""
    return pathlib.Path(__file__).resolve().parents[2]


@functools.lru_cache(maxsize=1)
def skin_method():
    """The example's skin-gated method (``fsv.method.Method``; its tracker a ``SkinConfirmedTracker``),
    loaded once per process.

    Raises:
        ValueError: One line, where the example cannot be loaded (e.g. no ``examples/`` beside the package).
    """
    path, _, attribute = SKIN_METHOD.partition(":")
    method = load_object(f"{repository_root() / path}:{attribute}", "the skin-gated method")
    if not dataclasses.is_dataclass(getattr(method, "tracker", None)) or not hasattr(method.tracker, "inner"):
        raise ValueError(f"{SKIN_METHOD}: expected a method whose tracker confirms an inner tracker's contacts")
    return method


@dataclass(frozen=True)
class _Tracked:
    """A tracker that returns a tracking already made (the reference's, shared by every variant)."""

    tracking: object

    def __call__(self, inputs, rng):
        return self.tracking


def gate_counts(truth_active, before, after) -> dict:
    """What the skin gate did to the tracker's contacts, finger-frames (T, K) bool each.

    Returns:
        ``true_found`` (tracker and truth in contact), ``true_kept`` (of those, kept by the gate),
        ``false_found`` (tracker in contact, truth not), ``false_kept``; ints.
    """
    t, b, a = (np.asarray(x, bool) for x in (truth_active, before, after))
    if not np.all(a <= b):
        raise BenchmarkError("the skin gate added a contact: it may only remove the tracker's contacts")
    return {"true_found": int((b & t).sum()), "true_kept": int((a & t).sum()),
            "false_found": int((b & ~t).sum()), "false_kept": int((a & ~t).sum())}


def ablate_episode(episode) -> dict:
    """The depth-only reference and the skin-gated method under every variant on one episode.

    Args:
        episode: A rendered ``benchmark.Episode`` with its depth (its colour, if any, is not used).

    Returns:
        ``{"reference": metrics, "variants": {name: {**metrics, "gate": gate_counts}}}``, the
        metrics those of :func:`score_episode`.
    """
    sc = episode.scenario
    spec = MethodSpec()
    inputs, known = camera_input_and_knowledge(episode, 1.0, spec.knowledge, spec.protocol)
    reference = spec.build()
    tracking = reference.track(inputs, sc.rng("tracker"))
    out = {"reference": score_episode(episode, reference.after_tracking(inputs, tracking), known.world_from_method),
           "variants": {}}
    skin = skin_method()
    confirm = dataclasses.replace(skin.tracker, inner=_Tracked(tracking))
    drawn = appearance_of(sc)
    for v in VARIANTS:
        frames = render_colour(episode, appearance=v.appearance(drawn))
        seen = episode.with_colour(frames.video, frames.labels)
        del frames
        inputs_c, known_c = camera_input_and_knowledge(seen, 1.0, spec.knowledge, spec.protocol)
        gated = confirm(inputs_c, sc.rng("tracker"))
        estimate = skin.after_tracking(inputs_c, gated)
        out["variants"][v.name] = {
            **score_episode(seen, estimate, known_c.world_from_method),
            "gate": gate_counts(episode.truth.contact_active, tracking.contacts.active, gated.contacts.active)}
        del seen, inputs_c, estimate
    return out


def _episode(job) -> dict:
    """One episode from the cache, ablated (a worker's unit of work)."""
    suite, scenario, cache = job
    t0 = time.perf_counter()
    episode, _ = cached_episode(suite, scenario, cache)
    return {**ablate_episode(episode), "seconds": time.perf_counter() - t0}


def colour_ablation(suite, *, cache=None, workers: int = 1, every: int = 1, first: int = 0) -> dict:
    """Every ``every``-th episode of ``suite`` from its ``first`` (``every`` 1, ``first`` 0: all)
    ablated (:func:`ablate_episode`), and the summary rows (:func:`summary_rows`,
    :func:`tone_rows`, :func:`verdict`)."""
    from benchmark.commands.colour_ablation import _episode as job  # lazy: by its module's name, also as __main__

    cache = episode_cache(cache)
    scenarios = suite.scenarios[first::every]
    found = dict(run_jobs(job, [(suite, sc, cache) for sc in scenarios], workers=workers))
    episodes = []
    for i, sc in enumerate(scenarios):
        episodes.append({"episode": episode_name(sc), "scenario": asdict(sc), "grasp_family": grasp_spec(sc)["family"],
                         "skin_tone": skin_of(sc.user)[0], "box_board": box_board(sc), **found[i]})
    return {"suite": {"name": suite.name, "version": suite.version, "episodes": len(suite.scenarios), "every": every,
                      "first": first},
            "skin_method": SKIN_METHOD,
            "variants": [asdict(v) for v in VARIANTS], "skin_fixed_tone": SKIN_FIXED_TONE,
            "rows": summary_rows(episodes), "tones": tone_rows(episodes),
            "boards": group_rows(episodes, "box_board"), "verdict": verdict(episodes),
            "episodes": episodes}


def _values(episodes, variant, metric) -> list:
    """One value per episode of ``metric`` for the reference (``variant`` None) or the skin-gated
    method under ``variant``; None where it could not be computed (NaN in process, null in the JSON)."""
    values = [(e["reference"] if variant is None else e["variants"][variant])[metric] for e in episodes]
    return [None if v is None or np.isnan(v) else v for v in values]


def _pooled(episodes, variant) -> dict:
    """The gate's counts summed over ``episodes``, and the shares kept (None where nothing was found)."""
    total = {k: sum(e["variants"][variant]["gate"][k] for e in episodes)
             for k in ("true_found", "true_kept", "false_found", "false_kept")}
    share = lambda kept, found: kept / found if found else None  # noqa: E731
    return {**total, "true_kept_share": share(total["true_kept"], total["true_found"]),
            "false_kept_share": share(total["false_kept"], total["false_found"])}


def _worst(episodes, variant) -> dict:
    """The episode with the lowest contact recall (a missing recall counts at 0)."""
    recall = [WORST["contact_recall"] if v is None else v for v in _values(episodes, variant, "contact_recall")]
    i = int(np.argmin(recall))
    return {"episode": episodes[i]["episode"], "contact_recall": recall[i]}


def _paired_test(episodes, variant, metric) -> dict:
    """:func:`paired_test` of the skin-gated method under ``variant`` minus the reference, per
    episode (a missing value at the metric's worst), with the mean of the finite differences."""
    d = [paired_difference(a, b, WORST[metric])
         for a, b in zip(_values(episodes, None, metric), _values(episodes, variant, metric))]
    finite = [x for x in d if x is not None and np.isfinite(x)]
    return {**paired_test(d), "mean_diff": float(np.mean(finite)) if finite else None}


def summary_rows(episodes: list) -> list:
    """One row per method: the depth-only reference, then the skin-gated method under each variant.

    Each row: ``{"row", "variant", metric: {"median": aggregate, "mean": aggregate} for :data:`METRICS`,
    "paired": {metric: paired_test of (row - reference)}, "gate": pooled counts, "worst": episode}``.
    """
    rows = []
    for variant in (None, *[v.name for v in VARIANTS]):
        row = {"row": REFERENCE if variant is None else f"skin-gated, {variant}", "variant": variant}
        for m in METRICS:
            row[m] = {s: aggregate(_values(episodes, variant, m), s, WORST[m]) for s in ("median", "mean")}
        if variant is not None:
            row["paired"] = {m: _paired_test(episodes, variant, m) for m in METRICS}
            row["gate"] = _pooled(episodes, variant)
        row["worst"] = _worst(episodes, variant)
        rows.append(row)
    return rows


def box_board(scenario) -> str:
    """The scenario's box board, ``"kraft"`` or ``"white"`` (:func:`appearance_of` draws one of the two
    and scales its lightness: the nearer in chromaticity)."""
    base = appearance_of(scenario).box_base[0]
    chroma = lambda rgb: np.asarray(rgb) / np.sum(rgb)  # noqa: E731
    kraft, white = (float(np.abs(chroma(base) - chroma(hex_to_linear(h))).sum()) for h in (_KRAFT, _WHITE_BOARD))
    return "kraft" if kraft < white else "white"


def tone_rows(episodes: list, variant: str = "drawn") -> list:
    """Per Monk tone present in ``episodes`` (:func:`group_rows` by ``skin_tone``)."""
    return group_rows(episodes, "skin_tone", variant)


def group_rows(episodes: list, key: str, variant: str = "drawn") -> list:
    """Per value of ``key`` in ``episodes`` (``skin_tone``, ``box_board``): the skin-gated method under
    ``variant`` (the world as drawn: ``drawn``) beside the depth-only reference on the same episodes."""
    rows = []
    for value in sorted({e[key] for e in episodes}):
        group = [e for e in episodes if e[key] == value]
        rows.append({key: value, "episodes": len(group), "users": sorted({e["scenario"]["user"] for e in group}),
                     **{f"{who}_{m}": aggregate(_values(group, v, m), "median", WORST[m])
                        for who, v in (("reference", None), ("gated", variant))
                        for m in ("contact_recall", "contact_precision")},
                     "gate": _pooled(group, variant)})
    return rows


def verdict(episodes: list, variant: str = "drawn") -> dict:
    """Whether skin colour helps the reference's contacts: under ``variant`` (the world as drawn,
    what a colour method meets), the paired differences from the depth-only reference. It helps
    when precision or recall rises (Wilcoxon p < :data:`ALPHA`, positive mean difference) and
    neither falls so; it hurts when one falls so and neither rises; otherwise no difference is
    shown."""
    tests = {m: _paired_test(episodes, variant, m) for m in ("contact_precision", "contact_recall")}
    up = [m for m, t in tests.items() if t["p"] is not None and t["p"] < ALPHA and (t["mean_diff"] or 0) > 0]
    down = [m for m, t in tests.items() if t["p"] is not None and t["p"] < ALPHA and (t["mean_diff"] or 0) < 0]
    answer = "helps" if up and not down else "hurts" if down and not up else "mixed" if up else "no difference shown"
    return {"variant": variant, "answer": answer, "tests": tests}


def _ci(a: dict, fmt: str = "{:.3f}") -> str:
    if a["value"] is None:
        return "—"
    v = fmt.format(a["value"])
    return v if a["ci_low"] == a["ci_high"] else f"{v} [{fmt.format(a['ci_low'])}, {fmt.format(a['ci_high'])}]"


def _kept(gate: dict, which: str) -> str:
    """``"97.1 % of 1352"``: the share of the tracker's true or false contacts the gate kept."""
    found = gate[f"{which}_found"]
    return "none found" if not found else f"{100 * gate[f'{which}_kept_share']:.1f} % of {found}"


def _paired(t: dict) -> str:
    if t["mean_diff"] is None:
        return "—"
    p = "too few differ" if t["p"] is None else f"p {t['p']:.2g}"
    return f"{t['mean_diff']:+.4f} ({p}, {t['n']} differ)"


def report_markdown(doc: dict) -> str:
    """``colour_ablation.md``: the verdict, the method rows, the tone rows."""
    s = doc["suite"]
    n = doc["rows"][0]["contact_recall"]["median"]["n"]
    few = " (few episodes: the intervals are little more than the range)" if n < FEW_EPISODES else ""
    v = doc["verdict"]
    tests = "; ".join(f"{m.replace('contact_', '')}: mean difference {t['mean_diff']:+.4f}, "
                      + ("too few differing episodes for a test" if t["p"] is None else f"Wilcoxon p {t['p']:.2g}")
                      + f" ({t['n']} of {n} episodes differ)"
                      for m, t in v["tests"].items() if t["mean_diff"] is not None)
    subset = "" if n == s["episodes"] else f" of {s['episodes']} (one in {s['every']}, from episode {s['first']})"
    runs = doc.get("runs") or []
    merged = f" (from {len(runs)} runs over disjoint episodes, merged: `runs` in the JSON)" if len(runs) > 1 else ""
    lines = [f"# Colour ablation: suite {s['name']} v{s['version']}, {n} episodes{subset}{merged}{few}", "",
             f"The reference tracker once per episode on the depth (lab knowledge); `{REFERENCE}` is the reference "
             f"method on it, `skin-gated` the same tracking with each contact kept only where the colour image shows "
             f"skin around it ({doc['skin_method']}: Chai & Ngan's fixed YCbCr rule), then the reference's stages "
             "after tracking. Each variant renders the colour with one source of appearance held fixed "
             f"(skin: Monk {doc['skin_fixed_tone']}, unjittered); the colour noise is the same in every variant.", "",
             f"**Does skin colour help the reference's contacts on {s['name']}?** {v['answer']} "
             f"(skin-gated under `{v['variant']}` against `{REFERENCE}`; {tests or 'no paired differences'}).", "",
             "Medians over episodes with 95 % bootstrap intervals; Δ: mean paired difference from the reference "
             "over the episodes (Wilcoxon's two-sided signed-rank p over those that differ); kept: the tracker's true / false contacts "
             "(finger-frames) the skin gate kept; worst: the lowest contact recall.", "",
             "| method | holds fixed | contact precision | contact recall | net force error [N] | Δ precision | "
             "Δ recall | Δ net force [N] | true contacts kept | false contacts kept | worst episode (recall) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    holds = {x["name"]: x["holds"] for x in doc["variants"]}
    for r in doc["rows"]:
        p, g = r.get("paired"), r.get("gate")
        lines.append(f"| {r['row']} | {'—' if r['variant'] is None else holds[r['variant']]} | "
                     f"{_ci(r['contact_precision']['median'])} | {_ci(r['contact_recall']['median'])} | "
                     f"{_ci(r['net_force_err_n_rms']['median'])} | "
                     + (" | ".join(_paired(p[m]) for m in METRICS) if p else "— | — | —") + " | "
                     + (f"{_kept(g, 'true')} | {_kept(g, 'false')}" if g else "— | —")
                     + f" | {r['worst']['episode']} ({r['worst']['contact_recall']:.3f}) |")
    lines += ["", "## By skin tone (Monk), the world as drawn", "",
              "A fixed YCbCr rule is known to miss darker and very light skin: per tone, the episodes of people "
              "drawn with it; medians (95 % bootstrap intervals where the tone has enough episodes to vary) and the "
              "tracker's true contacts the gate kept, pooled.", "",
              "| Monk tone | episodes | people | recall, reference | recall, skin-gated | precision, reference | "
              "precision, skin-gated | true contacts kept | false contacts kept |", "|---|---|---|---|---|---|---|---|---|"]
    for t in doc["tones"]:
        g = t["gate"]
        lines.append(f"| {t['skin_tone']} | {t['episodes']} | {', '.join(str(u) for u in t['users'])} | "
                     f"{_ci(t['reference_contact_recall'])} | {_ci(t['gated_contact_recall'])} | "
                     f"{_ci(t['reference_contact_precision'])} | {_ci(t['gated_contact_precision'])} | "
                     f"{_kept(g, 'true')} | {_kept(g, 'false')} |")
    lines += ["", "## By the box's board, the world as drawn", "",
              "The box is kraft or white-coated board (half each; benchmark/camera/appearance.py). The skin "
              "window around a contact also sees what is behind and beside the finger: the board and the table.", "",
              "| board | episodes | recall, reference | recall, skin-gated | precision, reference | precision, skin-gated | "
              "true contacts kept | false contacts kept |", "|---|---|---|---|---|---|---|---|"]
    for t in doc["boards"]:
        g = t["gate"]
        lines.append(f"| {t['box_board']} | {t['episodes']} | {_ci(t['reference_contact_recall'])} | "
                     f"{_ci(t['gated_contact_recall'])} | {_ci(t['reference_contact_precision'])} | "
                     f"{_ci(t['gated_contact_precision'])} | {_kept(g, 'true')} | {_kept(g, 'false')} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """``python -m benchmark.commands.colour_ablation``: writes colour_ablation.md and colour_ablation.json."""
    p = OneLineParser(prog="python -m benchmark.commands.colour_ablation", description=__doc__.splitlines()[0])
    p.add_argument("--suite", default="dev", help="suite whose episodes are ablated (default dev: choose there)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/colour_ablation"),
                   help="output folder, replaced whole if fsv-bench wrote it (default runs/colour_ablation)")
    p.add_argument("--cache", default=None, help="episode cache folder (default: fsv-bench's under the user's cache)")
    p.add_argument("--workers", type=integer(1, MAX_WORKERS), default=1,
                   help=f"local worker processes, 1 to {MAX_WORKERS}")
    p.add_argument("--every", type=integer(1, 1000), default=1,
                   help="ablate every N-th episode of the suite from the first (default 1: all; the dev suite "
                        "lists its tasks four episodes each, so 2 keeps every task twice)")
    p.add_argument("--first", type=integer(0, 1000), default=0, help="with --every: the first episode ablated (from 0)")
    p.add_argument("--quiet", action="store_true", help="print only where the ablation was written")
    args = p.parse_args(argv)
    try:
        suite = get_suite(args.suite)
        check_out(args.out)
        check_cache(args.cache or default_cache(), {"--out": args.out})
        skin_method()
    except (ValueError, OutputFolderError) as e:
        p.exit(2, f"{p.prog}: error: {e}\n")
    t0 = time.perf_counter()
    if args.first >= len(suite.scenarios):
        p.exit(2, f"{p.prog}: error: --first {args.first}: the suite has {len(suite.scenarios)} episodes\n")
    doc = colour_ablation(suite, cache=args.cache, workers=args.workers, every=args.every, first=args.first)
    doc["seconds"] = time.perf_counter() - t0
    doc["provenance"] = provenance()
    md = report_markdown(doc)
    write_folder(args.out, {"colour_ablation.md": md,
                            "colour_ablation.json": json.dumps(strict(doc), indent=1, allow_nan=False) + "\n"})
    if not args.quiet:
        print(md)
    print(f"written to {args.out}/ (colour_ablation.md, colour_ablation.json)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
