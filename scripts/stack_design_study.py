"""Study the free choices of the stack's design against the whole-stack robustness grid.

    .venv/bin/python scripts/stack_design_study.py [--rates 1000,100] [--speeds 10,20,30]
        [--only NAME ...] [--wobble]

Each candidate design (the rider-torque cancellation gain, the reference inverse-dynamics
terms, the controller's bandwidth, order and integral corner, the observer's injection
bandwidth and the J_eq, beta_eq it is designed with, and whether the extra damping of an
observer whose beta_eq is below the nominal one is given back to the virtual motorcycle) is
built for the packaged handlebar as ``motosim design`` builds it, and analysed by
:func:`motosim.sim.loop_analysis.analyse_stack` at each rate and speed: the nominal loop's
margins and rendered-feel error over 0.1-3 Hz, and how many of the 27 handlebars of
:func:`motosim.sim.loop_analysis.robustness_grid` (J_eq, beta_eq x0.5/1/1.5, N k_t
x0.7/1/1.3) the loop stabilises with 6 dB and 45 deg. One Markdown row per candidate and
rate.

``--runs NAME ...`` simulates the named candidates instead, as ``motosim simulate`` would, on
the lane change (20 m/s), the crosswind (30 m/s) and the avoidance (15 m/s) at 1 kHz and the
paper's riding run (Fig. 15) at 100 Hz: tracking and estimate RMS as fractions of the peak
steer angle and rider torque, and the current's buzz over the last 2 s
(:func:`motosim.sim.metrics.run_metrics`).

``--wobble`` prints instead the steering damper, added to the virtual motorcycle (torque
-c delta' on the steer), that makes its wobble or weave unstable at each speed: a loop whose
estimator reads a handlebar damping error as rider torque puts (beta_true - beta_obs) on the
motorcycle, negative when the true handlebar is less damped than the observer believes.
"""

import argparse
import dataclasses
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motosim.control.statespace import StateSpace
from motosim.control.torque_feedback import (
    INTEGRAL_CORNER,
    default_bandwidth,
    design_torque_feedback,
)
from motosim.estimation.walcott_zak import ObserverSettings, WalcottZakObserver, design_with
from motosim.io.runs import load_run, load_scenario, resolve
from motosim.model import sharp as sharp_model
from motosim.params import load_parameters
from motosim.params.handlebar import HandlebarParameters
from motosim.sim import RunInputs, loop_analysis, simulate
from motosim.sim.closed_loop import build_stack
from motosim.sim.loop_analysis import MARGINS, StackLoop, StackLoopAnalysis, analyse_stack
from motosim.sim.metrics import run_metrics
from motosim.sim.stack import StackModel, design_stack

DELTA_RATE = 3  # index of the steer rate delta' in the motorcycle's lateral state


@dataclass(frozen=True)
class Candidate:
    """One design: every field left at its default is the default design at 1 kHz, the
    observer on the nominal handlebar ("before" in the design guide's table); below 200 Hz
    the default observer is designed for more inertia (at 100 Hz: "observer J x2",
    :func:`motosim.sim.closed_loop.observer_settings`)."""

    name: str
    cancellation: float = 1.0  # Feedforward.cancellation: share of the estimate cancelled
    reference: bool = True  # the reference inverse-dynamics term
    reference_inertia: float = 1.0  # its J_eq, as a factor of the nominal
    reference_damping: float = 1.0  # its beta_eq, as a factor of the nominal
    bandwidth: float | None = None  # controller bandwidth [Hz]; None: default_bandwidth(rate)
    order: int = 1
    integral_corner: float = INTEGRAL_CORNER  # W1's corner, a fraction of the bandwidth
    injection: float | None = None  # observer injection bandwidth [1/s]; None: for_step
    filter_time_constant: float | None = None  # the estimate's low-pass [s]; None: for_step
    beta_obs: float = 1.0  # the observer's beta_eq, as a factor of the nominal
    inertia_obs: float = 1.0  # the observer's J_eq, as a factor of the nominal
    compensate: bool = False  # give (beta_nom - beta_obs) delta' back to the motorcycle
    rates: tuple[float, ...] = (1000.0, 100.0)  # rates [Hz] it is meant for


