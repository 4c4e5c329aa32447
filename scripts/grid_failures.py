"""Which handlebars of the robustness grid lose the margins, where, and what the bound says.

    .venv/bin/python scripts/grid_failures.py [--rates 1000,100] [--speed 20] [--all]
        [--no-prediction]

For the default design (``motosim design`` on the packaged handlebar; ``--no-prediction``:
with the plain rider-torque cancellation) at each rate and the speed, every handlebar of
:func:`motosim.sim.loop_analysis.robustness_grid` (J_eq, beta_eq x0.5/1/1.5, N k_t
x0.7/1/1.3) that is not stable with 6 dB and 45 deg (or every one with ``--all``) gets one
Markdown row:

- the whole stack's margins, broken at the motor current (:func:`analyse_stack`, what
  ``motosim design`` counts), with the frequencies of the crossings that set them;
- for a loop that adds an unstable mode, the frequency of that mode;
- the rider-torque cancellation's own loop, broken at the estimate it reads
  (:func:`cancellation_loop_gain`): its gain and phase margins and where;
- the gain margin that :func:`cancellation_bound` predicts from the estimate filter F alone,
  and where F Delta crosses the negative real axis.

Above the rows, F (rider torque to the torque the cancellation reads, :func:`estimate_filter`)
where its phase reaches -180 deg, its largest gain, and at 1 Hz its gain and its lag as a
delay; with the prediction, its lead T_d (the plain estimate's delay at 1 Hz,
:func:`prediction_lead`).
"""

import argparse
import dataclasses
import math

import numpy as np

from motosim.control.torque_feedback import default_bandwidth, design_torque_feedback
from motosim.estimation.walcott_zak import WalcottZakObserver, design_with
from motosim.params import load_parameters
from motosim.params.handlebar import HandlebarParameters
from motosim.sim.closed_loop import observer_settings
from motosim.sim.loop_analysis import (
    MARGINS,
    analyse_stack,
    cancellation_bound,
    cancellation_loop_gain,
    estimate_filter,
    negative_real_crossings,
    prediction_lead,
    stack_loop,
)
from motosim.sim.stack import StackModel, default_prediction, design_stack

POINTS = 4000  # frequencies of the crossing search


def default_stack(
    hb: HandlebarParameters, rate: float, speed: float, prediction: bool | None = None
) -> StackModel:
    """The stack ``motosim design`` analyses: default bandwidth, order 1, both feedforwards,
    the predicted cancellation where :func:`default_prediction` says (or ``prediction``)."""
    sharp = load_parameters("sharp1971", "sharp")
    controller = design_torque_feedback(
        hb, rng=np.random.default_rng(0), bandwidth=default_bandwidth(rate), order=1, rate=rate
    ).controller_zoh
    kernel = WalcottZakObserver(design_with(hb, observer_settings(rate)), 1.0 / rate)

    def build(lead: float = 0.0) -> StackModel:
        return design_stack(
            sharp,
            kernel.kernel,
            controller,
            control_rate=rate,
            measurement_rate=rate,
            lipschitz=300.0,
            max_current=30.0,
            speed=speed,
            handlebar=hb,
            rider_feedforward=True,
            reference_feedforward=True,
            prediction_lead=lead,
        )

    model = build()
    if default_prediction(rate) if prediction is None else prediction:
        model = build(prediction_lead(model, hb))
    return model


def crossings(L: np.ndarray, f: np.ndarray) -> tuple[float, float, float, float]:
    """(gain margin [dB], its frequency, phase margin [deg], its frequency) of 1 + L."""
    gm, fg, pm, fp = math.inf, math.nan, math.inf, math.nan
    for _, where, x in negative_real_crossings(L, f):
        if abs(20.0 * math.log10(-x)) < gm:
            gm, fg = abs(20.0 * math.log10(-x)), where
    mag = np.abs(L)
    for k in range(L.size - 1):
        if (mag[k] - 1.0) * (mag[k + 1] - 1.0) < 0.0:
            p = 180.0 - abs(math.degrees(np.angle(L[k])))
            if p < pm:
                pm, fp = p, f[k]
    last = L[-1]
    if (
        abs(last.imag) <= 1e-9 * abs(last)
        and last.real < 0.0
        and abs(20 * math.log10(-last.real)) < gm
    ):
        gm, fg = abs(20.0 * math.log10(-last.real)), f[-1]  # real at the Nyquist frequency
    return gm, fg, pm, fp


