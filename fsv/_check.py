"""Shape and value checks shared by the stage interfaces (frozen dataclasses)."""

from __future__ import annotations

import numpy as np

from fsv.errors import InputError


def as_array(name: str, value, shape: tuple, dtype=np.float64) -> np.ndarray:
    """Converts ``value`` to an array and checks its shape.

    Args:
        name: Name of the field, used in the error message.
        value: Anything ``np.asarray`` accepts.
        shape: Expected shape; ``None`` entries match any length, and an int entry must match.
        dtype: Target dtype.

    Returns:
        A read-only array of ``dtype`` with the checked shape.

    Raises:
        InputError: If the number of dimensions or a fixed length differs.
    """
    arr = np.array(value, dtype=dtype, copy=True)
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        want = "(" + ", ".join("*" if s is None else str(s) for s in shape) + ")"
        raise InputError(f"{name} must have shape {want}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


def same_length(owner: str, **arrays: np.ndarray) -> int:
    """Checks that arrays share their first (time) axis and returns its length."""
    lengths = {k: v.shape[0] for k, v in arrays.items()}
    if len(set(lengths.values())) > 1:
        raise InputError(f"{owner}: time axes differ in length: {lengths}")
    return next(iter(lengths.values()))


def finite(name: str, arr: np.ndarray) -> None:
    """Raises :class:`InputError` if ``arr`` holds NaN or inf."""
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite; it holds {int(np.sum(~np.isfinite(arr)))} NaN/inf values")


def positive(name: str, value, what: str = "a finite number > 0", error: type = InputError) -> None:
    """Raises ``error`` ("``name`` must be ``what``, got ``value``") unless ``value`` is finite and > 0."""
    if not (np.isfinite(value) and value > 0):
        raise error(f"{name} must be {what}, got {value!r}")
