"""The rendered steering feel (``motosim fidelity``): measured, and improved by the feedforward."""

import dataclasses
import json

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.io.runs import resolve
from motosim.sim import simulate
from motosim.sim.fidelity import feel_scenario, rendered_feel
from motosim.sim.scenario import Scenario


def _worst_against_the_run(feedforward: tuple[str, ...]) -> float:
    """RMS over 0.5-3 Hz of |theta_h / tau_r| / |delta / tau_r| in the run [dB]."""
    base = Scenario(name="feel")
    base = dataclasses.replace(
        base, controller=dataclasses.replace(base.controller, feedforward=feedforward)
    )
    scenario = feel_scenario(base, speed=20.0, duration=20.0)
    inputs = resolve(scenario, ".")
    r = simulate(inputs, rng=np.random.default_rng(0))
    feel = rendered_feel(r.t, r["tau_r"], r["theta_h"], r["delta"], inputs.sharp, 20.0)
    band = (feel.frequency >= 0.5) & (feel.frequency <= 3.0)
    ratio_db = 20 * np.log10(np.abs(feel.rendered[band] / feel.steer[band]))
    return float(np.sqrt(np.mean(ratio_db**2)))


def test_handlebar_renders_the_virtual_steer_closer_with_feedforward() -> None:
    # The handlebar's response to the rider is the motorcycle's steer response when it
    # tracks delta. Measured over 0.5-3 Hz at 20 m/s (20 s chirp): 2.0 dB RMS apart with the
    # feedforward, 6.6 dB with the feedback alone.
    with_ff = _worst_against_the_run(("rider", "reference"))
    without = _worst_against_the_run(())
    assert with_ff < 2.5
    assert with_ff < 0.5 * without


def test_fidelity_command_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["fidelity", "--duration", "12", "--band", "0.5:3", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload["worst_in"] == [0.5, 3.0]
    assert len(payload["frequency_hz"]) == len(payload["magnitude_error_db"]) > 10
    assert np.isfinite(payload["worst_magnitude_error_db"])


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--speed", "100"], "--speed 100.0; expected 3 to 60 m/s"),
        (["--band", "3:1"], "band = 3:1"),
        (["--band", "x"], "--band 'x'"),
        (["--duration", "1"], "--duration 1.0"),
    ],
)
def test_fidelity_bad_options(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main(["fidelity", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
