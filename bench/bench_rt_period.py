"""What one period of ``motosim run`` costs, piece by piece, before and after the fast link.

One process, two ends of python-can's ``udp_multicast`` bus (the loop's and a drive's): each
period the drive sends a status frame, then the loop's period runs
(:meth:`motosim.rt.run.RealtimeRunner.period`: read the bus, one compiled call that decodes
the frames, steps the stack and the safety stage, encodes the command and writes the row
into the ring, then send the command). The pieces (the Python codec and safety stage that
the compiled call replaces among them) are timed alone the same number of times. Everything
is measured twice in the same run: with the python-can ``CanLink`` (every frame a
``can.Message``, packed and unpacked by python-can: the "before") and with
:class:`motosim.io.can.UdpMulticastLink` (python-can's socket and wire format, no message
objects: the "after"), and the ratios are printed.

Run alone: ``python bench/bench_rt_period.py [--periods 3000]``; the load average is printed
with the figures (on a shared machine the absolute numbers move with it, the ratios less).
"""

import argparse
import os
import socket
import time
from collections.abc import Callable

import numpy as np

from motosim.control.torque_feedback import PAPER_CONTROLLER
from motosim.io.can import UdpMulticastLink, handlebar_codecs, open_link
from motosim.params import load_parameters
from motosim.rt.ring import SampleRing
from motosim.rt.run import RealtimeRunner, RunSettings
from motosim.rt.safety import SafetyLimits, SafetyStage
from motosim.rt.stack import CompiledStack, compiled
from motosim.rt.telemetry import StateSender
from motosim.sim import build_stack, parse_scenario, prepare
from motosim.sim.stack import new_data, reset
from motosim.sim.stack import step as sim_step

HB = load_parameters("simacom_handlebar", "handlebar")
BUS = "udp_multicast:239.74.163.141"  # a group of its own (other users of the machine)

LIMITS = SafetyLimits(
    max_current=10.0,
    max_slew=2000.0,
    max_speed=6.0,
    speed_band=4.0,
    soft_stop=0.6,
    hard_stop=0.8,
    end_stop_gain=50.0,
    hands_off_torque=0.3,
    hands_off_time=1.0,
    hands_off_gain=0.3,
    watchdog_periods=1000,
)


def _stack() -> CompiledStack:
    sc = parse_scenario(
        {
            "scenario": {"name": "bench", "description": "", "duration": 10.0},
            "rider": {"kind": "torque", "profile": {"kind": "constant", "value": 0.0}},
            "controller": {"kind": "paper"},
        },
        origin="bench",
    )
    hb = load_parameters("simacom_handlebar", "handlebar")
    inputs = prepare(
        sc,
        sharp=load_parameters("sharp1971", "sharp"),
        true_handlebar=hb,
        nominal_handlebar=hb,
        controller=PAPER_CONTROLLER,
    )
    return CompiledStack(build_stack(inputs))


def _times(
    fn: Callable[[], object], n: int, between: Callable[[], object] | None = None
) -> np.ndarray:
    out = np.empty(n)
    clock = time.perf_counter
    for k in range(n):
        if between is not None:
            between()
        a = clock()
        fn()
        out[k] = clock() - a
    return out


def _us(values: np.ndarray) -> str:
    p50, p99 = np.percentile(values, (50, 99))
    return f"p50 {p50 * 1e6:6.1f} us, p99 {p99 * 1e6:6.1f} us"


def _measure(fast: bool, n: int, *, own_filter: bool = True) -> dict[str, np.ndarray]:
    codecs = handlebar_codecs()
    host, drive = open_link(BUS, fast=fast), open_link(BUS, fast=fast)
    if not own_filter:  # each end reads its own frames back, as before the BPF filter
        for link in (host, drive):
            if isinstance(link, UdpMulticastLink):
                link._sock.setsockopt(socket.SOL_SOCKET, 27, 0)  # SO_DETACH_FILTER
    st = codecs.status
    values = np.zeros(len(st.names))
    counter = [0]
    i_counter = codecs.position(st, "counter")

    def status() -> None:  # the drive's frame, sent and given time to arrive
        counter[0] += 1
        values[i_counter] = counter[0] & 0xF
        drive.send(st.frame_id, st.encode(values))
        time.sleep(2e-4)

    def drain() -> None:
        while host.receive() is not None:
            pass

    out: dict[str, np.ndarray] = {}
    try:
        drain()
        frame = codecs.command.encode(np.zeros(len(codecs.command.names)))
        out["send a frame"] = _times(lambda: host.send(0x100, frame), n, between=drain)
        out["receive a waiting frame"] = _times(host.receive, n, between=status)
        drain()
        out["receive, nothing waiting"] = _times(host.receive, n)
        stack = _stack()
        runner = RealtimeRunner(
            stack, host, codecs, RunSettings(limits=LIMITS, rate=1000.0, handlebar=HB)
        )
        runner.discard_pending()
        out["period (whole)"] = _times(
            lambda: runner.period(counter[0], counter[0] * 1e-3), n, between=status
        )
        drive.close()
        drive = host
    finally:
        host.close()
        if drive is not host:
            drive.close()
    return out


