"""Entry point of the ``motosim`` command.

Each subcommand lives in its own module with ``register(subparsers)``, which adds its parser
and sets ``func`` to a ``run(args) -> int``. Only the module of the chosen subcommand is
imported (the others are listed by name and one-line help), so ``motosim --help`` and a
mistyped command answer at once instead of loading SciPy and the models.

Every :class:`MotosimError` raised below, and every usage error of the parser, is printed as
one line ``motosim: error: ...`` with exit code 2, without a traceback.
"""

import argparse
import copy
import gc
import importlib
import logging
import os
import re
import signal
import sys
import threading
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from types import FrameType
from typing import Any, NoReturn, TextIO

from motosim import __version__
from motosim.errors import (
    EXIT_BAD_INPUT,
    EXIT_RUN_FAILED,
    MotosimError,
    MotosimWarning,
    RunFailedError,
    stop_signals,
)

__all__ = ["COMMANDS", "build_parser", "main"]

COMMANDS: dict[str, tuple[str, str]] = {
    "params": ("motosim.cli.params", "list and show parameter sets"),
    "modes": ("motosim.cli.modes", "eigenvalues and modes of the motorcycle against speed"),
    "trim": (
        "motosim.cli.trim",
        "the steady turn of the multibody motorcycle, the handling figure",
    ),
    "excite": (
        "motosim.cli.excite",
        "simulate an open-loop excitation run of the handlebar (section II.D)",
    ),
    "identify": (
        "motosim.cli.identify",
        "identify the handlebar's inertia and frictions from an excitation log",
    ),
    "estimate": (
        "motosim.cli.estimate",
        "estimate the rider torque from a log of theta_h and i_m",
    ),
    "design": (
        "motosim.cli.design",
        "design the rider-torque observer and the torque-feedback controller",
    ),
    "simulate": (
        "motosim.cli.simulate",
        "simulate a scenario in closed loop (Fig. 7) and write its result",
    ),
    "report": ("motosim.cli.simulate", "build the HTML report of a result folder"),
    "paper": ("motosim.cli.paper", "regenerate every figure of the paper's section V"),
    "view": (
        "motosim.cli.view",
        "ride a saved result in the browser: the rider's view and a dashboard",
    ),
    "telemetry": (
        "motosim.cli.view",
        "export a saved result as MCAP, or stream it to PlotJuggler or esmini over UDP",
    ),
    "campaign": (
        "motosim.cli.campaign",
        "run many perturbed runs of a scenario (grid, Latin hypercube, random draws)",
    ),
    "fidelity": (
        "motosim.cli.fidelity",
        "the steering feel a design renders, against the virtual motorcycle's",
    ),
    "cueing": (
        "motosim.cli.cueing",
        "platform roll/pitch/yaw commands for a run, scored by what the rider perceives",
    ),
    "run": ("motosim.cli.run", "run the stack in real time against the handlebar over CAN"),
    "rig": (
        "motosim.cli.rig",
        "start the virtual rig: the scenario's handlebar and drive on a CAN bus",
    ),
    "rt-check": (
        "motosim.cli.rtcheck",
        "measure this machine's wake-up latency and missed deadlines at a rate",
    ),
    "cache": (
        "motosim.cli.cache",
        "show, clear or warm the cache of designs (controllers, riders)",
    ),
}
"""Subcommand name -> (module that registers it, one-line help shown by ``motosim --help``)."""


