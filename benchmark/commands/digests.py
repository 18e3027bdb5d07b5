"""Digests of what each stage of the main command made, in pipeline order.

``summary.json`` records them (``digests``), so that ``fsv-bench reproduce`` can name the first
stage whose output differs from the committed run (the truth, the depth, the tracking, ...)
instead of counting the values that moved downstream of it.
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

WALL_CLOCK = frozenset({"solve_time_s"})
"""Array fields that measure time, not results: left out of the digests."""

STAGES = ("truth", "depth", "colour", "tracking", "kinematics", "nominal_forces", "final_forces")
"""The digested outputs, in pipeline order (``colour`` only in runs that rendered it)."""


def digest(*records) -> str | None:
    """SHA-256 (first 16 hex digits) of the array fields of dataclass records, in field order
    (but :data:`WALL_CLOCK`'s); None when every record is None."""
    records = [r for r in records if r is not None]
    if not records:
        return None
    h = hashlib.sha256()
    for record in records:
        for field in dataclasses.fields(record):
            value = getattr(record, field.name)
            if isinstance(value, np.ndarray) and field.name not in WALL_CLOCK:
                h.update(field.name.encode())
                h.update(str(value.dtype).encode())
                h.update(memoryview(np.ascontiguousarray(value).reshape(-1)).cast("B"))  # no copy
    return h.hexdigest()[:16]


def colour_digest(colour) -> str:
    """The ``colour`` digest of :func:`stage_digests`: of an ``fsv.ColourVideo`` and its calibration."""
    return digest(colour, colour.calib)


def stage_digests(episode, estimate, known: dict | None = None) -> dict:
    """``{stage: digest}`` for :data:`STAGES` of one run of the main command.

    Args:
        episode: The rendered ``benchmark.world.episode.Episode``.
        estimate: The method's ``fsv.method.Estimate`` on it.
        known: Digests already computed (the depth's and the colour's, by the jobs that rendered
            them beside the later stages): taken as they are.
    """
    known = known or {}
    tracking = estimate.tracking
    colour = {} if episode.colour is None else {"colour": known.get("colour") or colour_digest(episode.colour)}
    return {
        "truth": digest(episode.truth),
        "depth": known.get("depth") or digest(episode.depth),
        **colour,
        "tracking": digest(getattr(tracking, "box", None), getattr(tracking, "contacts", None)),
        "kinematics": digest(estimate.kinematics),
        "nominal_forces": digest(estimate.nominal),
        "final_forces": digest(estimate.forces),
    }


def first_difference(new: dict | None, old: dict | None) -> str | None:
    """The first stage of :data:`STAGES` whose digest differs between two runs' ``digests``
    (None when all agree; "digests" when one run has none)."""
    if not new or not old:
        return None if new == old else "digests"
    return next((s for s in STAGES if new.get(s) != old.get(s)), None)
