"""Numbers the docs quote from the committed results are the committed results' numbers."""

import json
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _smoke(metric: str, statistic: str = "median") -> float:
    scores = json.loads((ROOT / "results/smoke/scores.json").read_text())
    return scores["aggregate"][metric][statistic]["value"]


QUOTES = [  # (document, text before the number, metric, statistic, format, text after)
    ("docs/suites.md", "box error median\n  ", "box_pos_err_mm", "median", "{:.2f}", " mm"),
    ("docs/suites.md", "contact std ", "contact_err_mm_std", "median", "{:.2f}", " mm, acceleration"),
    ("docs/suites.md", "acceleration RMS ", "acc_err_rms", "median", "{:.3f}", " m/s²"),
    ("docs/suites.md", "net force ", "net_force_err_n_rms", "median", "{:.3f}", " N, mean"),
    ("docs/suites.md", "learned forces ", "learned_rel_err_pct", "median", "{:.1f}", " % (`results/smoke"),
    ("docs/suites.md", "the reference's 4.12 mm, 0.37 m/s², 0.15 N and ", "learned_rel_err_pct", "median", "{:.1f}", " %)"),
]


@pytest.mark.parametrize("doc, before, metric, statistic, fmt, after", QUOTES)
def test_a_quoted_smoke_number_is_the_committed_one(doc, before, metric, statistic, fmt, after):
    text = (ROOT / doc).read_text()
    quoted = before + fmt.format(_smoke(metric, statistic)) + after
    assert quoted in text, f"{doc} should quote {quoted!r} (results/smoke/scores.json)"


def _standard(metric: str, unit: str = "") -> str:
    """The reference's median on `standard` with its interval, as the docs print it: ``14.1 [11.3, 17.5]``
    (``14.1 % [11.3, 17.5]`` with ``unit=" %"``)."""
    scores = json.loads((ROOT / "results/standard/reference/scores.json").read_text())
    m = scores["aggregate"][metric]["median"]
    return f"{m['value']:.1f}{unit} [{m['ci_low']:.1f}, {m['ci_high']:.1f}]"


STANDARD_QUOTES = [  # (document, text before, metric, unit, text after)
    ("README.md", "| **reference, blind** | 0.251 [0.229, 0.317] | 0.142 [0.117, 0.151] | 0.46 % [0.07, 1.05] | ",
     "learned_rel_err_pct", "", " | "),
    ("docs/results.md", "| reference (blind) | 4.67 [3.86, 6.20] | 2.73 [2.49, 3.20] | 0.251 [0.229, 0.317] | 0.142 [0.117, 0.151] | 0.46 % [0.07, 1.05] | ",
     "learned_rel_err_pct", "", " | "),
    ("docs/results.md", "| learned forces, every contact frame, relative error [%] | ", "learned_rel_err_pct", "", " |"),
    ("docs/results.md", "| learned forces, the paper's sample rule [%] | ", "learned_rel_err_pct_paper", "", " |"),
]


@pytest.mark.parametrize("doc, before, metric, unit, after", STANDARD_QUOTES)
def test_a_quoted_standard_number_is_the_committed_one(doc, before, metric, unit, after):
    text = (ROOT / doc).read_text()
    quoted = before + _standard(metric, unit) + after
    assert quoted in text, f"{doc} should quote {quoted!r} (results/standard/reference/scores.json)"


def _aggregate(result: str, metric: str, statistic: str = "median") -> float:
    return json.loads((ROOT / "results" / result / "scores.json").read_text())["aggregate"][metric][statistic]["value"]