def render_default(value: object) -> str:
    """An option's default as a person types it: ``100`` for 100.0, ``10,20,30`` for a list."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, list | tuple):
        return ",".join(render_default(item) for item in value)
    return str(value)


class _DefaultsFormatter(argparse.HelpFormatter):
    """A help formatter that states every option's default.

    An option whose help already speaks of its default is left as it is; a help ending in the
    default in parentheses (``length [s] (60)``) reads ``(default: 60)``; any other option
    with a default gets `` (default: VALUE)`` appended. Flags (``store_true``) and options
    without a default say what they do when absent in their own text.
    """

    def _format_action(self, action: argparse.Action) -> str:
        if not action.help and has_default(action):  # no text: the default alone
            action = copy.copy(action)
            action.help = ""
            action.help = f"default: {render_default(action.default)}".replace("%", "%%")
        return super()._format_action(action)

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help
        if text is None or text == argparse.SUPPRESS or not has_default(action):
            return text
        if "default" in text.lower():
            return text
        shown = render_default(action.default).replace("%", "%%")
        for mark in ")", ";", ":", ",", " ":
            if f"({shown}{mark}" in text:
                return text.replace(f"({shown}{mark}", f"(default: {shown}{mark}", 1)
        return f"{text} (default: {shown})" if text else f"default: {shown}"


def has_default(action: argparse.Action) -> bool:
    """Whether ``action`` is an option whose default a user reads in ``--help``.

    Flags (``store_true``, ``store_false``, ``--help``, ``--version``), positional arguments
    and required options have none to state; an option whose default is None states what
    happens when it is absent in its own help text.
    """
    if not action.option_strings or action.required or action.nargs == 0:
        return False
    return action.default is not None and action.default != argparse.SUPPRESS


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line, exit code 2, and whose help states
    every option's default (:class:`_DefaultsFormatter`)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", _DefaultsFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        message = _one_line(message)
        self.exit(2, f"motosim: error: {message} (see {self.prog} --help)\n")


def _chosen(argv: Sequence[str]) -> str | None:
    """The subcommand named on the command line: the first word that is not an option.

    Raises
    ------
    MotosimError
        If that word is not a subcommand, with the closest one as a suggestion.
    """
    for word in argv:
        if not word.startswith("-"):
            if word not in COMMANDS:
                from motosim.params.checks import short_repr, suggestion

                raise MotosimError(
                    f"unknown command {short_repr(word)}{suggestion(word, COMMANDS)} "
                    f"(expected one of {', '.join(COMMANDS)}; see motosim --help)"
                )
            return word
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser, with the full parser of ``command`` and the others listed by name.

    Parameters
    ----------
    command : str, optional
        The subcommand whose module is imported and registered; ``"all"`` registers every
        module (for documentation and tests).

    Returns
    -------
    argparse.ArgumentParser
        The ``motosim`` parser.
    """
    parser = _Parser(
        prog="motosim",
        description="Motorcycle riding simulator with a motorised handlebar.",
    )
    parser.add_argument("--version", action="version", version=f"motosim {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the traceback of an internal error"
    )
    sub = parser.add_subparsers(
        dest="command", required=True, parser_class=_Parser, metavar="COMMAND"
    )
    chosen = COMMANDS[command][0] if command in COMMANDS else None
    for name, (module, text) in COMMANDS.items():
        if name in sub.choices:  # registered with another command of its module
            continue
        if command == "all" or module == chosen:
            importlib.import_module(module).register(sub)
        else:
            sub.add_parser(name, help=text, add_help=False)
    return parser


_SHOWN: set[str] = set()


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    """Print a warning as one line ``motosim: warning: ...``, once: a
    :class:`MotosimWarning` as it is, another (a library's: NumPy's overflow, SciPy's
    ill-conditioning) with its kind and the file that raised it, not the two lines of
    Python's format with that file's source line."""
    text = _one_line(str(message))
    if not issubclass(category, MotosimWarning):
        text = f"{category.__name__} in {os.path.basename(filename)}:{lineno}: {text}"
    if text not in _SHOWN:
        _SHOWN.add(text)
        print(f"motosim: warning: {text}", file=sys.stderr)


class _OneLine(logging.Handler):
    """Print the library's log warnings as ``motosim: warning: ...``, one line each."""

    def emit(self, record: logging.LogRecord) -> None:
        text = _one_line(record.getMessage())
        print(f"motosim: warning: {text}", file=sys.stderr)