CANDIDATES = [
    Candidate("before"),
    Candidate("cancel 0.8", cancellation=0.8),
    Candidate("cancel 0.5", cancellation=0.5),
    Candidate("cancel 0", cancellation=0.0),
    Candidate("no reference ff", reference=False),
    Candidate("reference beta x0.5", reference_damping=0.5),
    Candidate("reference J x0", reference_inertia=0.0),
    Candidate("bandwidth 5 Hz", bandwidth=5.0),
    Candidate("bandwidth 15 Hz", bandwidth=15.0),
    Candidate("bandwidth 20 Hz", bandwidth=20.0),
    Candidate("bandwidth 25 Hz", bandwidth=25.0, rates=(1000.0,)),
    Candidate("bandwidth 30 Hz", bandwidth=30.0, rates=(1000.0,)),
    Candidate("bandwidth 40 Hz", bandwidth=40.0, rates=(1000.0,)),
    Candidate("order 2", order=2),
    Candidate("injection 0.5x", injection=0.5),
    Candidate("injection 0.25x", injection=0.25),
    Candidate("observer J x1.5", inertia_obs=1.5),
    Candidate("observer J x2 (the default below 200 Hz: 2 at 100 Hz)", inertia_obs=2.0),
    Candidate("observer J x0.5", inertia_obs=0.5),
    Candidate("observer beta x0.75", beta_obs=0.75),
    Candidate("observer beta x0.5", beta_obs=0.5),
    Candidate("observer beta x0.75, compensated", beta_obs=0.75, compensate=True),
    Candidate("observer beta x0.5, compensated", beta_obs=0.5, compensate=True),
    Candidate("30 Hz, cancel 0.9", bandwidth=30.0, cancellation=0.9, rates=(1000.0,)),
    Candidate("30 Hz, order 2", bandwidth=30.0, order=2, rates=(1000.0,)),
    Candidate("30 Hz, injection 0.5x", bandwidth=30.0, injection=0.5, rates=(1000.0,)),
    Candidate("30 Hz, observer beta x0.75", bandwidth=30.0, beta_obs=0.75, rates=(1000.0,)),
    Candidate("cancel 0.9", cancellation=0.9, rates=(1000.0,)),
    Candidate("observer beta x0.9", beta_obs=0.9),
    Candidate("observer beta x0.85", beta_obs=0.85),
    Candidate("observer J x1.25", inertia_obs=1.25),
    Candidate("observer beta x0.85, J x1.25", beta_obs=0.85, inertia_obs=1.25),
    Candidate("observer beta x0.8, J x1.25", beta_obs=0.8, inertia_obs=1.25),
    Candidate("observer beta x0.85, J x1.5", beta_obs=0.85, inertia_obs=1.5),
    Candidate("cancel 0.7", cancellation=0.7, rates=(100.0,)),
    Candidate("cancel 0.6", cancellation=0.6, rates=(100.0,)),
    Candidate("cancel 0.4", cancellation=0.4, rates=(100.0,)),
    Candidate("cancel 0.6, injection 0.5x", cancellation=0.6, injection=0.5, rates=(100.0,)),
    Candidate("cancel 0.6, 15 Hz", cancellation=0.6, bandwidth=15.0, rates=(100.0,)),
    Candidate("cancel 0.6, 10 Hz", cancellation=0.6, bandwidth=10.0, rates=(100.0,)),
    Candidate("cancel 0.5, injection 0.75x", cancellation=0.5, injection=0.75, rates=(100.0,)),
    Candidate("cancel 0.5, observer J x1.5", cancellation=0.5, inertia_obs=1.5, rates=(100.0,)),
    Candidate(
        "10 Hz, estimate filter 40 ms", bandwidth=10.0, filter_time_constant=0.04, rates=(100.0,)
    ),
    Candidate(
        "10 Hz, estimate filter 60 ms", bandwidth=10.0, filter_time_constant=0.06, rates=(100.0,)
    ),
    Candidate("integral corner 0.14", integral_corner=1 / 7),
    Candidate("integral corner 0.2", integral_corner=0.2),
    Candidate("J x2, integral corner 0.14", inertia_obs=2.0, integral_corner=1 / 7, rates=(100.0,)),
    Candidate("J x2, integral corner 0.2", inertia_obs=2.0, integral_corner=0.2, rates=(100.0,)),
    Candidate(
        "J x2, estimate filter 5 ms", inertia_obs=2.0, filter_time_constant=0.005, rates=(100.0,)
    ),
    Candidate(
        "J x2, estimate filter 2 ms", inertia_obs=2.0, filter_time_constant=0.002, rates=(100.0,)
    ),
    Candidate("J x2, bandwidth 5 Hz", inertia_obs=2.0, bandwidth=5.0, rates=(100.0,)),
    Candidate("J x2, bandwidth 7 Hz", inertia_obs=2.0, bandwidth=7.0, rates=(100.0,)),
    Candidate("J x2, bandwidth 8.5 Hz", inertia_obs=2.0, bandwidth=8.5, rates=(100.0,)),
    Candidate("J x2, injection 0.5x", inertia_obs=2.0, injection=0.5, rates=(100.0,)),
    Candidate("J x2, injection 0.25x", inertia_obs=2.0, injection=0.25, rates=(100.0,)),
    Candidate("J x2, cancel 0.8", inertia_obs=2.0, cancellation=0.8, rates=(100.0,)),
    Candidate(
        "J x2, 7 Hz, injection 0.5x",
        inertia_obs=2.0,
        bandwidth=7.0,
        injection=0.5,
        rates=(100.0,),
    ),
]