def _pieces(n: int) -> dict[str, np.ndarray]:
    codecs = handlebar_codecs()
    stack = _stack()
    stack.reset(0.0, 0.0)
    model = stack.model
    data, data2 = new_data(model), new_data(model)  # each from the same start
    fast_step = compiled(sim_step, model, data2, 0.0, 0.0, 0.0, 0.0, 0.0)  # the same kernel
    reset(model, data, 0.0, 0.0)
    reset(model, data2, 0.0, 0.0)
    safety = SafetyStage(LIMITS, dt=1e-3)
    safety.enable()
    cmd = np.zeros(len(codecs.command.names))
    frame = codecs.status.encode(np.zeros(len(codecs.status.names)))
    buf = np.zeros(len(codecs.status.names))
    ring = SampleRing(1 << 14, 7 + len(stack.names))
    row = np.zeros(7 + len(stack.names))
    sender = StateSender(("127.0.0.1", 47999), width=len(stack.names))
    try:
        return {
            "codec: encode the command": _times(lambda: codecs.command.encode(cmd), n),
            "codec: decode the status": _times(lambda: codecs.status.decode(frame, buf), n),
            "stack step (CompiledStack.step, from Python)": _times(
                lambda: stack.step(0.01, 0.0), n
            ),
            "stack kernel through numba's dispatcher (before)": _times(
                lambda: sim_step(model, data, 0.01, 0.0, 0.0, 0.0, 0.0), n
            ),
            "stack kernel, compiled entry point (after)": _times(
                lambda: fast_step(model, data2, 0.01, 0.0, 0.0, 0.0, 0.0), n
            ),
            "safety stage step": _times(
                lambda: safety.step(1.0, theta=0.0, omega=0.0, tau_hat=1.0), n
            ),
            "ring push": _times(lambda: ring.push(row), n),
            "state stream datagram (--telemetry)": _times(
                lambda: sender.send(1, 0.0, stack.row()), n
            ),
        }
    finally:
        sender.close()


def run(periods: int = 3000) -> dict[str, object]:
    """Measure; return the figures (p50/p99 in microseconds) and the after/before ratios."""
    out: dict[str, object] = {"load average (1, 5, 15 min)": os.getloadavg()}
    for name, values in _pieces(periods).items():
        out[name] = _us(values)
    before = _measure(False, periods)
    unfiltered = _measure(True, periods, own_filter=False)
    after = _measure(True, periods)
    for name in before:
        out[f"{name}: python-can"] = _us(before[name])
        out[f"{name}: UdpMulticastLink"] = _us(after[name])
        ratio = np.percentile(after[name], 50) / np.percentile(before[name], 50)
        out[f"{name}: after/before p50"] = round(float(ratio), 2)
    # the fast link without its BPF filter (reading its own frames back) and with it
    for name in ("send a frame", "period (whole)"):
        out[f"{name}: fast link, own frames read back"] = _us(unfiltered[name])
        out[f"{name}: fast link, own frames dropped by BPF"] = _us(after[name])
        for q in (50, 99):
            ratio = np.percentile(after[name], q) / np.percentile(unfiltered[name], q)
            out[f"{name}: BPF filter on/off p{q}"] = round(float(ratio), 2)
    out["load average after"] = os.getloadavg()
    return out


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--periods", type=int, default=3000, help="periods per measurement")
    args = parser.parse_args()
    for key, value in run(args.periods).items():
        print(f"  {key:<52} {value}")
