"""The compiled wait and bus read (``RealtimeRunner.wait_period``) against the Python path.

``motosim run`` on the clock with a compiled stack and the fast ``udp_multicast`` link ends
each wait, reads the socket and runs the period in one compiled call
(:func:`motosim.rt.fused.context_cycle`, the socket read by ``recv`` from compiled code);
every other loop keeps :meth:`RealtimeRunner.period`, which reads the socket from Python
(:meth:`UdpMulticastLink.receive_into`). Both must give the same rows to the last bit
(the time stamps aside) for the same datagrams, count the same socket errors, and trip the
same faults. The datagrams come through a ``socketpair`` (delivered within the send: the
runs are deterministic); one test reads a real multicast socket.
"""

import select
import socket
import time
from typing import Any

import numba
import numpy as np
import pytest

from motosim.control.torque_feedback import PAPER_CONTROLLER
from motosim.errors import MotosimError
from motosim.params import load_parameters
from motosim.rt import fused
from motosim.rt.clock import SimulatedClock
from motosim.rt.loop import WARM_LEAD, RateLoop
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.safety import SafetyLimits
from motosim.rt.stack import CompiledStack
from motosim.sim import build_stack, parse_scenario, prepare

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")
if not fused.RECV_AVAILABLE:
    pytest.skip("the compiled socket read is Linux only", allow_module_level=True)
if numba.config.DISABLE_JIT:
    pytest.skip(
        "the compiled wait needs numba's JIT (without it: the Python path)", allow_module_level=True
    )

from motosim.io.can import HandlebarCodecs, UdpMulticastLink, handlebar_codecs, open_link

RATE = 1000.0
SCENARIO = {
    "scenario": {"name": "compiled_wait", "description": "square torque", "duration": 1.0},
    "rates": {"plant": 10_000.0, "control": RATE, "measurement": RATE},
    "rider": {
        "kind": "torque",
        "profile": {"kind": "square", "low": -5.0, "high": 5.0, "period": 1.0, "start": 0.2},
    },
    "controller": {"kind": "paper"},
}
LIMITS = SafetyLimits(  # limits that bind: slew, speed, clamp, a 50 ms fade-in
    max_current=0.1,
    max_slew=400.0,
    max_speed=1.0,
    speed_band=2.0,
    soft_stop=0.05,
    hard_stop=5.0,
    end_stop_gain=20.0,
    hands_off_torque=0.0,
    hands_off_time=1.0,
    hands_off_gain=0.5,
    fade_in=0.05,
)
TIMING = {"wake", "compute", "done_read", "done_control", "done_send", "stack"}
"""The columns that are times measured on the machine's clock (they differ run to run)."""


class _PairLink(UdpMulticastLink):
    """The fast link's receiving side on one end of a ``socketpair`` (a datagram is queued
    within the send, so a run is deterministic); what the runner sends is kept."""

    def __init__(self) -> None:
        import msgpack  # type: ignore[import-untyped]

        self._sock, self.peer = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
        self._sock.setblocking(False)
        self._poll = select.poll()
        self._poll.register(self._sock.fileno(), select.POLLIN)
        self._select = select.select
        self._unpack = msgpack.unpackb
        self._templates = {}
        self._dest = ("unused", 0)
        self.sent: list[bytes] = []
        self._out = self
        self.errors = 0
        self.own_filtered = True
        self.spec = "socketpair"

    def sendto(self, datagram: Any, dest: object) -> int:
        self.sent.append(bytes(datagram))
        return len(datagram)

    def close(self) -> None:
        self._sock.close()
        self.peer.close()


def _stack() -> CompiledStack:
    scenario = parse_scenario(SCENARIO, origin="test")
    hb = load_parameters("simacom_handlebar", "handlebar")
    inputs = prepare(
        scenario,
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=PAPER_CONTROLLER,
    )
    return CompiledStack(build_stack(inputs))


def _datagram(codecs: HandlebarCodecs, frame: str, **signals: float) -> bytes:
    codec = getattr(codecs, frame)
    values = np.zeros(len(codec.names))
    for part, value in signals.items():
        values[codecs.position(codec, part)] = value
    before, after = UdpMulticastLink._template(codec.frame_id, codec.length)
    return before + codec.encode(values) + after