@contextmanager
def _stop_signals_as_ctrl_c() -> Iterator[None]:
    """Within the block SIGTERM and SIGHUP do what Ctrl-C (SIGINT) does at that moment.

    A lab's process manager, ``timeout`` or a closed terminal stops a command with SIGTERM or
    SIGHUP, whose default action ends the process at once: exit -15, a file half written,
    ``motosim run``'s torque not faded out. Passed to the SIGINT handler installed when the
    signal arrives (Python's, which raises KeyboardInterrupt; a result writer's; the real-time
    loop's stop), they stop the command as Ctrl-C does: exit 130, the same files left.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def as_ctrl_c(signum: int, frame: FrameType | None) -> None:
        handler = signal.getsignal(signal.SIGINT)
        if callable(handler):
            handler(signal.SIGINT, frame)
        else:  # SIGINT ignored (a background job of a script): the stop is still asked for
            raise KeyboardInterrupt(signal.Signals(signum).name)

    previous = {sig: signal.signal(sig, as_ctrl_c) for sig in stop_signals()}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


@contextmanager
def _log_in_one_line() -> Iterator[None]:
    """Within the block, the ``motosim`` loggers print through :class:`_OneLine` only."""
    logger = logging.getLogger("motosim")
    handler = _OneLine(logging.WARNING)
    propagate = logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate


def _refuse_empty(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Refuse an empty string given for any option or argument (``--out ''``).

    An empty value would otherwise read as "not given" and the default would be used.
    """
    actions = list(parser._actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            chosen = action.choices.get(getattr(args, "command", ""))
            actions += list(chosen._actions) if chosen is not None else []
    for action in actions:
        value = getattr(args, action.dest, None)
        name = action.option_strings[0] if action.option_strings else action.dest
        if isinstance(value, str) and not value.strip() and action.default != value:
            raise MotosimError(f"{name} is empty; expected a value (see motosim --help)")
        if (
            isinstance(value, list)
            and action.nargs is None
            and type(action) is argparse._StoreAction
        ):
            # argparse reads "--rate=--" as no value at all: a list, not a number
            raise MotosimError(f"{name} has no value; expected one (see motosim --help)")


_LONG_WORD = re.compile(r"\S{201,}")


def _one_line(message: str) -> str:
    """``message`` on one line, each word over 200 characters cut (a value, a key, a path)."""
    return _LONG_WORD.sub(
        lambda m: f"{m.group()[:80]}... ({len(m.group())} characters)", " ".join(message.split())
    )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code.

    0 success, 1 an internal error (a bug; ``--debug`` shows its traceback), 2 bad input,
    3 a run that failed (diverged, fell, faulted), 130 interrupted (Ctrl-C, SIGTERM or
    SIGHUP: the same stop, :func:`_stop_signals_as_ctrl_c`).
    """
    code = _main(list(sys.argv[1:] if argv is None else argv))
    if argv is None:  # the process's own command line: it ends now
        _exit_on_stop_signals(code)
        # the command's files are closed: the interpreter's exit need not walk the objects
        # of every imported module (NumPy, SciPy, numba) for cycles to collect
        gc.freeze()
    return code


def _exit_on_stop_signals(code: int) -> None:
    """From now on SIGTERM and SIGHUP end the process at once with ``code``.

    The command is over and its files are closed; the interpreter's exit (joblib's workers,
    numba, matplotlib) can take a second in which the default action would report the
    finished command as killed (exit -15), or hang. The handler flushes the standard streams
    and leaves with the command's own code (:func:`os._exit`); a signal the process was
    started with ignored (``nohup``) stays ignored.
    """
    if threading.current_thread() is not threading.main_thread():
        return

    def leave(signum: int, frame: FrameType | None) -> None:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):  # closed, or a broken pipe
                pass
        os._exit(code)

    for sig in stop_signals():
        signal.signal(sig, leave)


def _is_numerical_failure(err: Exception) -> bool:
    """Whether ``err`` is a linear-algebra failure (NumPy's ``LinAlgError``, which SciPy's is).

    The inputs were checked against their plausible ranges first, so a singular matrix or a
    diverged solver on them is a failed run (exit 3), not bad input and not a bug.
    """
    numpy = sys.modules.get("numpy")
    return numpy is not None and isinstance(err, numpy.linalg.LinAlgError)


def _main(words: list[str]) -> int:
    """:func:`main` on the words of a command line."""
    try:
        try:
            parser = build_parser(_chosen(words))
            args = parser.parse_args(words)
        except SystemExit as stop:  # --help, --version and usage errors: already printed
            return stop.code if isinstance(stop.code, int) else 2
        _refuse_empty(parser, args)
        _SHOWN.clear()
        with warnings.catch_warnings(), _log_in_one_line(), _stop_signals_as_ctrl_c():
            warnings.simplefilter("always", MotosimWarning)
            warnings.showwarning = _show_warning
            code: int = args.func(args)
    except MotosimError as err:
        message = _one_line(str(err))
        print(f"motosim: error: {message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except RunFailedError as err:
        message = _one_line(str(err))
        print(f"motosim: run failed: {message}", file=sys.stderr)
        return EXIT_RUN_FAILED
    except KeyboardInterrupt:
        print("motosim: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (e.g. `| head`): not an error of ours
        sys.stderr.close()
        return 0
    except OSError as err:  # a path the system refuses (too long, no permission, disk full)
        from motosim.params.checks import short_repr

        name = f" ({short_repr(str(err.filename))})" if err.filename else ""
        print(f"motosim: error: {err.strerror or err}{name}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except Exception as err:  # a bug of ours: one line, exit 1, the traceback on request
        if "--debug" in words:
            raise
        if _is_numerical_failure(err):
            message = " ".join(str(err).split())[:300]
            print(
                f"motosim: run failed: the computation failed numerically on inputs that passed "
                f"their checks ({type(err).__name__}: {message})",
                file=sys.stderr,
            )
            return EXIT_RUN_FAILED
        message = " ".join(str(err).split())[:300]
        print(
            f"motosim: internal error: {type(err).__name__}: {message} (a bug: please report "
            "it with the output of motosim --debug and the same arguments)",
            file=sys.stderr,
        )
        return 1
    return code


if __name__ == "__main__":
    sys.exit(main())