def test_the_savgol_examples_scores_in_the_methods_page_are_the_committed_ones():
    """docs/methods.md quotes the example differentiator on smoke (results/smoke_savgol) beside the
    reference (results/smoke), and which gates it fails."""
    text = " ".join((ROOT / "docs/methods.md").read_text().split())
    s, r = "smoke_savgol", "smoke"
    quoted = (f"acceleration error median {_aggregate(s, 'acc_err_rms'):.3f} m/s² ({_aggregate(r, 'acc_err_rms'):.3f}) "
              f"against the gate's 0.6, net force {_aggregate(s, 'net_force_err_n_rms'):.3f} N "
              f"({_aggregate(r, 'net_force_err_n_rms'):.3f}) against 0.3, and the net force's largest episode (its "
              f"90th percentile) {_aggregate(s, 'net_force_err_n_rms', 'p90'):.3f} N "
              f"({_aggregate(r, 'net_force_err_n_rms', 'p90'):.3f}) against 0.5; least-violation frames "
              f"{_aggregate(s, 'least_violation_frac', 'mean'):g} ({_aggregate(r, 'least_violation_frac', 'mean'):g}), "
              f"learned forces {_aggregate(s, 'learned_rel_err_pct'):.1f} % ({_aggregate(r, 'learned_rel_err_pct'):.1f} %)")
    assert quoted in text, quoted
    scores = json.loads((ROOT / "results/smoke_savgol/scores.json").read_text())
    failed = [g["name"] for g in scores["gates"] if not g["passed"]]
    assert failed == ["median acc_err_rms <= 0.6", "median net_force_err_n_rms <= 0.3", "p90 net_force_err_n_rms <= 0.5"]
    assert "fails three of the nine gates" in text and len(scores["gates"]) == 9


def test_the_pictures_the_docs_show_are_the_committed_runs_pictures():
    """``fsv-bench reproduce --write`` copies them (``Result.docs_pictures``): the docs never show an
    older run than the committed one."""
    from benchmark.reproduce import RESULTS

    shown = [(ROOT / r.path / picture, ROOT / "docs" / doc) for r in RESULTS for picture, doc in r.docs_pictures]
    assert len(shown) == 5
    for committed, doc in shown:
        assert doc.read_bytes() == committed.read_bytes(), f"{doc} is not {committed}"


def _summary(run: str) -> dict:
    return json.loads((ROOT / "results" / run / "summary.json").read_text())


def test_the_walkthroughs_numbers_are_the_committed_runs():
    """docs/getting-started.md's walkthrough quotes results/lift-u0-g0-m0-s0 and
    results/rotate-u2-g3-m0-s17 (both regenerated by `fsv-bench reproduce`)."""
    text = " ".join((ROOT / "docs/getting-started.md").read_text().split())
    lift, rot = _summary("lift-u0-g0-m0-s0"), _summary("rotate-u2-g3-m0-s17")
    t, f, learned = lift["tracking"], lift["forces"], lift["learning"]
    quotes = [
        f"(median {t['box_pos_err_mm']:.2f} mm and {t['box_rot_err_deg']:.2f}° off the truth)",
        f"(recall {t['contact_recall']:.2f}, precision {t['contact_precision']:.2f}; contact point error "
        f"{t['contact_err_mm_mean']:.2f} ± {t['contact_err_mm_std']:.2f} mm per axis",
        f"they are {learned['rel_err_pct_mean']:.1f} % off (MAE {learned['mae_n']:.2f} N)",
        f"({f['net_force_err_n_rms']:.3f} N RMS against the truth's mean over each frame's interval, "
        f"{f['net_force_err_n_rms_instant']:.3f} N against the instant)",
    ]
    t, f, learned = rot["tracking"], rot["forces"], rot["learning"]
    quotes += [
        f"recall {t['contact_recall']:.2f}, precision {t['contact_precision']:.2f}, contact error "
        f"{t['contact_err_mm_mean']:.2f} ± {t['contact_err_mm_std']:.2f} mm per axis; the box "
        f"{t['box_pos_err_mm']:.2f} mm and {t['box_rot_err_deg']:.2f}° off",
        f"({f['net_force_err_n_rms']:.3f} N RMS against the frame mean, {f['net_force_err_n_rms_instant']:.3f} N "
        f"against the instant)",
        f"The learned forces are {learned['rel_err_pct_mean']:.1f} % off (MAE {learned['mae_n']:.2f} N)",
    ]
    for quote in quotes:
        assert quote.replace("-", "−") in text or quote in text, quote
    for run in (lift, rot):
        assert run["verdict"]["verdict"] == "pass" and len(run["verdict"]["gates"]) == 9


