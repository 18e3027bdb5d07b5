"""The commands' argument parser: every error one line, exit status 2."""

from __future__ import annotations

import argparse
import math


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit status 2. No option takes an empty value,
    and no ``type=float`` option a NaN or an infinity (options that accept ``inf`` have their own type,
    ``benchmark.limits.number``)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")

    def _get_values(self, action, arg_strings):
        for text in arg_strings:
            if not text.strip():
                raise argparse.ArgumentError(action, f"expected a value, got {text!r}")
        value = super()._get_values(action, arg_strings)
        if action.type is float and isinstance(value, float) and not math.isfinite(value):
            raise argparse.ArgumentError(action, f"expected a finite number, got {arg_strings[0]!r}")
        return value
