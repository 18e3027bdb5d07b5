"""Errors raised by the FSV method.

Every error the `fsv` package raises derives from :class:`FsvError`, so a caller can catch
the package's failures with one ``except`` clause.
"""


class FsvError(Exception):
    """Base class of every error raised by `fsv`."""


class InputError(FsvError, ValueError):
    """An argument has the wrong shape, type or value.

    The message names the bad value and what is accepted.
    """


class SolverError(FsvError):
    """A numerical solver failed in a way that cannot be reported per frame."""


class TrackingError(FsvError):
    """The tracker cannot continue (e.g. no object visible in the first frame)."""


def one_line(error: BaseException, limit: int = 240) -> str:
    """An exception's message on one line (a library's may span several), cut to ``limit`` characters,
    for error messages that must stay one line."""
    text = " ".join(str(error).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."