_controllers: dict[tuple[float, int, float, float], StateSpace] = {}


def _controller(hb: HandlebarParameters, c: Candidate, rate: float) -> StateSpace:
    bandwidth = default_bandwidth(rate) if c.bandwidth is None else c.bandwidth
    key = (bandwidth, c.order, rate, c.integral_corner)
    if key not in _controllers:
        design = design_torque_feedback(
            hb,
            rng=np.random.default_rng(0),
            bandwidth=bandwidth,
            order=c.order,
            rate=rate,
            integral_corner=c.integral_corner,
        )
        _controllers[key] = design.controller_zoh
    return _controllers[key]


def _settings(c: Candidate, rate: float) -> ObserverSettings:
    """The observer's settings of candidate ``c`` at ``rate`` [Hz]."""
    settings = ObserverSettings.for_step(1.0 / rate)
    if c.injection is not None:
        settings = dataclasses.replace(
            settings, injection_bandwidth=c.injection * settings.injection_bandwidth
        )
    if c.filter_time_constant is not None:
        settings = dataclasses.replace(settings, filter_time_constant=c.filter_time_constant)
    return settings


def build(c: Candidate, hb: HandlebarParameters, rate: float, speed: float) -> StackModel:
    """The stack of candidate ``c`` for the nominal handlebar ``hb`` at ``rate`` [Hz]."""
    sharp = load_parameters("sharp1971", "sharp")
    controller = _controller(hb, c, rate)
    settings = _settings(c, rate)
    observed = dataclasses.replace(
        hb, beta_eq=c.beta_obs * hb.beta_eq, J_eq=c.inertia_obs * hb.J_eq
    )
    kernel = WalcottZakObserver(design_with(observed, settings), 1.0 / rate).kernel
    model = design_stack(
        sharp,
        kernel,
        controller,
        control_rate=rate,
        measurement_rate=rate,
        lipschitz=300.0,
        max_current=30.0,
        speed=speed,
        handlebar=hb,
        rider_feedforward=True,
        reference_feedforward=True,
    )
    ff = model.feedforward
    ff = ff._replace(
        cancellation=c.cancellation,
        reference=float(c.reference),
        J_eq=ff.J_eq * c.reference_inertia,
        beta_eq=ff.beta_eq * c.reference_damping,
    )
    model = model._replace(feedforward=ff)
    if c.compensate:
        A0 = model.A0.copy()
        A0[:, DELTA_RATE] += (1.0 - c.beta_obs) * hb.beta_eq * model.Bv
        model = model._replace(A0=A0)
    return model


def analyse(
    c: Candidate, model: StackModel, true: HandlebarParameters, speed: float, beta_nom: float
) -> StackLoopAnalysis:
    """:func:`analyse_stack`, the feel and the own modes against the unmodified motorcycle."""
    if not c.compensate:
        return analyse_stack(model, true, speed)
    original = loop_analysis.stack_loop
    extra = (1.0 - c.beta_obs) * beta_nom

    def patched(m: StackModel, h: HandlebarParameters, v: float) -> StackLoop:
        loop = original(m, h, v)
        own = loop.motorcycle.copy()
        own[:, DELTA_RATE] -= extra * loop.motorcycle_input
        return dataclasses.replace(loop, motorcycle=own)

    loop_analysis.stack_loop = patched  # type: ignore[assignment]
    try:
        return analyse_stack(model, true, speed)
    finally:
        loop_analysis.stack_loop = original


def grid(
    hb: HandlebarParameters,
) -> Iterator[tuple[tuple[float, float, float], HandlebarParameters]]:
    """The 27 true handlebars of :func:`motosim.sim.loop_analysis.robustness_grid`."""
    for fj in (0.5, 1.0, 1.5):
        for fb in (0.5, 1.0, 1.5):
            for fk in (0.7, 1.0, 1.3):
                yield (
                    (fj, fb, fk),
                    dataclasses.replace(
                        hb,
                        J_eq=hb.J_eq * fj,
                        beta_eq=hb.beta_eq * fb,
                        k_t=hb.k_t * fk,
                        J_m=0.0,
                        beta_vm=0.0,
                    ),
                )


