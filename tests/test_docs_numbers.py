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
    ("docs/suites.md", "the reference's 4.00 mm, 0.39 m/s², 0.18 N and ", "learned_rel_err_pct", "median", "{:.1f}", " %)"),
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
    ("README.md", "| **reference, blind** | 0.317 [0.267, 0.351] | 0.166 [0.146, 0.199] | 0.37 % [0.14, 0.65] | ",
     "learned_rel_err_pct", "", " | "),
    ("docs/results.md", "| reference (blind) | 4.70 [3.86, 6.14] | 3.75 [3.41, 4.45] | 0.317 [0.267, 0.350] | 0.166 [0.146, 0.199] | 0.37 % [0.14, 0.65] | ",
     "learned_rel_err_pct", "", " | "),
    ("docs/results.md", "| learned forces, every contact frame, relative error [%] | ", "learned_rel_err_pct", "", " |"),
    ("docs/results.md", "| learned forces, the paper's sample rule [%] | ", "learned_rel_err_pct_paper", "", " |"),
]


@pytest.mark.parametrize("doc, before, metric, unit, after", STANDARD_QUOTES)
def test_a_quoted_standard_number_is_the_committed_one(doc, before, metric, unit, after):
    text = (ROOT / doc).read_text()
    quoted = before + _standard(metric, unit) + after
    assert quoted in text, f"{doc} should quote {quoted!r} (results/standard/reference/scores.json)"
