"""Upper bounds on the work one command may be asked for, and the command-line types that hold each
count and number to its documented range while the command line is parsed (one line, exit status 2,
before any work).

    p.add_argument("--epochs", type=integer(1, MAX_EPOCHS), ...)
    p.add_argument("--init-perturbation", type=number(0, MAX_INIT_SCALE), ...)
    seeds = parse_ints("0-9", "--seeds")          # (0, 1, ..., 9); counted before it is built

A grid (``generate``'s tasks x users x grasps x masses x seeds x views, a sweep's scenarios x
values, a suite) larger than :data:`MAX_EPISODES` is refused from the counts of its ranges, without
building it.
"""

from __future__ import annotations

import argparse
import math
import pathlib
from typing import Callable

MAX_EPISODES = 100_000
"""Most episodes one command's grid may hold. At the ~10 s one episode takes to simulate and render
on one core, 100,000 episodes are about twelve days of one core's work; a grid is held in memory
(its scenarios, the dataset's manifest), and one of 10^8 episodes grew past 24 GB."""

MAX_EPOCHS = 100_000
"""Most Rprop epochs per network (``train``, ``table2``; the default is 1500)."""

MAX_MEMBERS = 50
"""Most networks averaged per ANN (``--members``; the default is 5)."""

MAX_FOLDS = 100
"""Most cross-validation folds (``train --folds``; each fold trains a whole model)."""

MAX_WORKERS = 256
"""Most local worker processes (``--workers``): each is a Python process of a few hundred MB."""

MAX_INIT_SCALE = 10.0
"""Largest scale of the seeded first-frame perturbation (``--init-perturbation``, the ``init`` sweep
axis): ten times the protocol's 3 mm and 2 degrees on the box, 5 mm and 3 degrees on the palm
(``benchmark.method.init.INIT_PERTURBATION``), beyond which the start is no longer near the hand."""

MAX_SEED = 2**32 - 1
"""Largest seed of the networks' initial weights (``--seed`` of ``train`` and ``table2``)."""


class RangeError(ValueError):
    """A command-line value outside its documented range; the message names the option."""


def integer(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer from ``low`` to ``high`` (both included)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected an integer from {low:,} to {high:,}, got {text!r}")
        return value

    parse.high = high
    return parse


def number(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """An argparse type: a number from ``low`` to ``high`` (both included), in ``unit``; never NaN.
    With ``high`` infinite, ``inf`` is accepted (an option that it turns off)."""
    unit = f" {unit}" if unit else ""
    accepted = f"a number from {low:g} to {high:g}{unit}" if math.isfinite(high) else f"a number >= {low:g}{unit}, or inf"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {accepted}, got {text!r}")
        return value

    parse.high = high
    return parse


def folder(text: str) -> pathlib.Path:
    """An argparse type: a folder to read and write (existing or not), never an existing file."""
    path = pathlib.Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: exists and is not a folder; give a folder (made if missing)")
    return path


def int_ranges(text: str, option: str) -> tuple:
    """The ranges of "0,2,5-7" (``(range(0, 1), range(2, 3), range(5, 8))``), none built.

    Raises:
        RangeError: Naming ``option`` for anything but non-negative integers and ascending ranges.
    """
    ranges = []
    for part in str(text).split(","):
        a, dash, b = part.strip().partition("-")
        try:
            first, last = int(a), int(b) if dash else int(a)
        except ValueError:
            raise RangeError(f"{option} {text!r}: expected non-negative integers and ranges like '0,2,5-7'") from None
        if first < 0 or last < first:
            raise RangeError(f"{option} {text!r}: {part.strip()!r} is not a non-negative integer or an ascending range")
        ranges.append(range(first, last + 1))
    return tuple(ranges)


def count_ints(text: str, option: str) -> int:
    """How many integers "0,2,5-7" names (5), counted from its ranges without building them."""
    return sum(len(r) for r in int_ranges(text, option))


def parse_ints(text: str, option: str, limit: int = MAX_EPISODES) -> tuple:
    """The integers of "0,2,5-7" ((0, 2, 5, 6, 7)); RangeError naming ``option`` if there are more
    than ``limit`` (counted before they are built)."""
    ranges = int_ranges(text, option)
    n = sum(len(r) for r in ranges)
    if n > limit:
        raise RangeError(f"{option} {text!r}: {n:,} values, more than the {limit:,} accepted")
    return tuple(v for r in ranges for v in r)


def check_grid(counts: dict, what: str = "episodes") -> int:
    """The product of ``counts`` ({"--seeds": 10, ...}); RangeError naming each factor if it is above
    :data:`MAX_EPISODES`."""
    total = math.prod(counts.values())
    if total > MAX_EPISODES:
        factors = " x ".join(f"{n:,} {name}" for name, n in counts.items())
        raise RangeError(f"{factors} = {total:,} {what}, more than the {MAX_EPISODES:,} accepted in one command; "
                         "split the grid over several commands")
    return total


def parsed(parse_text: Callable[[str], object]) -> Callable[[str], object]:
    """An argparse type: ``parse_text(text)``; its ValueError becomes the option's one-line error."""

    def parse(text: str):
        try:
            return parse_text(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None

    return parse


def checked(check: Callable[[str], object]) -> Callable[[str], str]:
    """An argparse type: the text itself, once ``check(text)`` has not raised; its ValueError becomes
    the option's one-line error."""

    def parse(text: str) -> str:
        try:
            check(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
        return text

    return parse
