"""``motosim rig``: the virtual rig, a handlebar and its drive on the bus, in its own process."""

import argparse
import math
import sys
import time
from contextlib import ExitStack
from typing import Any

from motosim.cli._common import (
    StopHandler,
    check_named_input,
    check_scenario_inputs,
    check_scenario_values,
    deferred_warnings,
    print_json,
    warn_atypical,
)
from motosim.cli.rtcheck import (
    add_link_option,
    add_privilege_options,
    check_privilege_options,
    check_udp_only_options,
    clock_from_args,
    privileges_from_args,
)
from motosim.errors import MotosimError

__all__ = ["platform_line", "register"]


def register(sub: Any) -> None:
    """Add ``rig`` to the subcommands."""
    parser = sub.add_parser(
        "rig",
        help="start the virtual rig: the scenario's handlebar and drive on a CAN bus",
        description=(
            "Simulate the scenario's true handlebar and its drive on the bus, answering the "
            "DBC's frames as hardware does (status frames at the scenario's measurement rate, "
            "current commands, E-stop), with the latency, frame loss and faults of the "
            "[realtime.rig] table. The rider's torque profile starts with the first enabled "
            "command; a virtual rider steers by the state that motosim run publishes "
            "(--telemetry). Runs until Ctrl-C or --duration."
        ),
    )
    parser.add_argument("scenario", help="scenario TOML file")
    parser.add_argument(
        "--bus", required=True, help="python-can INTERFACE[:CHANNEL]: udp_multicast, ..."
    )
    parser.add_argument(
        "--duration", type=float, help="stop after this long [s] (default: until stopped)"
    )
    add_link_option(parser)
    parser.add_argument(
        "--rate",
        type=float,
        default=1000.0,
        help="ticks per second [Hz] at which the rig takes commands and sends frames (1000)",
    )
    parser.add_argument(
        "--telemetry",
        default="127.0.0.1:47474",
        metavar="HOST:PORT",
        help="where a virtual rider reads the run's state stream (default 127.0.0.1:47474)",
    )
    parser.add_argument(
        "--platform-udp",
        default="off",
        metavar="HOST:PORT",
        help="also be the motion platform: listen for motosim run's platform datagrams here "
        "and apply the platform's limits and actuator bandwidth (default off)",
    )
    parser.add_argument(
        "--platform-can",
        action="store_true",
        help="also be the motion platform on the bus: take motosim run's PF_COMMAND frames "
        "(--platform-can there) and answer with PF_STATUS frames at 100 Hz",
    )
    parser.add_argument(
        "--platform",
        default="simacom_platform",
        metavar="NAME|FILE",
        help="platform file of the twin (default simacom_platform)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_privilege_options(parser)
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the rig until Ctrl-C or the duration; print what it did; exit 0, or 130 after
    Ctrl-C."""
    check_udp_only_options(args)  # before the numerical stack is imported
    check_privilege_options(args)  # the options first, then the files
    check_scenario_inputs(args.scenario)
    check_named_input(args.platform, "platform file")
    check_scenario_values(args.scenario)  # before the numerical stack is imported
    stops = StopHandler()  # Ctrl-C while the rig starts: counted, not lost in a C callback
    with stops.installed():
        return _run(args, stops)


class _TickStop:
    """Ctrl-C on the rig: its loop ends after the current tick (a first or a second press)."""

    def __init__(self) -> None:
        self.requested = False

    def request_stop(self) -> None:
        """End the rig's loop after the current tick (safe from a signal handler)."""
        self.requested = True

    def emergency_stop(self) -> None:
        """The same: the rig has no torque of its own to fade."""
        self.requested = True


def _run(args: argparse.Namespace, stops: StopHandler) -> int:
    """:func:`run`, with Ctrl-C counted by ``stops`` until the loop takes it over."""
    from motosim.cli._realtime import check_rt_options

    options = check_rt_options(args)  # before the rig and the simulator are imported
    if not (math.isfinite(args.rate) and 1.0 <= args.rate <= 100_000.0):
        raise MotosimError(f"--rate {args.rate!r}; expected a rate from 1 to 100000 Hz")
    from motosim.rt.config import read_realtime, resolve_realtime, rig_settings

    with deferred_warnings():  # the scenario's, once its checks have passed
        scenario, realtime = read_realtime(args.scenario)
        settings = rig_settings(scenario, realtime, origin=args.scenario)
        if not args.rate <= settings.plant_rate:  # before the bus is opened
            raise MotosimError(
                f"--rate {args.rate!r}; expected a rate from 1 to {settings.plant_rate:g} Hz (the "
                "rig's plant_rate)"
            )
        if args.duration is not None and not (args.duration > 0.0):
            raise MotosimError(f"--duration {args.duration!r}; expected seconds > 0")
        print("motosim rig: loading the virtual rig ...", file=sys.stderr, flush=True)
        start = time.monotonic()
        inputs = resolve_realtime(args.scenario, scenario)
    with ExitStack() as held:
        rider = _rider(args, inputs, settings, options, held)
        twin = _twin(args, options, held)
        link = _open_link(held, args)
        rig = _virtual_rig(inputs, settings, link, rider)
        if twin is not None and args.platform_can:
            rig.on_frame = twin.receive_frame
        stops.check()  # Ctrl-C while the rig was built: no run
        sensed = ", each with a torque sensor's HB_TORQUE" if rig.torque_sensor else ""
        print(
            f"motosim rig: ready on {args.bus} ({time.monotonic() - start:.1f} s): "
            f"{args.rate:g} Hz ticks, status frames at {settings.status_rate:g} Hz{sensed}; "
            "Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
        stats, privileges, stopped = _serve(args, rig, twin, link, settings, stops)
    summary = _summary(args, rig, twin, link, stats, privileges)
    _print(args, summary, rig, stats)
    return 130 if stopped else 0


def _open_link(held: ExitStack, args: argparse.Namespace) -> Any:
    """The rig's bus link, closed when ``held`` ends."""
    from motosim.io.can import open_link

    link = open_link(args.bus, fast=args.link != "python-can")
    held.callback(link.close)
    return link


def _rider(
    args: argparse.Namespace, inputs: Any, settings: Any, options: Any, held: ExitStack
) -> Any:
    """The rider's torque: the scenario's profile, or a virtual rider steering by the run's
    state stream (its receiver closed when ``held`` ends)."""
    import numpy as np

    sc = inputs.scenario
    if sc.rider.profile is not None:
        t_fine = np.arange(round(sc.duration * settings.plant_rate) + 1) / settings.plant_rate
        return sc.rider.profile.sample(t_fine, inputs.tables)
    from motosim.rt.rig import VirtualRider
    from motosim.rt.telemetry import StateReceiver, parse_address
    from motosim.sim import build_rig

    world = build_rig(inputs, rng=np.random.default_rng(sc.seed))
    VirtualRider.check(world)  # before its socket is opened
    # --telemetry off: refused by parse_address, as the virtual rider needs the stream
    receiver = StateReceiver(options.telemetry or parse_address(args.telemetry))
    held.callback(receiver.close)
    return VirtualRider(world, receiver, rate=sc.rates.control)


def _twin(args: argparse.Namespace, options: Any, held: ExitStack) -> Any:
    """The motion platform's twin (--platform-udp or --platform-can), or None."""
    if options.platform is None:
        return None
    from motosim.io.can import platform_codecs
    from motosim.rt.platform import PlatformTwin

    twin = PlatformTwin(
        options.platform.platform,
        0.001,
        options.platform_udp,
        codecs=platform_codecs() if args.platform_can else None,
    )
    held.callback(twin.close)
    return twin


def _virtual_rig(inputs: Any, settings: Any, link: Any, rider: Any) -> Any:
    """The scenario's true handlebar and its drive on ``link``."""
    import numpy as np

    from motosim.io.can import handlebar_codecs
    from motosim.rt.rig import RigRider, VirtualRig, torque_sensor
    from motosim.sim.hands import arms_of

    sc = inputs.scenario
    held = RigRider(
        rider,
        arms=arms_of(sc.rider_hands),
        hands_off=np.array(sc.rider.hands_off, dtype=np.float64).reshape(-1, 2),
    )
    return VirtualRig(
        inputs.true_handlebar,
        settings,
        handlebar_codecs(),
        link,
        held,
        np.random.default_rng(sc.seed),
        torque_sensor=torque_sensor(sc),
    )


class _Received:
    """What the rig tells while it runs: its first command frame, then every few seconds
    the commands received and the status frames sent (stderr, once per tick: a count)."""

    EVERY = 5.0
    """Seconds of the rig's time between two lines."""

    def __init__(self, rig: Any) -> None:
        self.rig = rig
        self.seen = 0
        self.next = self.EVERY

    def tick(self) -> None:
        """Print a line when it is due."""
        rig = self.rig
        if not self.seen and rig.commands:
            self.seen = rig.commands
            print(
                f"motosim rig: first command frame at t = {rig.t:.3f} s",
                file=sys.stderr,
                flush=True,
            )
        elif self.seen and rig.t >= self.next:
            self.next += self.EVERY
            print(
                f"motosim rig: t = {rig.t:.0f} s, {rig.commands} commands received, "
                f"{rig.frames_sent} status frames sent",
                file=sys.stderr,
                flush=True,
            )


def _serve(
    args: argparse.Namespace, rig: Any, twin: Any, link: Any, settings: Any, stops: StopHandler
) -> tuple[Any, tuple[Any, ...], bool]:
    """Tick the rig until the duration or Ctrl-C: its loop's timing, the privileges, and
    whether Ctrl-C ended it."""
    from motosim.rt.loop import RateLoop
    from motosim.rt.privileges import freeze_gc, thaw_gc

    rate = args.rate
    warn_atypical("rig", "--rate", args.rate)
    warn_atypical("rig", "--duration", args.duration)
    periods = 2**62 if args.duration is None else round(args.duration * rate)
    loop = RateLoop(rate, clock_from_args(args), capacity=min(periods, 1 << 20))
    privileges = privileges_from_args(args)
    received = _Received(rig)
    stop = _TickStop()
    status_due, t0, last = [0.0], [math.nan], [-1]

    def tick(k: int, t: float) -> bool:
        if t0[0] != t0[0]:
            t0[0] = t
        # a late tick (deadlines skipped) sends the newest status frame, not a backlog
        rig.advance_to(t - t0[0], catch_up=k <= last[0] + 1 or rate < settings.status_rate)
        last[0] = k
        received.tick()
        if twin is not None:
            twin.advance_to(t - t0[0])
            if args.platform_can and twin.t >= status_due[0]:
                status_due[0] += 0.01  # PF_STATUS at 100 Hz
                link.send(*twin.status_frame())
        return not stop.requested

    stops.aim(stop)
    freeze_gc()
    try:
        loop.run(tick, periods=periods)
    finally:
        thaw_gc()
        stops.release()
    return loop.stats(), privileges, stop.requested


def _summary(
    args: argparse.Namespace, rig: Any, twin: Any, link: Any, stats: Any, privileges: Any
) -> dict[str, Any]:
    """The rig's summary (its JSON)."""
    import numpy as np

    platform = None
    if twin is not None:
        platform = {
            "datagrams": twin.frames,
            "can": bool(args.platform_can),
            "lost": twin.lost,
            "late": twin.late,
            "bad": twin.bad,
            "watchdog_timeouts": twin.timeouts,
            "achieved_deg": [float(np.degrees(a)) for a in twin.achieved],
        }
    return {
        "time": rig.t,
        "frames_sent": rig.frames_sent,
        "torque_frames_sent": rig.torque_frames_sent,
        "frames_dropped": rig.frames_dropped,
        "frames_late": rig.frames_late,
        "commands": rig.commands,
        "bad_commands": rig.bad_commands,
        "bus_errors": link.errors,
        "timing": stats.as_dict(),
        "platform": platform,
        "privileges": [
            {"name": p.name, "applied": p.applied, "detail": p.detail} for p in privileges
        ],
    }


def _print(args: argparse.Namespace, summary: dict[str, Any], rig: Any, stats: Any) -> None:
    """The summary, or its JSON."""
    if args.json:
        print_json(summary)
        return
    print(
        f"rig: {rig.t:.3f} s simulated, {rig.frames_sent} status frames sent "
        f"({rig.frames_dropped} dropped, {rig.frames_late} not sent because the rig was "
        f"late), {rig.commands} commands received "
        f"({rig.bad_commands} bad); wake-up p99 {stats.wake_p99 * 1e6:.0f} us, "
        f"missed {stats.missed}"
    )
    platform = summary["platform"]
    if isinstance(platform, dict):
        print(platform_line(platform))


def platform_line(platform: dict[str, Any]) -> str:
    """The platform twin's line of the rig's summary: commands taken, losses, angles reached.

    Parameters
    ----------
    platform : dict of str to Any
        The summary's ``platform`` entry: ``datagrams``, ``can``, ``lost``, ``late``, ``bad``,
        ``watchdog_timeouts`` and ``achieved_deg`` (roll, pitch, yaw [deg]).

    Returns
    -------
    str
        One line, angles in degrees.
    """
    roll, pitch, yaw = platform["achieved_deg"]
    medium = "PF_COMMAND frames" if platform["can"] else "datagrams"
    return (
        f"platform: {platform['datagrams']} {medium} taken ({platform['lost']} lost, "
        f"{platform['late']} late, {platform['bad']} bad), "
        f"{platform['watchdog_timeouts']} watchdog timeouts; at the end roll {roll:.2f}, "
        f"pitch {pitch:.2f}, yaw {yaw:.2f} deg"
    )