def _cell(value: float, where: float, unit: str) -> str:
    return "none" if math.isinf(value) else f"{value:.1f}{unit} at {where:.1f} Hz"


def rows(rate: float, speed: float, show_all: bool, prediction: bool | None) -> None:
    """Print the Markdown rows of one rate."""
    hb = load_parameters("simacom_handlebar", "handlebar")
    model = default_stack(hb, rate, speed, prediction)
    f = np.append(np.geomspace(0.05, 0.999 * 0.5 * rate, POINTS - 1), 0.5 * rate)
    F = estimate_filter(model, hb, speed, f)
    phase = np.unwrap(np.angle(F))
    k180 = int(np.argmax(phase < -math.pi))
    one = int(np.argmin(np.abs(f - 1.0)))
    delay = -phase[one] / (2 * math.pi * f[one])  # F's lag at 1 Hz as a delay [s]
    print(
        f"\n{rate:g} Hz, {speed:g} m/s: F = {abs(F[k180]):.3f} where its phase reaches -180 deg "
        f"({f[k180]:.1f} Hz); max |F| {np.max(np.abs(F)):.3f} at {f[np.argmax(np.abs(F))]:.1f} Hz"
        f"; at 1 Hz |F| {abs(F[one]):.3f}, a delay of {delay * 1e3:.1f} ms"
        + (f" (predicted {model.prediction[0] * 1e3:.1f} ms ahead)" if model.prediction[0] else "")
    )
    print(
        "\n| J, beta, N k_t | stack at the motor current: GM; PM | unstable mode "
        "| cancellation loop: GM; PM | bound from F: GM |"
    )
    print("|---|---|---|---|---|")
    count = 0
    for fj in (0.5, 1.0, 1.5):
        for fb in (0.5, 1.0, 1.5):
            for fk in (0.7, 1.0, 1.3):
                true = dataclasses.replace(
                    hb,
                    J_eq=hb.J_eq * fj,
                    beta_eq=hb.beta_eq * fb,
                    k_t=hb.k_t * fk,
                    J_m=0.0,
                    beta_vm=0.0,
                )
                a = analyse_stack(model, true, speed)
                ok = (
                    a.stable
                    and a.gain_margin_db >= MARGINS[0]
                    and (a.phase_margin_deg >= MARGINS[1])
                )
                count += ok
                if ok and not show_all:
                    continue
                loop = stack_loop(model, true, speed)
                gm, fg, pm, fp = crossings(loop.loop_gain(f, 1), f)
                mode = "-"
                if not a.stable:
                    eig = np.linalg.eigvals(loop.A)
                    worst = eig[np.argmax(np.abs(eig))]
                    at = abs(np.angle(worst)) * rate / (2 * math.pi)
                    mode = f"{at:.1f} Hz, |z| {abs(worst):.3f}"
                cg, cfg, cp, cfp = crossings(cancellation_loop_gain(loop, f), f)
                bound = cancellation_bound(F, f, hb, true, 1.0 / rate)
                bound_cell = (
                    "none"
                    if math.isinf(bound.gain_margin_db)
                    else f"{bound.gain_margin_db:.1f} dB at {bound.frequency:.1f} Hz"
                ) + (
                    ""
                    if math.isinf(bound.low_frequency_db)
                    else f"; low {bound.low_frequency_db:.1f} dB"
                )
                print(
                    f"| {fj:g}, {fb:g}, {fk:g} | {_cell(gm, fg, ' dB')}; {_cell(pm, fp, ' deg')} "
                    f"| {mode} | {_cell(cg, cfg, ' dB')}; {_cell(cp, cfp, ' deg')} "
                    f"| {bound_cell} |",
                    flush=True,
                )
    print(f"\n{count} of 27 stable with {MARGINS[0]:g} dB and {MARGINS[1]:g} deg")


def main() -> int:
    """Print the tables."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rates", default="1000,100")
    parser.add_argument("--speed", type=float, default=20.0)
    parser.add_argument("--all", action="store_true", help="every handlebar, not only failing")
    parser.add_argument("--no-prediction", action="store_true", help="the plain cancellation")
    args = parser.parse_args()
    for rate in (float(r) for r in args.rates.split(",")):
        rows(rate, args.speed, args.all, False if args.no_prediction else None)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
