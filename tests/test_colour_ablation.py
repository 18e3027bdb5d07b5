"""The colour ablation: the depth-only reference and the skin-gated example under each appearance
variant, scored as the method run end to end would be; the table's rows, tones and verdict."""

import importlib.util
import json
import pathlib
import shutil
import sys

import numpy as np
import pytest
from tiny_suite import TINY

from benchmark.camera.appearance import appearance_of, skin_of
from benchmark.camera.colour import render_colour
from benchmark.commands import colour_ablation as ca
from benchmark.method import run_method
from benchmark.method.run import camera_input_and_knowledge
from benchmark.method.spec import MethodSpec
from benchmark.scores.episode import score_episode
from benchmark.suites import SUITES
from benchmark.suites.evaluate import cached_episode

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def run(tmp_path_factory, tiny_episode_folder):
    """The command on the tiny suite (one 1.5 s lift): its folder, document and cache (which held the
    episode's depth: the command rendered its colour variants)."""
    base = tmp_path_factory.mktemp("colour_ablation")
    out, cache = base / "out", shutil.copytree(tiny_episode_folder, base / "cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(SUITES, "tiny", TINY)
        assert ca.main(["--suite", "tiny", "--out", str(out), "--cache", str(cache), "--quiet"]) == 0
    doc = json.loads((out / "colour_ablation.json").read_text(),
                     parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))
    return out, doc, cache


