"""``motosim cache``: show, clear or warm the design cache; the others' ``--no-cache``."""

import argparse
import sys
import threading
from typing import TYPE_CHECKING, Any

from motosim.cli._common import print_json

if TYPE_CHECKING:
    from motosim.io.cache import DesignCache

__all__ = ["add_cache_option", "design_cache", "register"]


def register(sub: Any) -> None:
    """Add ``cache`` (``info``, ``clear``, ``warm``) to the subcommands."""
    parser = sub.add_parser(
        "cache",
        help="show, clear or warm the cache of designs (controllers, riders)",
        description=(
            "Designs (controller syntheses, the virtual rider's schedules, the stacks) are "
            "computed once and kept in the cache folder: $MOTOSIM_CACHE_DIR, else "
            "$XDG_CACHE_HOME/motosim, else ~/.cache/motosim. Each is keyed by a hash of all "
            "it depends on, motosim's version and its code included, so it is never stale; "
            "clearing it only costs the next runs their design time."
        ),
    )
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")
    info = actions.add_parser("info", help="the cache folder, its entries and their size")
    info.add_argument("--json", action="store_true", help="print JSON")
    actions.add_parser("clear", help="remove every entry")
    warm = actions.add_parser(
        "warm",
        help="design and compile ahead of the first run",
        description=(
            "Design each scenario into the cache and compile its closed loop (numba keeps the "
            "machine code beside the package), so that its first run costs what a later one "
            "does; a scenario of the same motorcycle and rider kind then needs no compiling "
            "either. Without a file: the loops of Sharp 1971 with a torque-profile rider and "
            "with the virtual rider, and of the multibody motorcycle (about a minute)."
        ),
    )
    warm.add_argument("scenarios", nargs="*", metavar="SCENARIO", help="scenario TOML files")
    warm.add_argument("--json", action="store_true", help="print what was warmed as JSON")
    parser.set_defaults(func=run)


def add_cache_option(parser: argparse.ArgumentParser) -> None:
    """Add ``--no-cache`` to a command that designs."""
    parser.add_argument(
        "--no-cache",
        dest="cache",
        action="store_false",
        help="design again instead of reading the design cache, and store nothing "
        "(see motosim cache)",
    )


ANNOUNCE_AFTER = 0.3
"""Seconds a design runs before the command says it is designing (a quick one says nothing)."""


class _Announcer:
    """Says on stderr that a run is designing, once it has taken :data:`ANNOUNCE_AFTER`, and
    how long it took when done: one line."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None
        self._shown = self._done = False

    def _show(self, label: str) -> None:
        with self._lock:
            if not self._done:
                print(
                    f"motosim: {label}: designing (once: kept in the design cache)...",
                    end="",
                    file=sys.stderr,
                    flush=True,
                )
                self._shown = True

    def __call__(self, label: str, seconds: float | None) -> None:
        if seconds is None:
            self._shown = self._done = False
            if ANNOUNCE_AFTER <= 0.0:
                self._show(label)
                return
            self._timer = threading.Timer(ANNOUNCE_AFTER, self._show, (label,))
            self._timer.daemon = True
            self._timer.start()
            return
        with self._lock:
            self._done = True
            if self._timer is not None:
                self._timer.cancel()
            if self._shown:
                print(f" {seconds:.1f} s", file=sys.stderr, flush=True)


def _on_a_terminal() -> bool:
    """Whether stderr is a terminal, where the command says that it designs (as the
    progress bars show: a log or a script's capture gets no such line)."""
    return sys.stderr.isatty()


def design_cache(args: argparse.Namespace, *, quiet: bool = False) -> "DesignCache":
    """The design cache of a command's ``--no-cache``; on a terminal it says when it designs."""
    from motosim.io.cache import DesignCache

    announce = not quiet and _on_a_terminal()
    return DesignCache.default(
        enabled=getattr(args, "cache", True), on_design=_Announcer() if announce else None
    )


def _size(n: int) -> str:
    if n < 1000:
        return f"{n} B"
    value = float(n)
    for unit in ("kB", "MB", "GB"):
        value /= 1000.0
        if value < 1000.0 or unit == "GB":
            break
    return f"{value:.1f} {unit}"


WARM_DEFAULTS: dict[str, dict[str, Any]] = {
    "sharp_profile_rider": {
        "scenario": {"name": "sharp_profile_rider", "duration": 1.0},
        "rider": {"kind": "torque", "profile": {"kind": "constant", "value": 0.0}},
    },
    "sharp_virtual_rider": {
        "scenario": {"name": "sharp_virtual_rider", "duration": 1.0},
        "rider": {"kind": "virtual", "path": {"kind": "straight"}},
    },
    "multibody_virtual_rider": {
        "scenario": {"name": "multibody_virtual_rider", "duration": 1.0},
        "motorcycle": {"model": "multibody", "params": "sel2004_motorcycle", "speed": 20.0},
        "rider": {"kind": "virtual", "path": {"kind": "straight"}},
    },
}
"""What ``motosim cache warm`` compiles without a file: one scenario per compiled variant of
the offline loop (the motorcycle model and the rider's kind choose it)."""

WARM_SECONDS = 0.02
"""Simulated time [s] of a warming run: one block of the loop, enough to compile it."""


def _warm(args: argparse.Namespace, cache: "DesignCache") -> int:
    """Design and compile each scenario of ``args`` (or :data:`WARM_DEFAULTS`)."""
    import time
    from dataclasses import replace
    from pathlib import Path

    from motosim.cli._common import check_scenario_inputs, check_scenario_values

    for path in args.scenarios:  # every file checked before the first is designed
        check_scenario_inputs(path)
        check_scenario_values(path)
    import numpy as np

    from motosim.cli.simulate import resolve_cached
    from motosim.io.runs import load_scenario
    from motosim.sim import parse_scenario, simulate

    named = [(path, load_scenario(path), Path(path).parent) for path in args.scenarios]
    if not args.scenarios:
        named = [
            (name, parse_scenario(data, origin=f"built-in {name}"), Path("."))
            for name, data in WARM_DEFAULTS.items()
        ]
    warmed = {}
    for label, scenario, base in named:
        if not args.json:
            print(f"{label}: designing and compiling...", end="", flush=True)
        start = time.perf_counter()
        inputs, stack = resolve_cached(scenario, base, cache)
        brief = replace(inputs, scenario=replace(scenario, duration=WARM_SECONDS))
        simulate(brief, rng=np.random.default_rng(0), stack=stack, keep=False)
        warmed[label] = time.perf_counter() - start
        if not args.json:
            print(f" {warmed[label]:.1f} s")
    if args.json:
        print_json({"folder": str(cache.folder), "seconds": warmed})
    return 0


def run(args: argparse.Namespace) -> int:
    """Show, clear or warm the cache."""
    from motosim.io.cache import DesignCache

    cache = DesignCache.default()
    if args.action == "warm":
        return _warm(args, cache)
    if args.action == "clear":
        removed = cache.clear()
        print(f"removed {removed} design(s) from {cache.folder}")
        return 0
    info = cache.info()
    if args.json:
        print_json(
            {
                "folder": str(info.folder),
                "entries": info.entries,
                "count": sum(info.entries.values()),
                "bytes": info.size,
            }
        )
        return 0
    count = sum(info.entries.values())
    kinds = ", ".join(f"{n} {k}" for k, n in info.entries.items())
    print(f"{info.folder}: {count} design(s){f' ({kinds})' if kinds else ''}, {_size(info.size)}")
    return 0
