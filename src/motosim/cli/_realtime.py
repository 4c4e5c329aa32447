"""What ``motosim run`` and ``motosim rig`` share: their options' checks (the scenario's
``[realtime]`` table is read by :mod:`motosim.rt.config`)."""

import argparse
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from motosim.cli.rtcheck import check_privilege_options
from motosim.errors import MotosimError
from motosim.params.checks import short_repr

if TYPE_CHECKING:
    from motosim.cueing import CueingConfig

__all__ = [
    "RtOptions",
    "check_rt_options",
    "check_wait",
]


def _platform_address(text: str) -> tuple[str, int]:
    from motosim.rt.telemetry import parse_address

    try:
        return parse_address(text)
    except MotosimError:
        raise MotosimError(
            f"--platform-udp {text!r}; expected HOST:PORT such as 127.0.0.1:47480, or off"
        ) from None


@dataclass(frozen=True)
class RtOptions:
    """The options of run and rig that :func:`check_rt_options` parsed, for the command to use.

    Attributes
    ----------
    telemetry : (str, int) or None
        ``--telemetry`` as (host, port); None when ``off``.
    platform_udp : (str, int) or None
        ``--platform-udp`` as (host, port); None when ``off``.
    platform : CueingConfig or None
        The ``--platform`` file, loaded when ``--platform-udp`` or ``--platform-can`` asks
        for it; else None.
    """

    telemetry: tuple[str, int] | None
    platform_udp: tuple[str, int] | None
    platform: "CueingConfig | None"


def check_rt_options(args: argparse.Namespace) -> RtOptions:
    """Refuse the options of run and rig before any work: --bus, --duration, --telemetry,
    --platform-udp, --platform, --fifo, --cpu, --spin (one line each); return those parsed."""
    from motosim.io.bus_spec import check_bus
    from motosim.rt.telemetry import parse_address

    check_bus(args.bus)
    if args.duration is not None and not (
        math.isfinite(args.duration) and 1e-3 <= args.duration <= 86_400.0
    ):
        raise MotosimError(
            f"--duration {short_repr(args.duration)}; expected seconds from 0.001 to 86400"
        )
    telemetry = None if args.telemetry == "off" else parse_address(args.telemetry)
    platform_udp = None if args.platform_udp == "off" else _platform_address(args.platform_udp)
    platform = None
    if platform_udp is not None or args.platform_can:
        from motosim.cueing import load_platform

        platform = load_platform(args.platform)  # refused here, not after the scenario's designs
    check_privilege_options(args)
    return RtOptions(telemetry, platform_udp, platform)


def check_wait(args: argparse.Namespace) -> None:
    """Refuse ``--wait compiled`` given with ``--pace bus`` or ``--link python-can``.

    The compiled wait ends a clock-paced loop's wait and reads the fast link's socket; those
    runs wait in Python, which the option left out (None) lets pass silently. Reads only the
    options: the line comes before the numerical stack is loaded.

    Raises
    ------
    MotosimError
        Naming both options.
    """
    if args.wait != "compiled":
        return
    if args.pace == "bus":
        raise MotosimError(
            "--wait compiled with --pace bus; the compiled wait applies only to a clock-paced "
            "loop (--pace clock): leave --wait out with --pace bus"
        )
    if args.link == "python-can":
        raise MotosimError(
            "--wait compiled with --link python-can; the compiled wait applies only to the "
            "fast link (--link fast): leave --wait out with --link python-can"
        )
