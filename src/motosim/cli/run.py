"""``motosim run``: the stack in real time against the handlebar drive over CAN.

The command parses its options into a :class:`~motosim.rt.request.RunRequest`, has
:mod:`motosim.rt.request` check it and build the run's configuration, runs the
:class:`~motosim.rt.session.RealtimeSession` and prints what happened; Ctrl-C is one
:class:`~motosim.cli._common.StopHandler` (a stop, then an emergency stop).
"""

import argparse
import json
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

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
from motosim.cli._realtime import RtOptions, check_rt_options, check_wait
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
    from motosim.rt.request import RunRequest
    from motosim.rt.session import Outcome, RealtimeSession, SessionConfig

__all__ = ["register"]


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
    check_udp_only_options(args)  # the options first, then the files, before the stack loads
    check_wait(args)
    check_privilege_options(args)
    check_scenario_inputs(args.scenario)
    check_named_input(args.platform, "platform file")
    folder = check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    check_scenario_values(args.scenario)
    if not 0 <= args.view_port < 65536:
        raise MotosimError(f"--view-port {short_repr(args.view_port)}; expected 0..65535")
    options = check_rt_options(args)
    stops = StopHandler()
    with stops.installed():
        from motosim.rt.request import check_run, session_config

        request = _request(args, options, folder)

        with deferred_warnings():  # the scenario's, once every check has passed
            cache = design_cache(args, quiet=args.json)
            checked = check_run(request)  # every refusal before the loading line
            if args.view:
                from motosim.view.app import _need_starlette

                _need_starlette()
            print("motosim run: loading the compiled stack ...", file=sys.stderr, flush=True)
            start = time.monotonic()
            config = session_config(request, checked, cache, live=_live_view(args))
        warn_atypical("run", "--duration", args.duration)  # once every check has passed
        from motosim.rt.session import RealtimeSession

        with RealtimeSession(config, clock_from_args(args)) as session:
            session.prepare()
            stops.check()  # Ctrl-C while the stack loaded: no run
            took = time.monotonic() - start
            print(f"motosim run: the stack is ready ({took:.1f} s)", file=sys.stderr, flush=True)
            stops.aim(session)  # from now on Ctrl-C is a stop, then an E-stop
            outcome = _run(session)
            stops.release()  # the loop has ended: Ctrl-C interrupts what is left
            payload = _finite_or_none(outcome.report)
            timing = json.dumps(payload, indent=2, allow_nan=False) + "\n"
            write_text(outcome.folder / "timing.json", timing)
            html = None
            if args.report:
                from motosim.report import build_report

                html = build_report(outcome.folder)
    return _print(args, config, outcome, html)


def _request(args: argparse.Namespace, options: RtOptions, folder: Path) -> "RunRequest":
    """The checked options as the run's request."""
    from motosim.rt.request import RunRequest
    from motosim.rt.session import RunOptions

    how = RunOptions(
        pace=args.pace,
        wait=args.wait or "compiled",
        fast_link=args.link != "python-can",
        warm=args.warm == "on",
        overwrite=args.overwrite,
        telemetry=options.telemetry,
        platform=options.platform,
        platform_udp=options.platform_udp,
        platform_can=args.platform_can,
        privileges=privilege_request(args),
    )
    return RunRequest(args.scenario, args.bus, folder, args.duration, how)


def _live_view(args: argparse.Namespace) -> Any:
    """What builds the rider's view of ``--view`` (None without)."""
    if not args.view:
        return None
    from motosim.cli._liveview import view_sink

    return lambda inputs, duration, limits: view_sink(args, inputs, duration, limits)


def _run(session: "RealtimeSession") -> "Outcome":
    """Open the result, say how to stop, run the loop."""
    err = sys.stderr
    url = session.open()
    c = session.config
    if url is not None and c.live is not None:
        token = getattr(c.live, "token", "")
        print(f"motosim run: rider's view {url}/?token={token}", file=err)
        print(f"motosim run: dashboard    {url}/dashboard?token={token}", file=err)
        print("motosim run: the torque is off until Arm is pressed", file=err, flush=True)
    if sys.stdin is not None and sys.stdin.isatty():
        threading.Thread(target=_keyboard, args=(session,), daemon=True).start()
        print("motosim run: Enter = emergency stop, Ctrl-C = stop", file=err)
    paced = "clock" if c.options.pace == "clock" else "status frames"
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


def _print(args: argparse.Namespace, config: "SessionConfig", outcome: "Outcome", html: Any) -> int:
    """The summary (or its JSON) and the exit code of the outcome."""
    from motosim.rt.request import summary_lines
    from motosim.rt.session import Ending

    folder = outcome.folder
    if args.json:
        print_json({"out": str(folder), "report": str(html) if html else None} | outcome.report)
    else:
        print("\n".join(summary_lines(config, outcome)))
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
        zeroed = outcome.counters.fault != "NONE"
        how = "emergency stop, torque zeroed" if zeroed else "stopped, torque faded out"
        print(f"motosim run: {how}; result in {folder}", file=sys.stderr)
        return 130
    return 0
