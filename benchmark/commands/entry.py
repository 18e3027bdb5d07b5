"""The ``fsv-bench`` console script: Ctrl-C's handler first, then the command line.

The handler (:mod:`benchmark.interrupt`) is installed before the heavy imports (MuJoCo, the
renderer, torch), so that an interrupt in any phase, importing included, ends the command with
status 130 within a second and writes nothing.
"""

from __future__ import annotations

import os
import sys

from benchmark import collector, interrupt


def main() -> int:
    """Runs ``fsv-bench`` with the process's arguments; returns the exit status."""
    interrupt.install()
    collector.tune()  # the process is the command's own (not a caller's that runs it in-process)
    try:
        code = run()
        sys.stdout.flush()  # here, where a closed pipe is caught, rather than at the interpreter's exit
    except BrokenPipeError:  # the reader of the output went away (`fsv-bench reproduce --list | head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit's flush
        return 0
    except BaseException as e:  # e.g. a C extension's import turns the interrupt into an ImportError
        if not interrupt.interrupted() or isinstance(e, SystemExit):
            raise
        print("fsv-bench: interrupted; nothing was written", file=sys.stderr)
        code = interrupt.EXIT_INTERRUPTED
    interrupt.finished(code)  # a Ctrl-C from here on ends the process with this status
    if interrupt.interrupted():  # every file is complete or removed: end now, before the interpreter's
        interrupt.exit_now(code)  # teardown, where a library could turn the interrupt into another status
    if code == BAD_INPUT:  # refused before any work (no pool, cluster or file of ours open): end now too,
        interrupt.exit_now(code)  # as a native library's thread torn down at exit can abort (status 134)
    if main_command_done(sys.argv[1:]):  # the main command has written and closed everything it makes
        interrupt.exit_now(code)
    return code


def run(argv: list | None = None) -> int:
    """``fsv-bench`` on ``argv`` (default: the process's arguments): ``reproduce``, which runs the other
    commands, here on the top floor; everything else by :func:`benchmark.commands.cli.main`. Returns
    the exit status."""
    from benchmark.commands import cli  # lazy: after the interrupt handler (MuJoCo, numba, scipy: 1 s)

    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] == "reproduce":
        return cli.run_subcommand(argv, subcommand_module(argv[0]))
    return cli.main(argv)


def subcommand_module(name: str):
    """The module of any sub-command of ``fsv-bench`` (:data:`benchmark.commands.cli.ALL_SUBCOMMANDS`)."""
    from benchmark.commands import cli  # lazy: after the interrupt handler (MuJoCo, numba, scipy: 1 s)

    if name == "reproduce":
        from benchmark import reproduce  # lazy: torch, pandas and every command: only when asked for

        return reproduce
    return cli.subcommand_module(name)


def subcommand_parser(name: str) -> tuple:
    """``(module, parser)`` of any sub-command of ``fsv-bench``."""
    from benchmark.commands import cli  # lazy: after the interrupt handler (MuJoCo, numba, scipy: 1 s)

    return cli.subcommand_parser(name, subcommand_module(name))


def main_command_done(argv: list) -> bool:
    """Whether ``argv`` ran the main command (not a sub-command, not ``--help``): it waits for its
    background work and renames its output folder into place before returning, so the interpreter's
    teardown (about 0.7 s of finalisers in the imported libraries) has nothing left to do for it."""
    from benchmark.commands.cli import ALL_SUBCOMMANDS  # lazy: after the interrupt handler (MuJoCo, numba, scipy: 1 s)

    return not (argv and argv[0] in ALL_SUBCOMMANDS)


BAD_INPUT = 2
"""The status of input refused before any work: the command ends at once, skipping the interpreter's
teardown (``table2`` on a damaged dataset once aborted there with "terminate called without an
active exception", status 134, after printing the right line)."""


if __name__ == "__main__":
    sys.exit(main())
