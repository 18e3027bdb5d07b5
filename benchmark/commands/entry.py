"""The ``fsv-bench`` console script: Ctrl-C's handler first, then the command line.

The handler (:mod:`benchmark.interrupt`) is installed before the heavy imports (MuJoCo, the
renderer, torch), so that an interrupt in any phase, importing included, ends the command with
status 130 within a second and writes nothing.
"""

from __future__ import annotations

import sys

from benchmark import interrupt


def main() -> int:
    """Runs ``fsv-bench`` with the process's arguments; returns the exit status."""
    interrupt.install()
    try:
        from benchmark.commands.cli import main as run

        code = run()
    except BaseException as e:  # e.g. a C extension's import turns the interrupt into an ImportError
        if not interrupt.interrupted() or isinstance(e, SystemExit):
            raise
        print("fsv-bench: interrupted; nothing was written", file=sys.stderr)
        code = interrupt.EXIT_INTERRUPTED
    if interrupt.interrupted():  # every file is complete or removed: end now, before the interpreter's
        interrupt.exit_now(code)  # teardown, where a library could turn the interrupt into another status
    return code


if __name__ == "__main__":
    sys.exit(main())
