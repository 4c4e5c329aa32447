"""``motosim run``: the stack in real time against the handlebar drive over CAN.

The command parses, builds the run's :class:`~motosim.rt.session.SessionConfig`, runs the
:class:`~motosim.rt.session.RealtimeSession` and prints what happened; Ctrl-C is one
:class:`~motosim.cli._common.StopHandler` (a stop, then an emergency stop).
"""

import argparse
import json
import sys
import threading
import time
from typing import TYPE_CHECKING, Any, NamedTuple

from motosim.cli._common import (
    StopHandler,
    _finite_or_none,
    check_named_input,
    check_result_folder,
    check_scenario_inputs,
    check_scenario_values,
    deferred_warnings,
    print_json,
    warn_atypical,
    write_text,
)
from motosim.cli._realtime import (
    RtOptions,
    check_rt_options,
    check_wait,
    load_realtime,
    read_realtime,
    resolve_realtime,
)
from motosim.cli.cache import add_cache_option, design_cache
from motosim.cli.rtcheck import (
    add_link_option,
    add_privilege_options,
    check_privilege_options,
    check_udp_only_options,
    clock_from_args,
    privilege_request,
)
from motosim.errors import MotosimError, RunFailedError
from motosim.params.checks import short_repr

if TYPE_CHECKING:
    from motosim.rt.session import Outcome, RealtimeSession, SessionConfig

__all__ = ["load_realtime", "register"]


def register(sub: Any) -> None:
    """Add ``run`` to the subcommands."""
    parser = sub.add_parser(
        "run",
        help="run the stack in real time against the handlebar over CAN",
        description=(
            "Run the scenario's stack in real time: read the drive's status frames, step the "
            "compiled stack at the control rate, pass the command through the safety stage and "
            "send it. Writes DIR/result.h5 and DIR/result.csv (as simulate does, one row per "
            "control period) and DIR/timing.json. At the end of the duration, and on Ctrl-C, "
            "the torque fades out; a "
            "second Ctrl-C, or Enter on the terminal, is an emergency stop."
        ),
    )
    parser.add_argument("scenario", help="scenario TOML file with a [realtime.safety] table")
    parser.add_argument(
        "--bus",
        required=True,
        help="python-can INTERFACE[:CHANNEL]: socketcan:can0, virtual, udp_multicast, ...",
    )
    parser.add_argument("--out", required=True, help="folder for the result")
    add_link_option(parser)
    parser.add_argument(
        "--duration", type=float, help="run for this long [s] (default: the scenario's)"
    )
    parser.add_argument(
        "--pace",
        choices=("clock", "bus"),
        default="clock",
        help="what starts each control period: this PC's clock (absolute deadlines, default) "
        "or the drive's status frame (one period per frame; needs the control rate equal to "
        "the measurement rate; the watchdog still trips if the frames stop)",
    )
    parser.add_argument(
        "--wait",
        choices=("compiled", "python"),
        default=None,  # compiled; None tells the default from the option given
        help="how a clock-paced loop ends its wait: 'compiled' (default) spins to the "
        "deadline, reads the bus and runs the period in one compiled call (the fast "
        "udp_multicast link, on Linux; Python elsewhere); 'python' spins and reads in Python",
    )
    parser.add_argument(
        "--warm",
        choices=("on", "off"),
        default="on",
        help="a clock-paced loop steps a copy of the stack, thrown away, in the last 50 us "
        "before each deadline, so that its step finds its code and data in the CPU's caches: "
        "'on' (default) or 'off' (the wait only spins; the rows are the same)",
    )
    _add_output_options(parser)
    add_privilege_options(parser)
    add_cache_option(parser)
    parser.set_defaults(func=run)


def _add_output_options(parser: argparse.ArgumentParser) -> None:
    """What ``run`` sends beside the drive's frames and what it writes and prints."""
    parser.add_argument(
        "--telemetry",
        default="127.0.0.1:47474",
        metavar="HOST:PORT",
        help="publish the stack's state each period as UDP datagrams here, or 'off' "
        "(the virtual rig's virtual rider steers by it; default 127.0.0.1:47474)",
    )
    parser.add_argument(
        "--platform-udp",
        default="off",
        metavar="HOST:PORT",
        help="send the motion platform's roll, pitch, yaw commands (washout cueing, faded with "
        "the handlebar's safety stage) as 48-byte UDP datagrams at 100 Hz here, or 'off' "
        "(default)",
    )
    parser.add_argument(
        "--platform-can",
        action="store_true",
        help="send the same platform commands as PF_COMMAND frames of the shipped DBC on the "
        "run's --bus at 100 Hz (instead of or beside --platform-udp)",
    )
    parser.add_argument(
        "--platform",
        default="simacom_platform",
        metavar="NAME|FILE",
        help="platform file for --platform-udp and --platform-can (default simacom_platform)",
    )
    parser.add_argument(
        "--view",
        action="store_true",
        help="serve the rider's view and the dashboard (fed by the result writer, outside the "
        "loop); the torque stays off until Arm is pressed there; Stop = Ctrl-C "
        "(needs pip install 'motosim[view]')",
    )
    parser.add_argument(
        "--view-port", type=int, default=8000, help="TCP port of the view (default 8000; 0: any)"
    )
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument(
        "--overwrite", action="store_true", help="replace a result already in the folder"
    )
    parser.add_argument(
        "--no-report", dest="report", action="store_false", help="skip the HTML report"
    )