def ok(a: StackLoopAnalysis) -> bool:
    """Stable with :data:`MARGINS`."""
    return a.stable and a.gain_margin_db >= MARGINS[0] and a.phase_margin_deg >= MARGINS[1]


def _margin(value: float, unit: str) -> str:
    return "inf" if math.isinf(value) else f"{value:.0f}{unit}" if unit == "" else f"{value:.1f}"


def study(c: Candidate, hb: HandlebarParameters, rate: float, speeds: list[float]) -> str:
    """One Markdown row: grid counts per speed, worst nominal margins, feel per speed."""
    counts, gms, pms, feels, failing = [], [], [], [], []
    for speed in speeds:
        model = build(c, hb, rate, speed)
        nominal = analyse(c, model, hb, speed, hb.beta_eq)
        points = [(f, analyse(c, model, t, speed, hb.beta_eq)) for f, t in grid(hb)]
        counts.append(sum(ok(a) for _, a in points))
        gms.append(nominal.gain_margin_db if nominal.stable else -math.inf)
        pms.append(nominal.phase_margin_deg if nominal.stable else -math.inf)
        feels.append(f"{nominal.feel_magnitude_db:.1f}/{nominal.feel_phase_deg:.0f}")
        if speed == 20.0:
            failing = [f for f, a in points if not ok(a)]
    gm, pm = min(gms), min(pms)
    fails = " ".join(f"{a:g},{b:g},{k:g}" for a, b, k in failing) if failing else "-"
    return (
        f"| {c.name} | {rate:g} | {'/'.join(map(str, counts))} | "
        f"{'none' if math.isinf(gm) and gm > 0 else f'{gm:.1f}'} | {pm:.0f} | "
        f"{' '.join(feels)} | {fails} |"
    )


RUNS = (
    ("lane_change_20.toml", 1000.0),
    ("crosswind_30.toml", 1000.0),
    ("obstacle_avoidance_15.toml", 1000.0),
    ("paper/fig15_riding.toml", 100.0),
)
SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


TRAINING = (
    "lane_change_20.toml",
    "crosswind_30.toml",
    "obstacle_avoidance_15.toml",
    "turn_30.toml",
    "opendrive_curve.toml",
    "slalom_10.toml",
    "paper/fig15_riding.toml",
)
"""The closed-loop training scenarios ``--runs ... --at RATE`` simulates at RATE."""


def _inputs(name: str, rate: float | None) -> RunInputs:
    """The scenario's run inputs, at its own rates or (``rate``) at that one for both."""
    if rate is None:
        return load_run(SCENARIOS / name)
    sc = load_scenario(SCENARIOS / name)
    rates = dataclasses.replace(sc.rates, control=rate, measurement=rate)
    return resolve(dataclasses.replace(sc, rates=rates), (SCENARIOS / name).parent)


def runs(c: Candidate, rates: list[float], at: float | None = None) -> None:
    """Closed-loop runs of candidate ``c``: one Markdown row per scenario; ``at``: every
    training scenario at that rate instead of :data:`RUNS` at theirs."""
    plan = RUNS if at is None else tuple((name, at) for name in TRAINING)
    for name, rate in plan:
        inputs = _inputs(name, at)
        sc = inputs.scenario
        if sc.rates.measurement != rate or rate not in c.rates or rate not in rates:
            continue
        hb = inputs.nominal_handlebar
        controller = _controller(hb, c, rate)
        reference = build_stack(dataclasses.replace(inputs, controller=controller))
        model = build(c, hb, rate, sc.motorcycle.speed)
        est = sc.estimator
        settings = dataclasses.replace(
            _settings(c, rate), friction_compensation=est.friction_compensation
        )
        observed = dataclasses.replace(
            hb, beta_eq=c.beta_obs * hb.beta_eq, J_eq=c.inertia_obs * hb.J_eq
        )
        kernel = WalcottZakObserver(
            design_with(observed, settings), 1.0 / rate, stick_projection=est.stick_projection
        ).kernel
        own = model.feedforward
        ff = reference.feedforward._replace(
            cancellation=reference.feedforward.cancellation * c.cancellation,
            reference=own.reference,
            J_eq=own.J_eq,
            beta_eq=own.beta_eq,
        )
        stack = reference._replace(estimator=kernel, feedforward=ff, A0=model.A0)
        run = simulate(inputs, rng=np.random.default_rng(sc.seed), stack=stack)
        m = run_metrics(run.t, run.get, complete=True, max_current=sc.controller.max_current)
        flags = [k[5:] for k, v in m.items() if k.startswith("flag_") and v]
        print(
            f"| {c.name} | {Path(name).stem} | {rate:g} | "
            f"{100 * m['tracking_rms_fraction']:.1f} % | "
            f"{100 * m['estimate_rms_fraction']:.1f} % | "
            f"{m['buzz_current_p2p']:.2f} A at {m['buzz_frequency']:.3g} Hz | "
            f"{', '.join(flags) or '-'} |",
            flush=True,
        )


