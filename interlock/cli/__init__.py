"""The ``interlock`` command line: one module per command, each with ``add_parser(commands)`` and its ``run``.

Every command reports bad input as one line on stderr and exits non-zero;
no traceback reaches the user for an :class:`~interlock.InterlockError`.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time

import interlock
from interlock.cli import completion, convert, gallery, generate, groups, periodic, stability, sweep, verify, view
from interlock.cli.common import EXIT_BAD_INPUT, OUTPUT_SUFFIXES
from interlock.errors import InterlockError

__all__ = ["main", "OUTPUT_SUFFIXES"]

#: The commands in the order ``interlock --help`` lists them.
COMMANDS = (groups, verify, periodic, gallery, stability, sweep, convert, generate, view, completion)


def main(argv: list[str] | None = None) -> int:
    """Run the command ``argv`` (default: the program's arguments) and return its exit status.

    ``--time-limit`` counts from here (:func:`~interlock.cli.common.command_started`): parsing the arguments,
    importing what the command uses and reading its files are part of the wait it bounds.  Run as the program
    (``argv`` None: the ``interlock`` script, ``python -m interlock``), the objects left when the command ends are
    frozen out of the garbage collector (:func:`gc.freeze`): the interpreter's last collection over trimesh's and
    scipy's objects took 0.2 s after every answer, and the process ends right after.
    """
    clock = time.perf_counter()
    top = parser()
    args = top.parse_args(argv)
    args.started = clock
    if args.command is None:
        top.print_help()
        return 0
    try:
        return _run(args)
    finally:
        if argv is None:
            gc.freeze()


def _run(args) -> int:
    try:
        return args.run(args)
    except InterlockError as error:
        print(f"interlock {args.command}: error: {one_line(error)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except BrokenPipeError:  # the reader of our output went away (``interlock verify x.stl | head``)
        sys.stderr.close()
        return 141
    except OSError as error:  # a file the checks could not foresee (permissions, a full disk, ...)
        where = f" {error.filename}" if error.filename else ""
        print(f"interlock {args.command}: error:{where}: {error.strerror or error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except MemoryError:
        print(f"interlock {args.command}: error: out of memory; try a smaller input (or --max-blocks / --max-points "
              "lower)", file=sys.stderr)
        return EXIT_BAD_INPUT  # never 1, which verify and periodic answer "not interlocked" with
    except KeyboardInterrupt:
        print("interlock: interrupted", file=sys.stderr)
        return 130


class _Parser(argparse.ArgumentParser):
    """argparse, but a bad argument is one line on stderr (``interlock verify: error: ...``) and exit status 2."""

    def error(self, message):
        command = self.prog if self.prog.startswith("interlock") else f"interlock {self.prog}"
        self.exit(EXIT_BAD_INPUT, f"{command}: error: {message} (see {command} --help)\n")


def one_line(error) -> str:
    """An error's message on one line (a message quoting a file's line may hold a line break)."""
    return " ".join(str(error).split())


def parser() -> argparse.ArgumentParser:
    """The whole command line: every command's ``add_parser`` on one set of subcommands."""
    top = _Parser(
        prog="interlock",
        description="Generate, export and verify interlocking assemblies of rigid blocks.",
    )
    top.add_argument("--version", action="version", version=f"interlock {interlock.__version__}")
    commands = top.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for command in COMMANDS:
        command.add_parser(commands)
    return top
