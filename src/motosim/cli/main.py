"""Entry point of the ``motosim`` command.

Each subcommand lives in its own module with ``register(subparsers)``, which adds its parser
and sets ``func`` to a ``run(args) -> int``. Every :class:`MotosimError` raised below is
printed as one line ``motosim: error: ...`` with exit code 2, without a traceback.
"""

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from motosim import __version__
from motosim.cli import (
    design,
    estimate,
    excite,
    identify,
    modes,
    paper,
    params,
    rig,
    rtcheck,
    simulate,
)
from motosim.cli import run as run_command
from motosim.errors import EXIT_BAD_INPUT, EXIT_RUN_FAILED, MotosimError, RunFailedError

__all__ = ["main"]

_COMMANDS = (
    params,
    modes,
    excite,
    identify,
    estimate,
    design,
    simulate,
    paper,
    run_command,
    rig,
    rtcheck,
)


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line, exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The parser with every subcommand registered."""
    parser = _Parser(
        prog="motosim",
        description="Motorcycle riding simulator with a motorised handlebar.",
    )
    parser.add_argument("--version", action="version", version=f"motosim {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for command in _COMMANDS:
        command.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (0 success, 2 bad input, 3 a failed run)."""
    args = build_parser().parse_args(argv)
    try:
        code: int = args.func(args)
    except MotosimError as err:
        print(f"motosim: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RunFailedError as err:
        print(f"motosim: run failed: {err}", file=sys.stderr)
        return EXIT_RUN_FAILED
    except KeyboardInterrupt:
        print("motosim: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (e.g. `| head`): not an error of ours
        sys.stderr.close()
        return 0
    return code


if __name__ == "__main__":
    sys.exit(main())