def wobble(speeds: list[float]) -> None:
    """The steering damper that destabilises the motorcycle at each speed.

    With the steer inertia as it is, and with J_eq / 2 added to it: a true handlebar 1.5
    times heavier than the observer believes puts -(J_eq / 2) delta'' on the motorcycle.
    """
    sharp = load_parameters("sharp1971", "sharp")
    hb = load_parameters("simacom_handlebar", "handlebar")
    A0, A1, Bv = sharp_model.lpv_matrices(sharp)
    print(
        "| speed [m/s] | wobble [Hz, damping ratio] | damper c that destabilises [N*m*s/rad] "
        "| with J_eq / 2 on the steer |"
    )
    print("|---|---|---|---|")
    for v in speeds:
        Av = A0 + v * A1
        cells = []
        for inertia in (0.0, 0.5 * hb.J_eq):
            # (I + dJ Bv e3^T) x' = (Av - c Bv e3^T) x: torque -c delta' - dJ delta'' on the steer
            M = np.eye(8)
            M[:, DELTA_RATE] += inertia * Bv

            def unstable(c: float, Av: np.ndarray = Av, M: np.ndarray = M) -> int:
                A = Av.copy()
                A[:, DELTA_RATE] -= c * Bv
                return int(np.sum(np.linalg.eigvals(np.linalg.solve(M, A)).real > 1e-9))

            own = unstable(0.0, Av, np.eye(8))
            lo, hi = -100.0, 20.0
            if unstable(lo) <= own:
                cells.append("< -100")
                continue
            if unstable(hi) > own:
                cells.append("> 20")
                continue
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                lo, hi = (mid, hi) if unstable(mid) > own else (lo, mid)
            cells.append(f"{hi:.2f}")
        lam = np.linalg.eigvals(Av)
        w = lam[np.argmax(np.abs(lam.imag))]
        print(
            f"| {v:g} | {abs(w.imag) / (2 * math.pi):.1f}, {-w.real / abs(w):.3f} | "
            f"{cells[0]} | {cells[1]} |"
        )
    print(f"\nbeta_eq / 2 = {0.5 * hb.beta_eq:.2f} N*m*s/rad")


def main() -> int:
    """Print the Markdown table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rates", default="1000,100")
    parser.add_argument("--speeds", default="10,20,30")
    parser.add_argument("--only", nargs="*", help="candidate names (default: all)")
    parser.add_argument("--wobble", action="store_true")
    parser.add_argument("--runs", nargs="+", metavar="NAME", help="simulate these candidates")
    parser.add_argument(
        "--at", type=float, metavar="RATE", help="with --runs: every training scenario at RATE"
    )
    args = parser.parse_args()
    speeds = [float(s) for s in args.speeds.split(",")]
    if args.runs:
        print("| candidate | scenario | rate [Hz] | tracking RMS | estimate RMS | buzz | flags |")
        print("|---|---|---|---|---|---|---|")
        for c in CANDIDATES:
            if c.name in args.runs:
                runs(c, [float(r) for r in args.rates.split(",")], args.at)
        return 0
    if args.wobble:
        wobble(speeds)
        return 0
    hb = load_parameters("simacom_handlebar", "handlebar")
    print(
        "| candidate | rate [Hz] | grid with margins at "
        + "/".join(f"{s:g}" for s in speeds)
        + " m/s | worst nominal GM [dB] | PM [deg] | feel dB/deg per speed | failing at 20 m/s"
        " (J beta Nk factors) |"
    )
    print("|---|---|---|---|---|---|---|")
    for c in CANDIDATES:
        if args.only and c.name not in args.only:
            continue
        for rate in (float(r) for r in args.rates.split(",")):
            if rate not in c.rates:
                continue
            print(study(c, hb, rate, speeds), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