def test_the_findings_quote_the_committed_failure_atlas():
    doc = json.loads((ROOT / "results/failure_atlas/atlas.json").read_text())
    text = (ROOT / "docs/findings.md").read_text()
    for k in ("lab", "exact"):
        t = doc["tail"][k]
        row = (f"| {k} | {t['failing_episodes']} of 48 | {t['net_force_p90_n']:.3f} | {t['net_force_max_n']:.3f} | "
               f"{t['no_contact_frames']} | {100 * t['least_violation_frac_mean']:.2f} % |")
        assert row in text, row
    lost = {k: sum(e[k]["table_lost_frames"] for e in doc["episodes"]) for k in ("lab", "exact")}
    assert f"({lost['lab']} such frames over" in text and f"under lab knowledge,\n  {lost['exact']} under exact" in text


def _mean_ci(result: str, metric: str) -> str:
    m = json.loads((ROOT / "results" / result / "scores.json").read_text())["aggregate"][metric]["mean"]
    return f"{m['value']:.2f} N [{m['ci_low']:.2f}, {m['ci_high']:.2f}]"


PEER_FORM_QUOTES = [  # (text before, result, metric, text after)
    ("per-contact force MAE ", "standard/reference", "force_mae_n", "\n(median"),
    ("RMSE ", "standard/reference", "force_rmse_n", " (median"),
    ("peak-force MAE ", "standard/reference", "peak_force_err_n", "\n(median"),
    ("has nearly the same peak-force error, ", "standard/baseline-no-internal", "peak_force_err_n", ": the nominal"),
]


@pytest.mark.parametrize("before, result, metric, after", PEER_FORM_QUOTES)
def test_the_peers_forms_quoted_in_results_are_the_committed_ones(before, result, metric, after):
    text = (ROOT / "docs/results.md").read_text()
    quoted = before + _mean_ci(result, metric) + after.replace("\\n", "\n")
    assert quoted in text, f"docs/results.md should quote {quoted!r} (results/{result}/scores.json)"


def test_the_findings_quote_the_committed_colour_ablation():
    doc = json.loads((ROOT / "results/colour_ablation/colour_ablation.json").read_text())
    text = " ".join((ROOT / "docs/findings.md").read_text().split())
    tests = doc["verdict"]["tests"]
    recall, precision = tests["contact_recall"], tests["contact_precision"]
    assert doc["verdict"]["answer"] == "hurts" and "No: the gate costs contact recall" in text
    assert f"(mean paired difference {recall['mean_diff']:.4f}, Wilcoxon p {recall['p']:.2g}, " in text
    assert f"gains no precision ({precision['mean_diff']:.4f}, p {precision['p']:.2g})" in text
    tone = {t["skin_tone"]: t for t in doc["tones"]}
    assert f"keeps {100 * tone[10]['gate']['true_kept_share']:.1f} % of the true contacts of the darkest" in text
    assert f"{100 * tone[1]['gate']['true_kept_share']:.1f} % of the lightest (Monk 1)" in text


def test_the_direct_windows_table_in_the_methods_page_is_the_committed_choice():
    text = (ROOT / "docs/methods.md").read_text()
    rows = [line.replace("**", "") for line in text.splitlines()
            if line.startswith("| ") and any(f" | {n} | " in line for n in (61, 97, 151))]
    assert len(rows) == 3
    for row, w in zip(rows, (0, 2, 5)):
        doc = json.loads((ROOT / f"results/direct_window/w{w}/direct_curve.json").read_text())
        r = doc["rows"][0]
        assert doc["config"]["window"] == w and r["people"] == 40
        m = r["aggregate"]["force_mae_n"]["mean"]
        mae = f"{m['value']:.3g} [{m['ci_low']:.3g}, {m['ci_high']:.3g}]"
        assert f" | {r['parameters']:,} | {r['best_epoch']} | " in row and mae in row, (row, mae)
