"""Scores of a method on a suite: per-episode metrics, aggregates with confidence intervals, gates."""