def _recording(codecs: HandlebarCodecs, n: int) -> list[list[bytes]]:
    """The datagrams waiting at each of ``n`` deadlines: a steered handlebar's status frames
    with a lost one, a duplicate (stale), a burst of 70 (more than one period reads), a
    datagram that is no frame, and an E-stop pressed near the end."""
    periods: list[list[bytes]] = []
    counter = 0
    for k in range(n):
        theta = 0.3 * np.sin(2.0 * np.pi * 2.0 * k / RATE)
        status = _datagram(
            codecs, "status", angle=theta, current=0.5 * np.cos(k / 50.0), counter=counter % 15
        )
        counter += 1
        waiting = [] if k in (5, 300) else [status]
        if k == 400:
            waiting.append(status)  # the same frame again: stale
        if k == 500:
            waiting += [status] * 70
        if k == 600:
            waiting.append(b"\x00not a python-can frame")
        if k == n - 20:
            waiting.append(_datagram(codecs, "estop", estop_signal=1.0))
        periods.append(waiting)
    return periods


def _run(
    compiled_wait: bool, recording: list[list[bytes]], *, warm: bool = True, live: bool = False
) -> tuple[RealtimeRunner, Any]:
    codecs = handlebar_codecs()
    link = _PairLink()
    runner = RealtimeRunner(
        _stack(),
        link,
        codecs,
        RunSettings(limits=LIMITS, rate=RATE, capacity=4096, warm=warm),
        now=time.monotonic,
    )
    assert runner.compile_wait()  # compiled stack, the fast link, Linux, numba's JIT
    step = runner.wait_period if compiled_wait else runner.period
    start = time.monotonic() + 1e-3 if live else 1.0
    for k, waiting in enumerate(recording):
        for datagram in waiting:
            link.peer.send(datagram)
        # not live: a deadline long past on the monotonic clock (no wait, one warm-up, a row
        # for each); live: every 1 ms on it, slept for until WARM_LEAD before as the loop
        # does (never a deadline skipped: a late one is served at once)
        due = start + k / RATE
        if live:
            time.sleep(max(0.0, due - WARM_LEAD - time.monotonic()))
            if not compiled_wait:
                runner.warm(due)
                while time.monotonic() < due:
                    pass
        if not step(k, due):
            break
    link.close()
    return runner, (runner.ring.drain(), link.sent)


def test_the_compiled_wait_gives_the_rows_and_frames_of_the_python_path() -> None:
    recording = _recording(handlebar_codecs(), 900)
    python, (rows, sent) = _run(False, recording)
    compiled, (rows_c, sent_c) = _run(True, recording)
    names = python.names
    assert rows.shape == rows_c.shape == (900, len(names))
    keep = _timeless(python)
    assert np.array_equal(rows[:, keep], rows_c[:, keep], equal_nan=True)
    assert sent == sent_c  # the command and heartbeat datagrams, byte for byte
    c, c_c = python.counters(), compiled.counters()
    assert (c.status_frames, c.frames_lost, c.frames_stale) == (
        c_c.status_frames,
        c_c.frames_lost,
        c_c.frames_stale,
    )
    assert c.fault == c_c.fault == "ESTOP_CAN"
    assert c.frames_lost >= 2 and c.frames_stale >= 1  # the recording's faults were seen
    assert python.link.errors == compiled.link.errors == 1  # the datagram that is no frame
    # the compiled path stamps its wake-up and bus read from compiled code
    col = names.index("done_read")
    assert np.all(rows_c[:, col] >= 0.0) and np.all(rows_c[:, names.index("wake")] > 0.0)


def test_the_warm_ups_before_each_deadline_change_nothing_and_can_be_turned_off() -> None:
    # at 1 kHz on the machine's clock, the compiled wait steps a copy of the stack (its
    # state copied, the step run on the copy, its result thrown away) again and again from
    # WARM_LEAD until about 2 us before each deadline (how many times varies from period to
    # period and run to run, and must not matter); with warm=False (motosim run --warm off)
    # it only spins. The rows and the frames sent are those of the Python path (here warmed
    # too) to the last bit, the warm-ups on or off; only the clock's times differ
    recording = _recording(handlebar_codecs(), 900)
    python, (rows, sent) = _run(False, recording, live=True)
    keep = [j for j in _timeless(python) if python.names[j] not in ("t", "t_clock")]
    t = python.names.index("t")
    for warm in (True, False):
        runner, (rows_w, sent_w) = _run(True, recording, warm=warm, live=True)
        assert runner.warms is warm
        assert np.array_equal(rows[:, keep], rows_w[:, keep], equal_nan=True)
        assert np.allclose(rows[:, t], rows_w[:, t], rtol=0.0, atol=1e-9)
        assert sent == sent_w
        # the copy the warm-ups step: its period index follows the stack's, or never moved
        assert runner._shadow is not None
        shadow = runner._shadow[1]  # the stack's state (its period index first)
        assert shadow[0] > 800.0 if warm else np.all(shadow == 0.0)
        runner.warm(time.monotonic() + 5e-3)
        assert (runner.warm_ups > 1) is warm  # again and again, or none