def _example_method():
    """examples/skin_colour.py's method, loaded here on its own (not through the command)."""
    spec = importlib.util.spec_from_file_location("skin_colour_for_test", ROOT / "examples" / "skin_colour.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module.method


def test_the_table_has_the_reference_and_every_variant_and_the_tone_of_the_person(run):
    out, doc, _ = run
    md = (out / "colour_ablation.md").read_text()
    names = [ca.REFERENCE] + [f"skin-gated, {v.name}" for v in ca.VARIANTS]
    assert [r["row"] for r in doc["rows"]] == names
    assert [v["name"] for v in doc["variants"]] == ["drawn", "skin-fixed", "print-off", "texture-off", "light-fixed",
                                                   "all-plain"]
    for name in names:
        assert f"| {name} |" in md
    tone = skin_of(TINY.scenarios[0].user)[0]
    assert [t["skin_tone"] for t in doc["tones"]] == [tone] and len(doc["boards"]) == 1 and f"\n| {tone} | 1 | {TINY.scenarios[0].user} |" in md
    assert doc["verdict"]["answer"] in ("helps", "hurts", "mixed", "no difference shown")
    assert "Does skin colour help" in md and doc["provenance"] and len(doc["episodes"]) == 1
    for r in doc["rows"]:  # one episode: every median is that episode's value, its interval the value itself
        a = r["contact_recall"]["median"]
        assert a["n"] == 1 and a["ci_low"] == a["value"] == a["ci_high"]


def test_the_rows_are_what_the_methods_score_run_end_to_end(run):
    """The reference and the skin-gated example under all-plain, each run whole on the episode here:
    the command's one shared tracking, its variant and its scoring give the same numbers."""
    _, doc, cache = run
    episode, rendered = cached_episode(TINY, TINY.scenarios[0], cache)
    assert not rendered
    e = doc["episodes"][0]
    inputs, known = camera_input_and_knowledge(episode)
    ref = score_episode(episode, run_method(MethodSpec(), episode, inputs=inputs), known.world_from_method)
    plain = appearance_of(episode.scenario).ablated(skin_tone=5, box_print=False, table_texture=False,
                                                    fixed_lighting=True)
    frames = render_colour(episode, appearance=plain)
    seen = episode.with_colour(frames.video, frames.labels)
    inputs_c, known_c = camera_input_and_knowledge(seen)
    gated = score_episode(seen, _example_method()(inputs_c, episode.scenario.rng("tracker")), known_c.world_from_method)
    for m in ("contact_precision", "contact_recall", "net_force_err_n_rms", "learned_rel_err_pct"):
        assert e["reference"][m] == pytest.approx(ref[m], rel=0, abs=0), m
        assert e["variants"]["all-plain"][m] == pytest.approx(gated[m], rel=0, abs=0), m
    assert doc["rows"][-1]["contact_recall"]["median"]["value"] == gated["contact_recall"]
    g = e["variants"]["all-plain"]["gate"]
    assert g["true_found"] + g["false_found"] > 0 and g["true_kept"] <= g["true_found"]


def test_the_gate_is_the_examples_rule(run, monkeypatch):
    """The example's rule asking for more skin pixels than its window holds: the gate keeps no
    contact; what the gated method still recalls are the pads near the surface that the forces stage
    takes on frames where nothing touches a lifted box (measured 0.71 against the reference's 1.0)."""
    _, _, cache = run
    episode, _ = cached_episode(TINY, TINY.scenarios[0], cache)
    module = type(ca.skin_method().tracker).__call__.__globals__  # the loaded example's globals
    monkeypatch.setitem(module, "MIN_SKIN_PIXELS", (2 * module["SEARCH_PX"] + 1) ** 2 + 1)
    monkeypatch.setattr(ca, "VARIANTS", ca.VARIANTS[:1])
    found = ca.ablate_episode(episode)
    g = found["variants"]["drawn"]["gate"]
    assert g["true_found"] > 0 and g["true_kept"] == 0 and g["false_kept"] == 0
    gated, reference = found["variants"]["drawn"]["contact_recall"], found["reference"]["contact_recall"]
    assert reference > 0.9 and (np.isnan(gated) or gated < reference - 0.15)


def test_gate_counts_split_the_trackers_contacts_by_the_truth():
    truth = np.array([[1, 1, 0], [0, 1, 0]], bool)
    before = np.array([[1, 1, 1], [1, 1, 0]], bool)
    after = np.array([[1, 0, 1], [0, 0, 0]], bool)
    assert ca.gate_counts(truth, before, after) == {"true_found": 3, "true_kept": 1, "false_found": 2, "false_kept": 1}
    with pytest.raises(Exception, match="added a contact"):
        ca.gate_counts(truth, before & ~truth, after)


def _episode(name, tone, ref_recall, gated_recall, kept=(4, 4, 2, 1)):
    metrics = lambda r: {"contact_recall": r, "contact_precision": 0.9, "net_force_err_n_rms": 0.3}  # noqa: E731
    gate = dict(zip(("true_found", "true_kept", "false_found", "false_kept"), kept))
    return {"episode": name, "skin_tone": tone, "box_board": "kraft", "scenario": {"user": tone * 100}, "reference": metrics(ref_recall),
            "variants": {v.name: {**metrics(gated_recall), "gate": gate} for v in ca.VARIANTS}}


def test_rows_tones_and_verdict_from_the_episodes():
    eps = [_episode(f"e{i}", 1 + i % 2, 0.9, 0.9 - 0.1 * (i + 1)) for i in range(8)]
    eps.append(_episode("nan", 2, 0.9, float("nan"), kept=(5, 0, 0, 0)))  # no contact kept: recall at its worst, 0
    rows = ca.summary_rows(eps)
    drawn = rows[1]
    assert drawn["row"] == "skin-gated, drawn" and drawn["worst"] == {"episode": "nan", "contact_recall": 0.0}
    assert rows[0]["worst"]["contact_recall"] == 0.9 and "paired" not in rows[0]
    assert drawn["contact_recall"]["median"]["value"] == pytest.approx(0.4)  # 0.8 .. 0.1 and 0: median 0.4
    assert drawn["gate"]["true_found"] == 37 and drawn["gate"]["true_kept_share"] == pytest.approx(32 / 37)
    assert drawn["paired"]["contact_recall"]["n"] == 9 and drawn["paired"]["contact_recall"]["p"] < 0.01
    tones = ca.tone_rows(eps)
    assert [(t["skin_tone"], t["episodes"]) for t in tones] == [(1, 4), (2, 5)]
    assert tones[0]["gated_contact_recall"]["value"] == pytest.approx(np.median([0.8, 0.6, 0.4, 0.2]))
    assert ca.verdict(eps)["answer"] == "hurts"
    assert ca.verdict([_episode(f"e{i}", 1, 0.5, 0.5 + 0.05 * (i + 1)) for i in range(8)])["answer"] == "helps"
    assert ca.verdict([_episode(f"e{i}", 1, 0.5, 0.5) for i in range(8)])["answer"] == "no difference shown"


def test_the_board_is_the_drawn_one():
    from benchmark.world.scenario import Scenario

    boards = [ca.box_board(Scenario(task="lift", seed=s)) for s in range(12)]
    assert set(boards) == {"kraft", "white"}  # half each, drawn
    sc = Scenario(task="lift", seed=boards.index("kraft"))
    base = appearance_of(sc).box_base[0]
    assert base[2] / base[0] < 0.5  # kraft is brown: little blue (white board: about 0.86)


@pytest.mark.parametrize("argv, needle", [
    (["--suite", "nope"], "no such suite"),
    (["--workers", "0"], "expected an integer"),
    (["--every", "0"], "expected an integer"),
    (["--first", "48"], "the suite has 48 episodes"),
])
def test_bad_options_exit_2_before_any_work(argv, needle, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        ca.main([*argv, "--out", str(tmp_path / "o"), "--cache", str(tmp_path / "c")])
    assert e.value.code == 2 and needle in capsys.readouterr().err


def test_the_cache_inside_the_output_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        ca.main(["--out", str(tmp_path / "o"), "--cache", str(tmp_path / "o" / "c")])
    assert e.value.code == 2 and "one inside the other" in capsys.readouterr().err
