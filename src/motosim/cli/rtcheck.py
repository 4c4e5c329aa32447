"""``motosim rt-check``: this machine's wake-up latency and missed deadlines at a given rate."""

import argparse
import math
import os
from typing import TYPE_CHECKING, Any

from motosim.cli._common import parse_float_list, print_json, warn_atypical
from motosim.errors import MotosimError
from motosim.params.checks import short_repr
from motosim.rt.clock import MonotonicClock
from motosim.rt.privileges import Privilege, apply_privileges

if TYPE_CHECKING:
    from motosim.rt.check import Verdict
    from motosim.rt.loop import TimingStats
    from motosim.rt.session import PrivilegeRequest

__all__ = [
    "add_link_option",
    "add_privilege_options",
    "check_privilege_options",
    "check_udp_only_options",
    "privilege_request",
    "privileges_from_args",
    "register",
]


def add_link_option(parser: argparse.ArgumentParser) -> None:
    """``--link``, how ``run`` and ``rig`` talk on a udp_multicast bus."""
    parser.add_argument(
        "--link",
        choices=("fast", "python-can"),
        default=None,  # fast; None tells the default from the option given (udp_multicast only)
        help="on udp_multicast, send and read python-can's frames on its socket without a "
        "can.Message per frame (fast, default) or through python-can's bus (the same frames)",
    )


def check_udp_only_options(args: argparse.Namespace) -> None:
    """Refuse ``--link`` (and ``run``'s ``--wait``) given with a bus other than udp_multicast.

    Both options choose how a udp_multicast bus is read; on another bus they would be ignored.
    Their defaults (None: not given) pass silently. Reads only the ``--bus`` text: nothing is
    imported, so the line comes before the numerical stack is loaded.

    Raises
    ------
    MotosimError
        Naming the option, its value and the bus.
    """
    interface = args.bus.partition(":")[0]
    if interface == "udp_multicast":
        return
    for name in ("link", "wait"):
        value = getattr(args, name, None)
        if value is not None:
            raise MotosimError(
                f"--{name} {value} with --bus {short_repr(args.bus)}; --{name} applies only to a "
                "udp_multicast bus: leave it out with this bus"
            )


def add_privilege_options(parser: argparse.ArgumentParser) -> None:
    """The real-time options shared by ``rt-check``, ``run`` and ``rig``."""
    parser.add_argument(
        "--fifo",
        type=int,
        metavar="PRIORITY",
        help=(
            "run under SCHED_FIFO at this priority, 1..99 (needs root, CAP_SYS_NICE or "
            "ulimit -r; default: the normal scheduler)"
        ),
    )
    parser.add_argument(
        "--cpu", metavar="LIST", help="pin the process to these CPUs, e.g. 1 (default: any CPU)"
    )
    parser.add_argument(
        "--mlock", action="store_true", help="lock the process's memory in RAM (mlockall)"
    )
    parser.add_argument(
        "--spin",
        type=float,
        default=200.0,
        metavar="US",
        help="poll the clock for the last US microseconds before each deadline (default 200)",
    )


def _cpus(args: argparse.Namespace) -> list[int] | None:
    if args.cpu is None:
        return None
    values = parse_float_list("--cpu", args.cpu, max_items=4096)
    count = os.cpu_count() or 1
    if not all(0 <= v < count and v == int(v) for v in values):
        raise MotosimError(
            f"--cpu {short_repr(args.cpu)}; expected CPU numbers from 0 to {count - 1} such as 1 "
            "or 0,1"
        )
    return [int(v) for v in values]


def check_privilege_options(args: argparse.Namespace) -> None:
    """Refuse --fifo, --cpu and --spin values before any work (one line each)."""
    if args.fifo is not None and not 1 <= args.fifo <= 99:
        raise MotosimError(f"--fifo {short_repr(args.fifo)}; expected a priority from 1 to 99")
    _cpus(args)
    clock_from_args(args)


def privileges_from_args(args: argparse.Namespace) -> tuple[Privilege, ...]:
    """Apply the privileges asked for on the command line; each reported, none fatal."""
    check_privilege_options(args)
    return apply_privileges(priority=args.fifo, cpus=_cpus(args), mlock=args.mlock)


