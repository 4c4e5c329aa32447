"""``motosim view`` and ``motosim telemetry``: ride a saved result in the browser, export it."""

import argparse
import ipaddress
import math
import sys
import time
from typing import Any

from motosim.cli._common import check_output, check_result_input, warn_atypical
from motosim.errors import MotosimError
from motosim.params.checks import short_repr

__all__ = ["register"]


def _address(option: str, text: str, default_port: int) -> tuple[str, int]:
    from motosim.rt.telemetry import is_host

    host, _, port = text.partition(":")
    if not is_host(host) or (port and not (port.isdigit() and len(port) <= 5)):
        raise MotosimError(f"{option} {short_repr(text)}; expected HOST or HOST:PORT")
    number = int(port) if port else default_port
    if not 0 < number < 65536:
        raise MotosimError(f"{option} port {number}; expected 1 to 65535")
    return host, number


def _check_rate(rate: float) -> None:
    if not (math.isfinite(rate) and 0.01 <= rate <= 1000.0):
        raise MotosimError(f"--rate {rate!r}; expected a replay speed from 0.01 to 1000")


def _cueing(folder: str) -> Any:
    """The result of ``motosim cueing`` in ``folder``; another command's is refused."""
    from motosim.cueing.washout import WASHOUT_OUTPUTS
    from motosim.io.results import load_result

    cue = load_result(folder)
    missing = [name for name in WASHOUT_OUTPUTS if name not in cue.names]
    if missing:
        raise MotosimError(
            f"--cueing {folder}: a result without {', '.join(missing)}; expected a folder "
            "written by motosim cueing (its platform commands)"
        )
    return cue


def register(sub: Any) -> None:
    """Add ``view`` and ``telemetry`` to the subcommands."""
    view = sub.add_parser(
        "view",
        help="ride a saved result in the browser: the rider's view and a dashboard",
        description=(
            "Serve the rider's view (three.js) and a live dashboard of a result folder written "
            "by motosim simulate, replayed against the clock; open the printed address. "
            "Reading is open to whoever reaches the server; play/pause/seek need the token "
            "in the address. Needs the optional group: pip install 'motosim[view]'."
        ),
    )
    view.add_argument("folder", help="a result folder written by motosim simulate")
    view.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    view.add_argument("--port", type=int, default=8000, help="TCP port (default 8000; 0: any)")
    view.add_argument("--rate", type=float, default=1.0, help="replay speed (1: real time)")
    view.add_argument("--loop", action="store_true", help="start over at the end")
    view.add_argument(
        "--cueing",
        metavar="DIR",
        help=(
            "a folder written by motosim cueing for this result: plot its platform commands "
            "(default: none)"
        ),
    )
    view.set_defaults(func=run_view)

    telemetry = sub.add_parser(
        "telemetry",
        help="export a saved result as MCAP, or stream it to PlotJuggler or esmini over UDP",
        description=(
            "Write a result folder as an MCAP file (Foxglove, Lichtblick) and/or replay it in "
            "real time as PlotJuggler UDP JSON and esmini ControllerUDPDriver pose packets."
        ),
    )
    telemetry.add_argument("folder", help="a result folder written by motosim simulate")
    telemetry.add_argument("--mcap", help="MCAP file to write (default: none)")
    telemetry.add_argument("--every", type=int, default=1, help="keep one row in EVERY (MCAP)")
    telemetry.add_argument(
        "--plotjuggler",
        metavar="HOST[:PORT]",
        help="stream UDP JSON to PlotJuggler (port 9870; default: off)",
    )
    telemetry.add_argument(
        "--esmini",
        metavar="HOST[:PORT]",
        help="stream the pose to esmini's UDP driver (port 49950; default: off)",
    )
    telemetry.add_argument("--rate", type=float, default=1.0, help="stream speed (1: real time)")
    telemetry.set_defaults(func=run_telemetry)


