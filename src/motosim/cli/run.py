"""``motosim run``: the stack in real time against the handlebar drive over CAN."""

import argparse
import logging
import math
import signal
import sys
import threading
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from motosim.cli._common import (
    check_named_input,
    check_result_folder,
    check_scenario_inputs,
    check_scenario_values,
    deferred_warnings,
    print_json,
    warn_atypical,
    write_text,
)
from motosim.cli.cache import add_cache_option, design_cache
from motosim.cli.rtcheck import (
    add_link_option,
    add_privilege_options,
    check_privilege_options,
    check_udp_only_options,
    clock_from_args,
    privileges_from_args,
)
from motosim.errors import MotosimError, RunFailedError, stop_signals, warn
from motosim.params.checks import short_repr
from motosim.params.toml import read_toml

if TYPE_CHECKING:
    import numpy as np

    from motosim.cueing import CueingConfig
    from motosim.io.cache import DesignCache
    from motosim.rt.rig import RigSettings
    from motosim.sim import RunInputs, Scenario

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
    add_privilege_options(parser)
    add_cache_option(parser)
    parser.set_defaults(func=run)


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


def load_realtime(
    path: str, *, safety: bool = False, pace: str | None = None, cache: "DesignCache | None" = None
) -> tuple["RunInputs", dict[str, Any]]:
    """Read a scenario file: its resolved run and its ``[realtime]`` table.

    With ``safety``, a missing ``[realtime.safety]`` table is refused before the run is
    resolved (which designs its controller: seconds). A ``status_latency`` that makes the
    status frame older than the stack accounts for is refused then too, in the line
    ``motosim run`` gives (:func:`motosim.rt.config.frame_age`): for ``motosim run`` at its
    ``pace``; without a ``pace`` (``motosim rig``, which serves whichever run comes) at the
    pace of ``run`` that reads the frame youngest at the scenario's rates
    (:func:`motosim.rt.config.run_paces`), so that a lab learns it before starting the rig.
    The rig thus keeps a latency that ``run --pace clock`` refuses and ``run --pace bus``
    takes (equal control and measurement rates: up to a frame period against half a control
    period less). The rig's own ``[realtime.rig]`` latency, the bus it emulates, is not
    bounded by the frame period: a slow bus is what it is there to show ``run``. The designs
    come from ``cache`` when one is given.
    """
    from motosim.io.runs import resolve
    from motosim.rt.config import frame_age, parse_latency, parse_safety, run_paces, split_realtime
    from motosim.sim import parse_scenario
    from motosim.sim.scenario import implausible

    source = Path(path)
    data = read_toml(source, what="scenario file")
    rest, realtime = split_realtime(data, origin=str(path))
    scenario = parse_scenario(rest, origin=str(path))
    for line in implausible(scenario):
        warn(f"{path}: {line}")
    # both tables are checked whichever command reads the file: a typo in the table the
    # other command uses is refused now, not when that command runs
    if "safety" in realtime or safety:
        parse_safety(realtime.get("safety"), origin=str(path))
    rates = scenario.rates
    frame_age(
        parse_latency(realtime, origin=str(path)),
        pace=pace or run_paces(rates.control, rates.measurement)[-1],
        control_rate=rates.control, measurement_rate=rates.measurement, origin=str(path),
    )  # fmt: skip
    rig_settings(scenario, realtime, origin=str(path))
    _check_realtime_motorcycle(scenario, origin=str(path))
    if cache is None:
        return resolve(scenario, source.parent), realtime
    with cache.designing(scenario.name):
        return resolve(scenario, source.parent, cache=cache), realtime


def _check_realtime_motorcycle(scenario: "Scenario", *, origin: str) -> None:
    """Refuse what the real-time loop does not read of a multibody motorcycle: its drive and
    brake torques and the road's friction change only offline (motosim simulate)."""
    from motosim.sim.scenario import ConstantProfile, Road

    mc = scenario.motorcycle
    if mc.model != "multibody":
        return
    for key in ("drive_torque", "front_brake_torque", "rear_brake_torque"):
        if getattr(mc, key) != ConstantProfile(0.0):
            raise MotosimError(
                f"{origin}: [motorcycle] {key} on the multibody motorcycle is read offline "
                "only (motosim simulate); expected none in real time"
            )
    if scenario.road != Road():
        raise MotosimError(
            f"{origin}: [road] friction is read offline only (motosim simulate); expected "
            "none in real time (the road's friction 1)"
        )