def run(args: argparse.Namespace) -> int:
    """Run in real time; write the result; exit 0, 130 after Ctrl-C, 3 on a fall or a fault."""
    check_udp_only_options(args)  # before the numerical stack is imported
    check_wait(args)
    check_privilege_options(args)  # the options first, then the files
    check_scenario_inputs(args.scenario)
    check_named_input(args.platform, "platform file")
    check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    check_scenario_values(args.scenario)  # before the numerical stack is imported
    if not 0 <= args.view_port < 65536:
        raise MotosimError(f"--view-port {short_repr(args.view_port)}; expected 0..65535")
    options = check_rt_options(args)  # before the stack and the simulator are imported
    stops = StopHandler()
    with stops.installed():
        with deferred_warnings():  # the scenario's, once every check has passed
            checked = _check(args)  # every refusal before the loading line
            print("motosim run: loading the compiled stack ...", file=sys.stderr, flush=True)
            start = time.monotonic()
            config = _config(args, options, checked)
        warn_atypical("run", "--duration", args.duration)  # once every check has passed
        from motosim.rt.session import RealtimeSession

        with RealtimeSession(config, clock_from_args(args)) as session:
            session.prepare()
            stops.check()  # Ctrl-C while the stack loaded: no run
            print(
                f"motosim run: the stack is ready ({time.monotonic() - start:.1f} s)",
                file=sys.stderr,
                flush=True,
            )
            stops.aim(session)  # from now on Ctrl-C is a stop, then an E-stop
            outcome = _run(args, session)
            stops.release()  # the loop has ended: Ctrl-C interrupts what is left
            write_text(outcome.folder / "timing.json", _json(outcome.report))
            html = None
            if args.report:
                from motosim.report import build_report

                html = build_report(outcome.folder)
    return _print(args, config, outcome, html)


class _Checked(NamedTuple):
    """The scenario and the options, checked: what :func:`_config` builds the run from."""

    scenario: Any
    realtime: dict[str, Any]
    limits: Any
    latency: float
    age: float
    cache: Any


def _check(args: argparse.Namespace) -> _Checked:
    """Read the scenario and refuse what a real-time run cannot take (one line each)."""
    from motosim.rt.config import (
        frame_age,
        parse_latency,
        parse_safety,
        refuse_offline_only,
        run_paces,
    )

    cache = design_cache(args, quiet=args.json)
    sc, realtime = read_realtime(args.scenario, safety=True, pace=args.pace)
    refuse_offline_only(sc, origin=args.scenario)
    limits = parse_safety(realtime.get("safety"), origin=args.scenario)
    rate, measurement = sc.rates.control, sc.rates.measurement
    latency = parse_latency(realtime, origin=args.scenario)
    age = frame_age(
        latency,
        pace=args.pace,
        control_rate=rate,
        measurement_rate=measurement,
        origin=args.scenario,
    )
    if args.pace not in run_paces(rate, measurement):
        raise MotosimError(
            f"--pace bus with control = {rate:g} Hz and measurement = {measurement:g} Hz; "
            "expected equal rates (one period per status frame)"
        )
    if args.view:
        from motosim.view.app import _need_starlette

        _need_starlette()
    return _Checked(sc, realtime, limits, latency, age, cache)