def run_view(args: argparse.Namespace) -> int:
    """Serve the view of a result until interrupted."""
    from motosim.rt.telemetry import is_host

    if not 0 <= args.port < 65536:
        raise MotosimError(f"--port {short_repr(args.port)}; expected 0..65535")
    if not is_host(args.host):
        raise MotosimError(f"--host {short_repr(args.host)}; expected an IP address or host name")
    _check_rate(args.rate)
    check_result_input(args.folder)
    if args.cueing is not None:
        check_result_input(args.cueing, "cueing folder")
    import json
    from pathlib import Path

    from motosim.io.results import load_result
    from motosim.view.app import ServerThread, create_app, new_token
    from motosim.view.feeds import ReplayFeed, merge_signals, road_from_xy

    result = load_result(args.folder)
    series = result if args.cueing is None else merge_signals(result, _cueing(args.cueing))
    warn_atypical("view", "--rate", args.rate)
    feed = ReplayFeed(series, rate=args.rate, loop=args.loop)
    road = road_from_xy(result["x"], result["y"])
    token = new_token()
    title = str(result.metadata.get("scenario", {}).get("name", args.folder))
    recorded = None
    timing = Path(args.folder) / "timing.json"  # written by motosim run
    if timing.is_file():
        try:
            recorded = json.loads(timing.read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError):
            raise MotosimError(f"{timing}: not valid JSON; expected motosim run's") from None
    app = create_app(feed, road, token=token, title=title, recorded=recorded)
    try:
        local = ipaddress.ip_address(args.host).is_loopback
    except ValueError:
        local = args.host == "localhost"
    if not local:
        print(
            f"motosim: warning: serving on {args.host}, reachable from the network", file=sys.stderr
        )
    server = ServerThread(app, args.host, args.port).start()
    print(f"rider's view: {server.url}/?token={token}")
    print(f"dashboard:    {server.url}/dashboard?token={token}")
    print("Ctrl-C stops the server.", flush=True)
    try:
        while True:
            time.sleep(0.5)
    finally:
        server.stop()


def run_telemetry(args: argparse.Namespace) -> int:
    """Write and/or stream a result's telemetry."""
    if not (args.mcap or args.plotjuggler or args.esmini):
        raise MotosimError("nothing to do; expected --mcap, --plotjuggler or --esmini")
    _check_rate(args.rate)
    if not 1 <= args.every <= 1_000_000:
        raise MotosimError(f"--every {short_repr(args.every)}; expected 1 to 1000000")
    check_result_input(args.folder)
    if args.mcap:
        check_output(args.mcap, overwrite=False, option="--mcap", suffixes=(".mcap",))
    import numpy as np

    from motosim.io.results import load_result
    from motosim.io.telemetry import (
        ESMINI_PORT,
        PLOTJUGGLER_PORT,
        EsminiUdp,
        PlotJugglerUdp,
        write_mcap,
    )

    addresses = [
        _address("--plotjuggler", args.plotjuggler, PLOTJUGGLER_PORT) if args.plotjuggler else None,
        _address("--esmini", args.esmini, ESMINI_PORT) if args.esmini else None,
    ]
    result = load_result(args.folder)
    warn_atypical("telemetry", "--rate", args.rate)
    if args.mcap:
        count = write_mcap(result, args.mcap, every=args.every)
        print(f"{args.mcap}: {count} messages")
    sinks: list[PlotJugglerUdp | EsminiUdp] = []
    if addresses[0] is not None:
        sinks.append(PlotJugglerUdp(*addresses[0]))
    if addresses[1] is not None:
        host, port = addresses[1]
        sinks.append(EsminiUdp(host, port=port))
    if sinks:
        names = ("t", *result.names)
        table = np.column_stack([result.t, result.data])
        start = time.monotonic()
        step = max(1, round(1.0 / (60.0 * float(np.median(np.diff(result.t))))))
        try:
            for k in range(0, table.shape[0], step):
                rows = table[k : k + step]
                for sink in sinks:
                    sink.send(names, rows)
                ahead = start + (float(rows[-1, 0]) - result.t[0]) / args.rate - time.monotonic()
                if ahead > 0:
                    time.sleep(ahead)
        finally:
            for sink in sinks:
                sink.close()
        print(f"streamed {table.shape[0]} rows to {len(sinks)} UDP sink(s)")
    return 0