def rig_settings(scenario: "Scenario", realtime: dict[str, Any], *, origin: str) -> "RigSettings":
    """The virtual rig's settings: the ``[realtime.rig]`` table over the scenario's values."""
    from motosim.rt.rig import parse_rig

    return parse_rig(
        realtime.get("rig", {}),
        base={
            "plant_rate": scenario.rates.plant,
            "status_rate": scenario.rates.measurement,
            "encoder_bits": scenario.measurement.encoder_bits,
            "current_noise": scenario.measurement.current_noise,
            "max_current": scenario.controller.max_current,
        },
        where=f"{origin}: [realtime.rig]",
    )


class _EarlyStopError(Exception):
    """The run ended before its duration (stop or fault): the result is kept, incomplete."""


@dataclass(frozen=True)
class _ViewSetup:
    """What the writer process needs to serve the view (picklable)."""

    token: str
    port: int
    road_x: "np.ndarray"
    road_y: "np.ndarray"
    duration: float
    title: str
    control: Any  # the sending end of a pipe to the loop's process
    watchdog_periods: int = 3


class _LoopControl:
    """The view's arm/stop, sent to the loop's process; the state read from the loop's rows."""

    def __init__(self, conn: Any) -> None:
        self._conn = conn
        self._lock = threading.Lock()
        self.current = "waiting"

    def _send(self, action: str) -> None:
        with self._lock:
            try:
                self._conn.send(action)
            except OSError:  # the loop has ended
                pass

    def arm(self) -> None:
        """Arm: the loop enables the safety stage (a fade-in)."""
        self._send("arm")

    def stop(self) -> None:
        """Stop as Ctrl-C does: the torque fades out and the run ends."""
        self._send("stop")

    def state(self) -> str:
        """The safety stage's state in the last row drained: ``waiting`` before the first,
        then ``idle``, ``fade_in``, ``running``, ``stopping`` or ``fault``."""
        return self.current


def _start_view(view: _ViewSetup, ring: Any) -> tuple[Any, _LoopControl, str]:
    """Serve the view of ``ring`` in this (the writer's) process; returns server, control, URL."""
    from motosim.view.app import ServerThread, create_app
    from motosim.view.feeds import LiveFeed, Road

    control = _LoopControl(view.control)
    feed = LiveFeed(ring, control, view.duration, view.watchdog_periods)
    app = create_app(feed, Road(view.road_x, view.road_y), token=view.token, title=view.title)
    server = ServerThread(app, "127.0.0.1", view.port).start()
    return server, control, server.url


def _writer_main(
    conn: Any,
    handle: Any,
    names: tuple[str, ...],
    folder: str,
    metadata: dict[str, Any],
    overwrite: bool,
    torque_per_amp: float,
    view: _ViewSetup | None = None,
    telemetry: tuple[str, int] | None = None,
    rate: float = 1000.0,
) -> None:
    """The writer process: drain the loop's shared ring into the result files every 0.1 s
    (and, with ``view``, into the view's ring every 5 ms); with ``telemetry``, publish the
    state stream there from the ring's newest row every 1 ms, in a thread
    (:class:`~motosim.rt.telemetry.StateRelay`: the loop sends no datagram of its own).

    Writing files takes milliseconds with the interpreter lock held; in its own process it
    cannot delay the loop. Messages on ``conn``: ("ready", view URL or None) or ("error",
    text) first; then, on ("close", complete, extra summary), the last rows are written and
    ("done", summary, folder, profile, state stream figures) sent back. With ``view``, it
    also serves the rider's view and the dashboard from a
    :class:`~motosim.io.telemetry.TelemetryRing` it fills every 5 ms, with the loop's timing
    and safety columns (:class:`~motosim.view.live.LoopRows`).

    The folder's lock (:func:`~motosim.io.results.folder_lock`) is taken before the result
    is opened, which joins it, and held after the result is closed, until ("release",) or
    the end of ``conn``: ``motosim run`` writes ``timing.json`` and the report beside the
    rows meanwhile, and a concurrent ``--overwrite`` of the folder is refused until then.
    """
    # Ctrl-C is the loop's to handle, and so are SIGTERM and SIGHUP, which a closed terminal
    # or a service manager sends the whole process group: the loop fades the torque out and
    # asks this process to close the result, as on Ctrl-C
    for sig in (signal.SIGINT, *stop_signals()):
        signal.signal(sig, signal.SIG_IGN)
    from motosim.io.results import folder_lock

    with ExitStack() as held:
        try:
            held.enter_context(folder_lock(Path(folder), shared=True))
        except MotosimError as err:
            conn.send(("error", str(err)))
            return
        if _write_result(conn, handle, names, folder, metadata, overwrite, torque_per_amp,
                         view, telemetry, rate):  # fmt: skip
            try:
                conn.recv()  # ("release",): motosim run has written its files
            except (EOFError, OSError):  # or has ended
                pass