def test_a_socket_error_is_counted_and_the_watchdog_trips_as_in_the_python_path() -> None:
    # the receiving socket closed under the runner: each read fails (EBADF, not "nothing
    # waiting"), is counted in the link's errors, and no frame comes: NO_DRIVE at the start
    # timeout, the same period both ways
    periods = 40
    out = []
    for compiled_wait in (False, True):
        codecs = handlebar_codecs()
        link = _PairLink()
        runner = RealtimeRunner(
            _stack(),
            link,
            codecs,
            RunSettings(limits=LIMITS, rate=RATE, start_timeout=0.03),
            now=time.monotonic,
        )
        assert runner.compile_wait()
        link._sock.close()
        step = runner.wait_period if compiled_wait else runner.period
        for k in range(periods):
            step(k, 1.0 + k / RATE)
        rows = runner.ring.drain()
        out.append((runner.counters().fault, link.errors, rows[:, _timeless(runner)]))
        link.peer.close()
    (fault, errors, rows), (fault_c, errors_c, rows_c) = out
    assert fault == fault_c == "NO_DRIVE"
    assert errors == errors_c == periods  # one failed read per period
    assert np.array_equal(rows, rows_c, equal_nan=True)


def _timeless(runner: RealtimeRunner) -> list[int]:
    """The columns of ``runner``'s rows that are no machine times."""
    return [j for j, name in enumerate(runner.names) if name not in TIMING]


def test_wait_period_waits_for_its_deadline_and_reads_a_real_multicast_socket() -> None:
    try:
        host = open_link("udp_multicast:239.74.163.152")
        drive = open_link("udp_multicast:239.74.163.152")
    except MotosimError as err:
        pytest.skip(f"udp_multicast is not available here: {err}")
    assert isinstance(host, UdpMulticastLink)
    try:
        codecs = handlebar_codecs()
        runner = RealtimeRunner(
            _stack(), host, codecs, RunSettings(limits=LIMITS, rate=RATE), now=time.monotonic
        )
        assert runner.compile_wait()
        drive.send(codecs.status.frame_id, _datagram(codecs, "status", angle=0.1)[-8:])
        assert host.readable(5.0)
        t = time.monotonic() + 2e-3
        assert runner.wait_period(0, t)
        assert runner.woke() >= t  # the compiled spin ended at the deadline, not before
        assert runner.status_frames == 1 and host.errors == 0
    finally:
        host.close()
        drive.close()


def test_the_loop_with_woke_lets_the_step_end_the_wait() -> None:
    # RateLoop(woke=...) sleeps until WARM_LEAD before each deadline and lets the step wait
    # the rest; its wake-up latency is the step's own wake-up against the deadline
    clock = SimulatedClock()
    called: list[float] = []

    def step(k: int, deadline: float) -> bool:
        called.append(deadline - clock.now())
        clock.sleep_until(deadline + 1e-6)  # the step's wait, waking 1 us late
        return True

    loop = RateLoop(RATE, clock, woke=clock.now)
    assert loop.run(step, periods=5) == 5
    assert np.allclose(called, WARM_LEAD)
    assert loop.stats().wake_max == pytest.approx(1e-6) and loop.stats().compute_max == 0.0


def test_wait_period_needs_compile_wait() -> None:
    codecs = handlebar_codecs()
    link = _PairLink()
    runner = RealtimeRunner(_stack(), link, codecs, RunSettings(limits=LIMITS, rate=RATE))
    assert not runner.waits_compiled
    with pytest.raises(MotosimError, match="compile_wait"):
        runner.wait_period(0, 1.0)
    assert runner.compile_wait() and runner.waits_compiled
    link.close()


def test_other_links_keep_the_python_wait() -> None:
    # python-can's link (here its virtual bus) has no socket read from compiled code
    codecs = handlebar_codecs()
    with open_link("virtual:compiled_wait") as link:
        runner = RealtimeRunner(_stack(), link, codecs, RunSettings(limits=LIMITS, rate=RATE))
        assert not runner.compile_wait() and not runner.waits_compiled
