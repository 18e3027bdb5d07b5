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
]


@pytest.mark.parametrize("doc, before, metric, statistic, fmt, after", QUOTES)
def test_a_quoted_smoke_number_is_the_committed_one(doc, before, metric, statistic, fmt, after):
    text = (ROOT / doc).read_text()
    quoted = before + fmt.format(_smoke(metric, statistic)) + after
    assert quoted in text, f"{doc} should quote {quoted!r} (results/smoke/scores.json)"