def _write_result(
    conn: Any,
    handle: Any,
    names: tuple[str, ...],
    folder: str,
    metadata: dict[str, Any],
    overwrite: bool,
    torque_per_amp: float,
    view: _ViewSetup | None,
    telemetry: tuple[str, int] | None,
    rate: float,
) -> bool:
    """:func:`_writer_main` under the folder's lock: False once ("error", text) is sent,
    True once ("done", ...) is."""
    import numpy as np

    from motosim.io.results import ResultWriter
    from motosim.io.telemetry import TelemetryRing
    from motosim.rt.ring import SampleRing
    from motosim.rt.run import profile_stats
    from motosim.rt.safety import State
    from motosim.rt.stack import RESULT_SIGNALS, result_block
    from motosim.sim.metrics import run_metrics

    ring = SampleRing.attach(handle)
    server: Any = None
    control: _LoopControl | None = None
    url = None
    live = None
    loop_rows: Any = None
    try:
        if view is not None:
            from motosim.view.live import LoopRows

            loop_rows = LoopRows(names, RESULT_SIGNALS)
            live = TelemetryRing(loop_rows.names, capacity=1 << 15)  # 32 s at 1 kHz
            server, control, url = _start_view(view, live)
        writer = ResultWriter(Path(folder), RESULT_SIGNALS, metadata, overwrite=overwrite)
    except MotosimError as err:
        conn.send(("error", str(err)))
        ring.close()
        if server is not None:
            server.stop()
        return False
    stop_relay = _start_relay(ring, names, telemetry, rate)
    conn.send(("ready", url))
    blocks: list[np.ndarray] = []
    states: list[np.ndarray] = []  # the safety stage's state of each row, for the metrics
    pending: list[np.ndarray] = []
    stamps: list[np.ndarray] = []  # the loop's profile columns, for timing.json
    stamp_names = ("compute", "done_read", "done_control", "done_send", "stack")
    stamp_cols = [names.index(n) for n in stamp_names] if set(stamp_names) <= set(names) else []
    col_state = names.index("state")
    period = 0.1 if view is None else 0.005  # the view is at most 5 ms behind the writer

    def flush(write: bool) -> None:
        rows = ring.drain()
        if rows.shape[0]:
            block = result_block(rows, names, torque_per_amp)
            blocks.append(block)
            states.append(rows[:, col_state])
            if stamp_cols:
                stamps.append(rows[:, stamp_cols])
            pending.append(block)
            if live is not None and control is not None:
                live.push_block(loop_rows.rows(rows, block))
                control.current = State(int(rows[-1, col_state])).name.lower()
        if write and pending:
            writer.append(np.vstack(pending))
            pending.clear()

    summary: dict[str, Any] = {}
    failed = None
    try:
        with writer:
            k = 0
            while True:
                if conn.poll(period):
                    _, complete, extra = conn.recv()
                    break
                k += 1
                flush(write=k % round(0.1 / period) == 0)
            flush(write=True)
            rows = np.vstack(blocks) if blocks else np.zeros((0, len(RESULT_SIGNALS)))
            col = {name: j for j, name in enumerate(RESULT_SIGNALS)}
            running = np.concatenate(states) == State.RUNNING if states else None
            summary = run_metrics(
                rows[:, 0],
                lambda n: rows[:, col[n]] if n in col else None,
                complete=complete,
                running=running,
            )
            summary |= extra
            summary["ring_dropped"] = float(ring.dropped)
            if not complete and "failure" not in extra:
                # stopped or faulted: files closed, marked incomplete (a fall is closed whole
                # and flagged with its failure, as offline); the writer's "run interrupted"
                # warning would name this exception and the staging folder; motosim run says
                # itself where the partial result is
                logging.getLogger("motosim.io.results").addFilter(
                    lambda record: not record.getMessage().startswith("run interrupted by")
                )
                raise _EarlyStopError
            writer.close(summary)
    except _EarlyStopError:
        pass
    except MotosimError as err:
        # a write failed (a full disk) or the folder gained files of another kind while the
        # run went: the message says where the rows are; motosim run ends with it at once
        failed = str(err)
    finally:
        stream = stop_relay()
        ring.close()
        if server is not None:
            server.stop()
    if failed is not None:
        conn.send(("error", failed))
        return False
    profile = profile_stats(np.vstack(stamps), stamp_names) if stamps else {}
    conn.send(("done", summary, str(writer.location), profile, stream))
    return True