def _config(args: argparse.Namespace, options: RtOptions, checked: _Checked) -> "SessionConfig":
    """The run resolved, its stack designed: the session's configuration."""
    from motosim.io.cache import cached_stack
    from motosim.rt.config import within_safety
    from motosim.rt.session import SessionConfig
    from motosim.sim import run_metadata
    from motosim.sim.stack import account_for_delay

    folder = check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    cache, limits = checked.cache, checked.limits
    inputs = resolve_realtime(args.scenario, checked.scenario, cache)
    inputs = within_safety(inputs, limits)  # the stack saturates where the clamp cuts
    sc = inputs.scenario
    duration = sc.duration if args.duration is None else args.duration
    live = None
    if args.view:
        from motosim.cli._liveview import view_sink

        live = view_sink(args, inputs, duration, limits)
    with cache.designing(sc.name):
        model = cached_stack(cache, inputs)
    model = account_for_delay(model, checked.age, inputs.design_handlebar)  # the frames' age
    udp = args.bus.partition(":")[0] == "udp_multicast"
    link = "fast" if args.link != "python-can" and udp else "python-can"
    metadata = run_metadata(inputs) | {
        "realtime": {
            "bus": args.bus,
            "link": link,
            "pace": args.pace,
            "status_latency": checked.latency,
            "measurement_delay": checked.age,
            "safety": limits,
            "duration": duration,
        }
    }
    return SessionConfig(
        inputs,
        model,
        limits,
        args.bus,
        folder,
        metadata,
        duration,
        pace=args.pace,
        wait=args.wait or "compiled",
        fast_link=args.link != "python-can",
        warm=args.warm == "on",
        overwrite=args.overwrite,
        telemetry=options.telemetry,
        platform=options.platform,
        platform_udp=options.platform_udp,
        platform_can=args.platform_can,
        live=live,
        privileges=privilege_request(args),
    )


def _run(args: argparse.Namespace, session: "RealtimeSession") -> "Outcome":
    """Open the result, say how to stop, run the loop."""
    err = sys.stderr
    url = session.open()
    live = session.config.live
    if url is not None and live is not None:
        token = getattr(live, "token", "")
        print(f"motosim run: rider's view {url}/?token={token}", file=err)
        print(f"motosim run: dashboard    {url}/dashboard?token={token}", file=err)
        print("motosim run: the torque is off until Arm is pressed", file=err, flush=True)
    if sys.stdin is not None and sys.stdin.isatty():
        threading.Thread(target=_keyboard, args=(session,), daemon=True).start()
        print("motosim run: Enter = emergency stop, Ctrl-C = stop", file=err)
    c = session.config
    paced = "clock" if c.pace == "clock" else "status frames"
    print(
        f"motosim run: {c.rate:g} Hz on {c.bus}, paced by the {paced}, {c.duration:g} s",
        file=err,
        flush=True,
    )
    return session.run()


def _keyboard(session: "RealtimeSession") -> None:
    """Enter on the terminal: emergency stop."""
    for _ in sys.stdin:
        session.emergency_stop()
        return


def _json(payload: Any) -> str:
    return json.dumps(_finite_or_none(payload), indent=2, allow_nan=False) + "\n"


def _print(args: argparse.Namespace, config: "SessionConfig", outcome: "Outcome", html: Any) -> int:
    """The summary (or its JSON) and the exit code of the outcome."""
    from motosim.rt.check import advice
    from motosim.rt.session import Ending

    folder, stats, counters = outcome.folder, outcome.stats, outcome.counters
    if args.json:
        print_json({"out": str(folder), "report": str(html) if html else None} | outcome.report)
    else:
        wake = "wake-up" if config.pace == "clock" else "frame interval jitter"
        gaps = f", {stats.gaps} frame periods without a frame" if config.pace == "bus" else ""
        print(
            f"{config.inputs.scenario.name}: {stats.served} periods at {stats.rate:g} Hz, "
            f"result in {folder}"
        )
        print(
            f"  {wake} p99 {stats.wake_p99 * 1e6:.0f} us, compute p99 "
            f"{stats.compute_p99 * 1e6:.0f} us, missed {stats.missed} of "
            f"{stats.periods}{gaps}"
        )
        for p in outcome.privileges:
            print(f"  {p}")
        print(f"  state {counters.state}; {counters.fault_reason}")
        if counters.frames_lost > max(10, counters.status_frames // 10):
            print(
                f"  {counters.frames_lost} status frames lost for {counters.status_frames} "
                "received: is a second rig or drive on this bus? (udp_multicast: give each "
                "rig and run pair a group of its own, --bus udp_multicast:239.74.163.50)"
            )
        asked = config.privileges.all_given
        for line in advice(
            stats, counters.fault, asked_all=asked, privileges=outcome.privileges, bus=config.bus
        ):
            print(f"  {line}")
    name = config.inputs.scenario.name
    if outcome.ending is Ending.FELL:
        raise RunFailedError(
            f"{name}: {outcome.reason}; the result is in {folder}, flagged", time=outcome.time
        )
    if outcome.ending is Ending.FAULT:
        raise RunFailedError(
            f"safety fault: {outcome.reason}; the result until then is in {folder}",
            time=outcome.time,
        )
    if outcome.ending is Ending.STOPPED:
        how = (
            "emergency stop, torque zeroed"
            if counters.fault != "NONE"
            else "stopped, torque faded out"
        )
        print(f"motosim run: {how}; result in {folder}", file=sys.stderr)
        return 130
    return 0