def privilege_request(args: argparse.Namespace) -> "PrivilegeRequest":
    """The privileges asked for on the command line, checked, to be applied by the loop."""
    from motosim.rt.session import PrivilegeRequest

    check_privilege_options(args)
    cpus = _cpus(args)
    return PrivilegeRequest(args.fifo, None if cpus is None else tuple(cpus), bool(args.mlock))


def clock_from_args(args: argparse.Namespace) -> MonotonicClock:
    """The monotonic clock with the ``--spin`` margin [us] converted to seconds."""
    if not (math.isfinite(args.spin) and 0.0 <= args.spin < 1e6):
        raise MotosimError(f"--spin {args.spin!r}; expected microseconds in [0, 1000000)")
    return MonotonicClock(spin=args.spin * 1e-6)


def register(sub: Any) -> None:
    """Add ``rt-check`` to the subcommands."""
    parser = sub.add_parser(
        "rt-check",
        help="measure this machine's wake-up latency and missed deadlines at a rate",
        description=(
            "Run an empty fixed-rate loop and print the wake-up latency after each deadline "
            "(p50, p99, p99.9, max) and the missed deadlines, then a verdict against the "
            "targets: wake-up p99 <= 100 us, at most 0.1 %% of the deadlines missed, compute "
            "p99 <= a fifth of the period (PASS/FAIL lines; exit 0 if every target is met, "
            "1 if not). Run it first on a new lab PC, with and without --fifo/--cpu/--mlock."
        ),
    )
    parser.add_argument("--rate", type=float, default=1000.0, help="loop rate [Hz] (1000)")
    parser.add_argument("--duration", type=float, default=5.0, help="how long [s] (5)")
    parser.add_argument(
        "--json", action="store_true", help="print the figures and the verdict as JSON"
    )
    add_privilege_options(parser)
    parser.set_defaults(func=run)


def _table(stats: "TimingStats", privileges: tuple[Privilege, ...], verdict: "Verdict") -> str:
    us = 1e6
    lines = [
        f"rate {stats.rate:g} Hz, {stats.periods} deadlines, {stats.served} served",
        f"{'':8}{'p50':>10}{'p99':>10}{'p99.9':>10}{'max':>10}  [us]",
        f"{'wake-up':8}{stats.wake_p50 * us:10.1f}{stats.wake_p99 * us:10.1f}"
        f"{stats.wake_p999 * us:10.1f}{stats.wake_max * us:10.1f}",
        f"missed deadlines: {stats.missed} ({100.0 * stats.miss_ratio:.3f} %)",
    ]
    for p in privileges:
        lines.append(str(p))
    if not privileges:
        lines.append("no real-time privilege asked for (see --fifo, --cpu, --mlock)")
    lines += [check.line() for check in verdict.checks]
    lines.append(
        "verdict: PASS, this PC keeps the targets at this rate"
        if verdict.passed
        else "verdict: FAIL (see the real-time guide: Setting up the lab PC)"
    )
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Measure, print the figures and the verdict; exit 0 if every target is met, else 1."""
    from motosim.rt.check import check_timing, verdict

    if not (math.isfinite(args.rate) and 1.0 <= args.rate <= 100_000.0):
        raise MotosimError(f"--rate {args.rate!r}; expected a rate from 1 to 100000 Hz")
    if not (math.isfinite(args.duration) and 1e-3 <= args.duration <= 86_400.0):
        raise MotosimError(f"--duration {args.duration!r}; expected seconds from 0.001 to 86400")
    warn_atypical("rt-check", "--rate", args.rate)
    warn_atypical("rt-check", "--duration", args.duration)
    check_privilege_options(args)
    clock = clock_from_args(args)
    privileges = privileges_from_args(args)
    stats = check_timing(args.rate, args.duration, clock=clock)
    judged = verdict(stats)
    if args.json:
        print_json(
            {
                "timing": stats.as_dict(),
                "units": "s",
                "privileges": [
                    {"name": p.name, "applied": p.applied, "detail": p.detail} for p in privileges
                ],
                "verdict": judged.as_dict(),
            }
        )
    else:
        print(_table(stats, privileges, judged))
    return 0 if judged.passed else 1