def _start_relay(
    ring: Any, names: tuple[str, ...], address: tuple[str, int] | None, rate: float
) -> Callable[[], dict[str, float]]:
    """Start the state stream's relay thread in the writer process (none without
    ``address``); the function that stops it and gives its figures (datagrams sent and
    dropped, the lag after the loop's row [s])."""
    if address is None:
        return dict
    from motosim.rt.stack import STACK_SIGNALS
    from motosim.rt.telemetry import StateRelay, StateSender

    sender = StateSender(address, width=len(STACK_SIGNALS))
    buffer, counters = ring.arrays
    relay = StateRelay(
        buffer, counters, names, names.index(STACK_SIGNALS[0]), sender.send, rate=rate
    )
    stop = threading.Event()
    thread = threading.Thread(target=relay.run, args=(stop,), name="motosim-state", daemon=True)
    thread.start()

    def finish() -> dict[str, float]:
        stop.set()
        thread.join(timeout=1.0)
        sender.close()
        lags = {f"lag_{k}": v for k, v in relay.lag_stats().items()}
        return {"sent": float(relay.sent), "dropped": float(sender.dropped)} | lags

    return finish


def _keyboard(runner: Any) -> None:
    """Enter on the terminal: emergency stop."""
    for _ in sys.stdin:
        runner.emergency_stop()
        return


class _Presses:
    """A SIGINT handler that counts the presses of Ctrl-C and raises nothing.

    While ``motosim run`` starts, numba and llvmlite call back into Python from C as they
    load and link the compiled stack (10-15 s); Python's own handler raises
    KeyboardInterrupt wherever the signal lands, and one raised in such a callback is printed
    ("Exception ignored") and lost: the run started anyway and drove the handlebar. Counted
    here, the press is acted on at :meth:`check`, outside any callback.
    """

    def __init__(self) -> None:
        self.count = 0

    def __call__(self, signum: int, frame: object) -> None:
        self.count += 1

    def check(self) -> None:
        """Raise KeyboardInterrupt if Ctrl-C was pressed."""
        if self.count:
            raise KeyboardInterrupt


def _check_wait(args: argparse.Namespace) -> None:
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


def run(args: argparse.Namespace) -> int:
    """Run in real time; write the result; exit 0, 130 after Ctrl-C, 3 on a safety fault."""
    check_udp_only_options(args)  # before the numerical stack is imported
    _check_wait(args)
    check_privilege_options(args)  # the options first, then the files
    check_scenario_inputs(args.scenario)
    check_named_input(args.platform, "platform file")
    check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    check_scenario_values(args.scenario)  # before the numerical stack is imported
    presses = _Presses()
    previous = signal.signal(signal.SIGINT, presses)
    try:
        return _run(args, presses, previous)
    finally:
        signal.signal(signal.SIGINT, previous)


