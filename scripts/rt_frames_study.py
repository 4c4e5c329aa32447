"""The lane change over slow status frames, in lock-step against the rig, with bus latency.

    .venv/bin/python scripts/rt_frames_study.py [--bus LATENCY:JITTER,...] [--no-clamp]
        [--delay bus|SECONDS] [--frames HZ] [--limits free,SIMACOM]

``scenarios/lane_change_20.toml`` with the drive's status frames at the paper's 100 Hz under
the 1 kHz loop, its virtual rider at the rig steering by the state stream, run by the
real-time loop on a simulated clock (deterministic; :class:`motosim.rt.lockstep.Lockstep`)
for each bus latency and jitter [s] (default 0:0, 0.5:0.2, 2:0.5, 5:1 and 9.5:1 ms), twice:
with safety limits that never bind ("free") and with the SIMACOM handlebar's of
``scenarios/realtime_square.toml`` (a 10 A clamp, hands-off detection). One Markdown row
each: the current's peak to peak after the manoeuvre (6-9 s), its largest value, the
tracking error's RMS, the rider-torque estimate's error RMS against the rider's torque at
the rig (and as a share of its peak) and the lateral position at the end. An 8 Hz limit
cycle at the clamp shows as 20 A peak to peak. The stack accounts for the frame's age
(:func:`motosim.sim.stack.account_for_delay`): by default (``--delay bus``) the frame's mean
age when the loop reads it, the bus latency and half a control period (0 without latency,
where the lock-step loop reads the frame in the period it is sampled); ``--delay 0`` is the
stack designed for a fresh sample, as before. ``--frames`` sets the status frames' rate
(100 Hz). ``--no-clamp`` builds the stack with the controller's own current limit instead of
the safety clamp (what ``motosim run`` did before :func:`motosim.rt.config.within_safety`);
the real-time guide quotes these rows.
"""

import argparse
import dataclasses
import math
import tomllib
from pathlib import Path

import numpy as np

from motosim.errors import MotosimError
from motosim.io.runs import load_run
from motosim.rt.config import frame_age, parse_safety, within_safety
from motosim.rt.lockstep import Lockstep, free_limits, ideal_rig
from motosim.rt.safety import SafetyLimits
from motosim.sim import RunInputs

ROOT = Path(__file__).resolve().parents[1]


def _row(
    inputs: RunInputs, limits: SafetyLimits, latency: float, jitter: float, delay: float | None
) -> str:
    """One lock-step run's figures as a Markdown row's cells; ``delay`` the stack's
    measurement delay [s] (None: the bus latency and half a control period)."""
    sc = inputs.scenario
    if delay is None:  # the frame's mean age when the loop reads it, as motosim run takes it
        d = frame_age(
            latency,
            pace="clock",
            control_rate=sc.rates.control,
            measurement_rate=sc.rates.measurement,
            origin="rt_frames_study",
        )
    else:
        d = delay
    settings = dataclasses.replace(ideal_rig(sc), latency=latency, jitter=jitter)
    lock = Lockstep(inputs, limits, settings=settings, delay=d, channel="rt_frames")
    angles: list[tuple[float, float]] = []  # the true angle, after the rig's advance
    lock.clock.listen(lambda now: angles.append((now, float(lock.rig.x[0]))))
    rows = lock.run()
    runner = lock.runner
    col = runner.names.index
    t, current = rows[:, 0], rows[:, col("i_safe")]
    theta = np.nan_to_num(rows[:, col("theta_h_meas")])
    error = np.sqrt(np.mean((theta - rows[:, col("delta")]) ** 2))
    true_angle = np.array(angles)
    at = np.clip(np.searchsorted(true_angle[:, 0], t + 1e-9, side="right") - 1, 0, None)
    true_error = np.sqrt(np.mean((true_angle[at, 1] - rows[:, col("delta")]) ** 2))
    hold = (t > 6.0) & (t < 9.0)
    log = np.array(lock.rider_torques)
    true = log[np.clip(np.searchsorted(log[:, 0], t, side="right") - 1, 0, None), 1]
    estimate = np.sqrt(np.mean((rows[:, col("tau_r_hat")] - true) ** 2))
    share = 100 * estimate / np.max(np.abs(true))
    return (
        f"{np.ptp(current[hold]) if hold.any() else math.nan:.2f} A | "
        f"{np.max(np.abs(current)):.1f} A | "
        f"{1e3 * error:.2f} mrad | {1e3 * true_error:.2f} mrad | "
        f"{estimate:.2f} N*m ({share:.1f} %) | "
        f"{rows[-1, col('y')]:.2f} m | {runner.counters().fault}"
    )


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--bus",
        default="0:0,0.0005:0.0002,0.002:0.0005,0.005:0.001,0.0095:0.001",
        help="latency:jitter pairs [s], comma-separated",
    )
    parser.add_argument(
        "--no-clamp", action="store_true", help="the stack at its own current limit"
    )
    parser.add_argument(
        "--delay", default="bus", help="bus (the frame's mean age), or the stack's delay [s]"
    )
    parser.add_argument("--frames", type=float, default=100.0, help="status frames [Hz] (100)")
    parser.add_argument("--limits", default="free,SIMACOM", help="free, SIMACOM or both")
    args = parser.parse_args()
    delay = None if args.delay == "bus" else float(args.delay)
    full = load_run(ROOT / "scenarios" / "lane_change_20.toml")
    rates = dataclasses.replace(full.scenario.rates, measurement=args.frames)
    inputs = dataclasses.replace(full, scenario=dataclasses.replace(full.scenario, rates=rates))
    table = tomllib.loads((ROOT / "scenarios" / "realtime_square.toml").read_text())
    simacom = parse_safety(table["realtime"]["safety"], origin="realtime_square.toml")
    print(
        "| latency, jitter | limits | current p-p 6-9 s | largest current | tracking RMS "
        "| true tracking RMS | estimate RMS | y at the end | fault |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for pair in args.bus.split(","):
        latency, jitter = (float(x) for x in pair.split(":"))
        for name, limits in (("free", free_limits(rates.control)), ("SIMACOM", simacom)):
            if name not in args.limits:
                continue
            run = inputs if args.no_clamp else within_safety(inputs, limits)
            try:
                cells = _row(run, limits, latency, jitter, delay)
            except MotosimError as exc:  # e.g. an age beyond a frame period, as run refuses
                cells = f"refused: {exc} |" + " |" * 7
            print(f"| {1e3 * latency:g}, {1e3 * jitter:g} ms | {name} | {cells} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
