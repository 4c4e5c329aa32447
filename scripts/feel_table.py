"""Where the rendered feel's error comes from: measurement or loop, one row per run.

    .venv/bin/python scripts/feel_table.py [--quick]

Each row is a feel measurement (:func:`motosim.sim.fidelity.feel_scenario`) on the default
stack, varied one thing at a time: the probe (a periodic multisine averaged over whole
periods, or the linear chirp analysed by Welch's method), its peak torque, how tightly the
virtual rider holds the straight, the handlebar's dry friction, the encoder, and whether the
virtual motorcycle is driven by the estimated or the true rider torque. Printed as a Markdown
table over 0.1-3 Hz: the worst and median error of theta_h / tau_r against the model's
delta / tau_r, split into the handlebar against the run's own steer angle (theta_h / delta,
the tracking) and the run's steer angle against the model (delta / tau_r, which the torque
estimate drives), the share of the lowest line's probe torque the rider leaves
(|tau_r / probe| at 0.1 Hz, multisine only) and the share of time the handlebar sticks after
the first fifth of the run.
``--quick`` runs the rows at 20 m/s, 1 kHz only.
"""

import argparse
import dataclasses

import numpy as np

from motosim.io.runs import resolve
from motosim.sim import simulate
from motosim.sim.fidelity import FeelResponse, feel_scenario, periodic_feel, rendered_feel
from motosim.sim.scenario import MultisineProfile, Scenario

BAND = (0.1, 3.0)
TIGHT = (0.3, 0.05)  # the rider of the first fidelity measurement [m, rad]
LOOSE = (3.0, 0.5)  # feel_scenario's default


def _row(
    *,
    excitation: str = "multisine",
    amplitude: float = 10.0,
    rider: tuple[float, float] = LOOSE,
    friction: bool = True,
    encoder_bits: int = 14,
    motorcycle_input: str = "estimate",
    speed: float = 20.0,
    rate: float = 1000.0,
) -> str:
    base = Scenario(name="feel")
    base = dataclasses.replace(
        base,
        rates=dataclasses.replace(base.rates, control=rate, measurement=rate),
        handlebar=dataclasses.replace(base.handlebar, friction=friction),
        measurement=dataclasses.replace(base.measurement, encoder_bits=encoder_bits),
        motorcycle=dataclasses.replace(base.motorcycle, input=motorcycle_input),
    )
    scenario = feel_scenario(
        base,
        speed=speed,
        amplitude=amplitude,
        excitation=excitation,  # type: ignore[arg-type]
        lateral_tolerance=rider[0],
        course_tolerance=rider[1],
    )
    inputs = resolve(scenario, ".")
    r = simulate(inputs, rng=np.random.default_rng(scenario.seed), keep=True)
    probe = scenario.rider.probe
    signals = (r.t, r["tau_r"], r["theta_h"], r["delta"], inputs.sharp, speed)
    feel: FeelResponse
    left = "-"
    if isinstance(probe, MultisineProfile):
        feel = periodic_feel(*signals, probe=probe)
        applied = probe.sample(r.t, {})
        share = periodic_feel(
            r.t, applied, r["tau_r"], r["delta"], inputs.sharp, speed, probe=probe
        )
        left = f"{abs(share.rendered[0]):.2f}"
    else:
        feel = rendered_feel(*signals)
    band = (feel.frequency >= BAND[0] - 1e-9) & (feel.frequency <= BAND[1] + 1e-9)

    def worst(ratio: np.ndarray) -> str:
        with np.errstate(divide="ignore"):
            db = np.max(np.abs(20 * np.log10(np.abs(ratio[band]))))
        return f"{db:.2f} dB, {np.max(np.abs(np.degrees(np.angle(ratio[band])))):.1f} deg"

    if not np.all(np.abs(feel.rendered) > 0):
        measured = "the handlebar never moves"
    else:
        median = feel.median(*BAND)
        measured = (
            f"{worst(feel.rendered / feel.model)} (median {median[0]:.2f} dB, {median[1]:.1f} deg)"
        )
    stick = float(np.mean(r["theta_h_dot"][r.t > 0.2 * r.t[-1]] == 0.0))
    what = (
        f"{excitation} {amplitude:g} N*m, rider {rider[0]:g} m / {rider[1]:g} rad, "
        f"{'friction' if friction else 'no friction'}, "
        f"{f'{encoder_bits}-bit' if encoder_bits else 'exact angle'}, "
        f"motorcycle on the {motorcycle_input} torque, {speed:g} m/s, {rate:g} Hz"
    )
    return (
        f"| {what} | {measured} | {worst(feel.rendered / feel.steer)} | "
        f"{worst(feel.steer / feel.model)} | {left} | {100 * stick:.0f} % |"
    )


def main() -> None:
    """Print the table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="20 m/s, 1 kHz only")
    args = parser.parse_args()
    rows = [
        {"excitation": "chirp", "amplitude": 3.0, "rider": TIGHT},  # the first measurement
        {
            "excitation": "chirp",
            "amplitude": 3.0,
            "rider": TIGHT,
            "friction": False,
            "encoder_bits": 0,
        },
        {"friction": False, "encoder_bits": 0},
        {"friction": False},
        {"rider": TIGHT},
        {"rider": TIGHT, "motorcycle_input": "true"},
        {},
        {"amplitude": 3.0},
        {"amplitude": 30.0},
        {"excitation": "chirp"},
        {"motorcycle_input": "true"},
    ]
    if not args.quick:
        rows += [
            {"excitation": "chirp", "amplitude": 3.0, "rider": TIGHT, "speed": 10.0},
            {"speed": 10.0},
            {"excitation": "chirp", "amplitude": 3.0, "rider": TIGHT, "speed": 30.0},
            {"speed": 30.0},
            {"excitation": "chirp", "amplitude": 3.0, "rider": TIGHT, "rate": 100.0},
            {"rate": 100.0},
        ]
    print(
        "| run | theta_h / tau_r against the model | theta_h / delta | delta / tau_r against "
        "the model | abs(tau_r / probe) at 0.1 Hz | handlebar stuck |"
    )
    print("|---|---|---|---|---|---|")
    for row in rows:
        print(_row(**row), flush=True)  # type: ignore[arg-type]


if __name__ == "__main__":
    main()