def _run(args: argparse.Namespace, presses: _Presses, sigint: Any) -> int:
    """:func:`run`, with Ctrl-C counted by ``presses`` until the loop takes it over, and
    given back to the handler ``sigint`` once the loop has ended."""
    options = check_rt_options(args)  # before the stack and the simulator are imported
    import numpy as np

    from motosim.io.cache import cached_stack
    from motosim.io.can import handlebar_codecs, open_link
    from motosim.rt.config import frame_age, parse_latency, parse_safety, run_paces, within_safety
    from motosim.rt.run import RealtimeRunner
    from motosim.rt.stack import CompiledStack
    from motosim.sim import build_rig, run_metadata
    from motosim.sim.metrics import validity_limits
    from motosim.sim.stack import account_for_delay

    if not 0 <= args.view_port < 65536:
        raise MotosimError(f"--view-port {short_repr(args.view_port)}; expected 0..65535")
    folder = check_result_folder(args.out, args.scenario, overwrite=args.overwrite)
    with deferred_warnings():  # the scenario's, once every check has passed
        cache = design_cache(args, quiet=args.json)
        inputs, realtime = load_realtime(args.scenario, safety=True, pace=args.pace, cache=cache)
        sc = inputs.scenario
        if sc.motorcycle.input == "true":
            raise MotosimError(
                f'{args.scenario}: motorcycle input = "true" is a simulation-only reference; '
                'expected "estimate" for a real-time run'
            )
        if sc.estimator.name == "torque_sensor":
            raise MotosimError(
                f'{args.scenario}: [estimator] name = "torque_sensor" is not read in real time '
                "yet (the loop does not take the HB_TORQUE frame); expected an estimator of "
                "the angle and the current"
            )
        limits = parse_safety(realtime.get("safety"), origin=args.scenario)
        inputs = within_safety(inputs, limits)  # the stack saturates where the clamp cuts
        sc = inputs.scenario
        duration = sc.duration if args.duration is None else args.duration
        if not (np.isfinite(duration) and 0.0 < duration <= 86_400.0):
            raise MotosimError(f"--duration {duration!r}; expected seconds in (0, 86400]")
        view = _view_setup(args, inputs, duration, limits) if args.view else None
        clock = clock_from_args(args)
        rate = sc.rates.control
        periods = round(duration * rate)
        latency = parse_latency(realtime, origin=args.scenario)
        age = frame_age(
            latency, pace=args.pace, control_rate=rate, measurement_rate=sc.rates.measurement,
            origin=args.scenario,
        )  # fmt: skip
        if args.pace not in run_paces(rate, sc.rates.measurement):
            raise MotosimError(
                f"--pace bus with control = {rate:g} Hz and measurement = "
                f"{sc.rates.measurement:g} Hz; expected equal rates (one period per status frame)"
            )
        with cache.designing(sc.name):
            model = cached_stack(cache, inputs)
        model = account_for_delay(model, age, inputs.nominal_handlebar)  # the frames' age
        world = build_rig(inputs, rng=np.random.default_rng(sc.seed))
        codecs = handlebar_codecs()
        stack = CompiledStack(model, force=world.force, side_force=world.side_force)
        telemetry = options.telemetry
        if telemetry is not None:  # sent by the writer process (StateRelay), not the loop
            from motosim.rt.telemetry import StateSender

            StateSender(telemetry, width=len(stack.names)).close()  # refused here, not there
        platform = None
        udp_sender = None
        if options.platform is not None:
            from motosim.rt.platform import PlatformOutput, PlatformSender

            if options.platform_udp is not None:
                udp_sender = PlatformSender(options.platform_udp)
            platform = PlatformOutput(
                options.platform,
                1.0 / rate,
                tuple(stack.names),
                sender=udp_sender,
                send_every=max(1, round(rate / 100.0)),
            )
    warn_atypical("run", "--duration", args.duration)  # once every check has passed
    link = open_link(args.bus, fast=args.link != "python-can")
    # the link in use: --link fast is python-can's own on a bus other than udp_multicast
    link_kind = "fast" if link.datagrams else "python-can"  # python-can's datagrams, read whole
    if platform is not None and args.platform_can:
        from motosim.io.can import platform_codecs
        from motosim.rt.platform import PlatformCanSender, PlatformTee

        can_sender = PlatformCanSender(link, platform_codecs())
        platform.sender = can_sender if udp_sender is None else PlatformTee(udp_sender, can_sender)
    end_writer: Callable[[], None] = _no_writer
    try:
        try:
            runner = RealtimeRunner(
                stack,
                link,
                codecs,
                limits,
                rate=rate,
                periods_per_frame=model.measure_every,
                capacity=max(1 << 14, round(5.0 * rate)),  # 5 s of rows between two drains
                shared_ring=True,
                wait_for_arm=view is not None,
                platform=platform,
                now=clock.now,
                clock=clock,
                handlebar=inputs.nominal_handlebar,
                validity=validity_limits(sc.motorcycle.speed),
                warm=args.warm == "on",
                duration=periods / rate,
            )
            metadata = run_metadata(inputs) | {
                "realtime": {
                    "bus": args.bus,
                    "link": link_kind,
                    "pace": args.pace,
                    "status_latency": latency,
                    "measurement_delay": age,
                    "safety": limits,
                    "duration": duration,
                }
            }
            try:
                presses.check()  # Ctrl-C while the stack was built: no run
            except KeyboardInterrupt:
                runner.ring.close()  # the loop would have: its shared memory
                raise
            # a partial result is kept beside a complete one already there (--overwrite):
            # the timing and the report go where the rows went
            stats, privileges, summary, folder, end_writer = _loop(
                args, runner, clock, rate, periods, folder, metadata,
                inputs.nominal_handlebar.torque_per_amp, view, telemetry,
            )  # fmt: skip
            signal.signal(signal.SIGINT, sigint)  # the files are closed: Ctrl-C as before
            counters = runner.counters()
        finally:
            link.close()
            if platform is not None and platform.sender is not None:
                platform.sender.close()
            elif udp_sender is not None:
                udp_sender.close()
        timing = stats.as_dict()
        report = {
            "link": link_kind,
            "pace": args.pace,
            "wait": "compiled" if runner.waits_compiled else "python",
            "warm": runner.warms and args.pace == "clock",
            "timing": timing,
            "profile": summary.get("profile", {}),
            "state_stream": summary.get("state_stream", {}),
            "units": "s",
            "privileges": [
                {"name": p.name, "applied": p.applied, "detail": p.detail} for p in privileges
            ],
            "counters": {
                "status_frames": counters.status_frames,
                "frames_lost": counters.frames_lost,
                "frames_stale": counters.frames_stale,
                "send_errors": counters.send_errors,
                "bus_errors": link.errors,
                "ring_dropped": int(summary.get("ring_dropped", 0)),
                "platform_datagrams": 0 if platform is None else platform.sequence,
                "platform_can": bool(args.platform_can),
            },
            "state": counters.state,
            "fault": counters.fault,
            "fault_reason": counters.fault_reason,
        }
        write_text(folder / "timing.json", _json(report))
        html = None
        if args.report:
            from motosim.report import build_report

            html = build_report(folder)
    finally:
        end_writer()  # the files beside the rows are written: the folder's lock is released
    if args.json:
        print_json({"out": str(folder), "report": str(html) if html else None} | report)
    else:
        us = 1e6
        print(f"{sc.name}: {stats.served} periods at {rate:g} Hz, result in {folder}")
        wake = "wake-up" if args.pace == "clock" else "frame interval jitter"
        print(
            f"  {wake} p99 {stats.wake_p99 * us:.0f} us, compute p99 "
            f"{stats.compute_p99 * us:.0f} us, missed {stats.missed} of {stats.periods}"
            + (f", {stats.gaps} frame periods without a frame" if args.pace == "bus" else "")
        )
        for p in privileges:
            print(f"  {p}")
        print(f"  state {counters.state}; {counters.fault_reason}")
        if counters.frames_lost > max(10, counters.status_frames // 10):
            print(
                f"  {counters.frames_lost} status frames lost for {counters.status_frames} "
                "received: is a second rig or drive on this bus? (udp_multicast: give each "
                "rig and run pair a group of its own, --bus udp_multicast:239.74.163.50)"
            )
        if stats.miss_ratio > 0.01:
            print(
                f"  {100.0 * stats.miss_ratio:.1f} % of the deadlines were missed: the virtual "
                "motorcycle fell behind the wall clock; check this PC with motosim rt-check "
                "and give --fifo 80 --cpu 1 --mlock (the real-time guide: Setting up the lab PC)"
            )
    reason = runner.left_range
    if counters.fault == "NONE" and reason is not None:
        raise RunFailedError(
            f"{sc.name}: {reason}; the result is in {folder}, flagged",
            time=runner.left_range_time,
        )
    if counters.fault == "NONE" and runner.stop_requested:
        print(f"motosim run: stopped, torque faded out; result in {folder}", file=sys.stderr)
        return 130
    if counters.fault != "NONE":
        raise RunFailedError(
            f"safety fault: {counters.fault_reason}; the result until then is in {folder}",
            time=counters.fault_time,
        )
    return 0


def _view_setup(
    args: argparse.Namespace, inputs: "RunInputs", duration: float, limits: Any
) -> _ViewSetup:
    """Check ``--view-port`` and the optional group; the road along the scenario's path."""
    import numpy as np

    from motosim.view.app import _need_starlette, new_token
    from motosim.view.feeds import road_from_xy

    if not 0 <= args.view_port < 65536:
        raise MotosimError(f"--view-port {args.view_port}; expected 0..65535")
    _need_starlette()
    sc = inputs.scenario
    length = max(duration * sc.motorcycle.speed, 10.0)
    if sc.rider.path is not None:
        built = sc.rider.path.build(length)
        road = road_from_xy(built.x, built.y)
    else:
        road = road_from_xy(np.array([0.0, length]), np.zeros(2))
    return _ViewSetup(new_token(), args.view_port, road.x, road.y, duration, sc.name, None,
                      limits.watchdog_periods)  # fmt: skip


def _controls(conn: Any, runner: Any) -> None:
    """The view's buttons, in the loop's process: blocked on the pipe until one is pressed."""
    while True:
        try:
            action = conn.recv()
        except (EOFError, OSError):
            return
        if action == "stop":
            runner.request_stop()  # as Ctrl-C: the torque fades out, then the run ends
        elif action == "arm":
            runner.arm()


def _json(payload: Any) -> str:
    import json

    from motosim.cli._common import _finite_or_none

    return json.dumps(_finite_or_none(payload), indent=2, allow_nan=False) + "\n"


def _loop(
    args: argparse.Namespace,
    runner: Any,
    clock: Any,
    rate: float,
    periods: int,
    folder: Path,
    metadata: dict[str, Any],
    torque_per_amp: float,
    view: _ViewSetup | None = None,
    telemetry: tuple[str, int] | None = None,
) -> tuple[Any, tuple[Any, ...], dict[str, Any], Path, Callable[[], None]]:
    """The real-time part: writer process (and view, and the state stream to ``telemetry``),
    privileges, signals, keyboard, the loop. Returns the loop's timing, the privileges, the
    result's summary, where its rows are, and the function that ends the writer process,
    which holds the folder's lock until then (called once the files beside the rows are
    written)."""
    import dataclasses
    import multiprocessing

    from motosim.rt.loop import FramePacedLoop, RateLoop
    from motosim.rt.privileges import freeze_gc, thaw_gc

    presses = [0]

    def on_sigint(signum: int, frame: object) -> None:
        presses[0] += 1
        if presses[0] == 1:
            runner.request_stop()  # before the loop starts: it ends at once
        else:
            runner.emergency_stop()

    # from here to the end Ctrl-C is ours: a stop, then an E-stop; never an exception that
    # would leave the writer and the shared ring behind
    previous = signal.signal(signal.SIGINT, on_sigint)
    if isinstance(previous, _Presses) and previous.count:
        on_sigint(signal.SIGINT, None)  # pressed since motosim run checked: stop at once
    ctx = multiprocessing.get_context("spawn")
    ours, theirs = ctx.Pipe()
    buttons = None
    if view is not None:
        buttons, pressed = ctx.Pipe(duplex=False)
        view = dataclasses.replace(view, control=pressed)
    writer = ctx.Process(
        target=_writer_main,
        args=(theirs, runner.ring.handle, runner.names, str(folder), metadata,
              bool(args.overwrite), torque_per_amp, view, telemetry, rate),
        name="motosim-writer",
        daemon=True,
    )  # fmt: skip
    writer.start()
    theirs.close()  # the writer holds its copy: EOF here at once if it ends without a word
    done = False  # the result closed: the writer holds the folder's lock until released
    if view is not None:
        view.control.close()  # the writer holds its copy: EOF here once it ends
    try:
        answer = _answer(ours, folder, "start")
        if view is not None:
            threading.Thread(target=_controls, args=(buttons, runner), daemon=True).start()
            url = answer[1]
            err = sys.stderr
            print(f"motosim run: rider's view {url}/?token={view.token}", file=err)
            print(f"motosim run: dashboard    {url}/dashboard?token={view.token}", file=err)
            print("motosim run: the torque is off until Arm is pressed", file=err, flush=True)
        privileges = privileges_from_args(args)
        margin = math.ceil(runner.safety.limits.fade_in * rate) + 4  # the fade-out at the end
        capacity = max(1, min(periods + margin, 1 << 22))
        loop: RateLoop | FramePacedLoop
        step = runner.period
        if args.pace == "bus":
            loop = FramePacedLoop(
                rate, clock, runner.wait_status, timeout=runner.watchdog_time,
                first_timeout=runner.first_timeout, capacity=capacity,
                received=lambda: runner.status_frames,
            )  # fmt: skip
        elif args.wait != "python" and runner.compile_wait():
            # the wait's end, the bus read and the period in one compiled call
            loop = RateLoop(rate, clock, capacity=capacity, woke=runner.woke)
            step = runner.wait_period
        else:  # the stack warmed in the caches just before each deadline (--warm on)
            warm = runner.warm if runner.warms else None
            loop = RateLoop(rate, clock, capacity=capacity, warm=warm)
        if sys.stdin is not None and sys.stdin.isatty():
            threading.Thread(target=_keyboard, args=(runner,), daemon=True).start()
            print("motosim run: Enter = emergency stop, Ctrl-C = stop", file=sys.stderr)
        print(
            f"motosim run: {rate:g} Hz on {args.bus}, paced by the "
            f"{'clock' if args.pace == 'clock' else 'status frames'}, {periods / rate:g} s",
            file=sys.stderr,
            flush=True,
        )
        freeze_gc()
        runner.discard_pending()  # frames queued while the writer started are stale
        try:
            # after the duration the torque fades out, never a step to zero, in the same run
            loop.run(step, periods=runner.max_periods)
        finally:
            thaw_gc()
        stats = loop.stats()
        complete = runner.reached_end and runner.safety.fault.name == "NONE"
        extra: dict[str, Any] = {f"rt_{k}": float(v) for k, v in stats.as_dict().items()}
        if runner.left_range is not None and runner.safety.fault.name == "NONE":
            extra["failure"] = runner.left_range  # the motorcycle fell: flagged, as offline
        try:
            ours.send(("close", complete, extra))
        except OSError:  # the writer has ended (a write failed): its answer is read below
            pass
        _, summary, location, profile, stream = _answer(ours, folder, "finish")
        summary = summary | {"profile": profile, "state_stream": stream}
        done = True
    finally:
        if not done:
            _end_writer(writer, None)
        runner.ring.close()
        signal.signal(signal.SIGINT, previous)
    return stats, privileges, summary, Path(location), lambda: _end_writer(writer, ours)


def _answer(conn: Any, folder: Path, what: str) -> tuple[Any, ...]:
    """The writer process's answer on ``conn``: ("ready", ...) or ("done", ...); its
    ("error", text) raised as :class:`MotosimError`, and so are no answer within 120 s and
    the end of ``conn`` (the writer ended without one)."""
    try:
        if conn.poll(120.0):
            answer: tuple[Any, ...] = conn.recv()
            if answer[0] == "error":
                raise MotosimError(answer[1])
            return answer
    except (EOFError, OSError):
        pass
    raise MotosimError(f"{folder}: the result writer did not {what}")


def _no_writer() -> None:
    """No writer process to end: the run stopped before it started."""


def _end_writer(writer: Any, conn: Any) -> None:
    """Let the writer process release the folder's lock through ``conn`` (None: it is not
    waiting for that), then join it; killed if it has not ended within 10 s."""
    if conn is not None:
        try:
            conn.send(("release",))
        except OSError:  # it has ended
            pass
        conn.close()
    writer.join(timeout=10.0)
    if writer.is_alive():
        writer.kill()
