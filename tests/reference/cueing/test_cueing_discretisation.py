"""Discrete washout and vestibular filters against their continuous design (scipy.signal).

Target of issue 13: the discrete filters are within 1 % of the continuous design below 0.2
of the Nyquist frequency. The error is measured on the complex frequency response and
taken relative to the filter's peak gain over that band, ``|H_d - H_c| <= 0.01 max |H_c|``
(the continuous responses are scipy.signal.freqs, the discrete ones scipy.signal.freqz).
"""

import math

import numpy as np
import pytest
from scipy import signal

from motosim.cueing.filters import highpass2, lowpass2, tustin
from motosim.cueing.platform import load_platform
from motosim.cueing.washout import design_washout

RATES = [100.0, 250.0, 1000.0]  # the loop rates the stack runs at [Hz]


def _error(num: tuple[float, ...], den: tuple[float, ...], section: np.ndarray, dt: float) -> float:
    w = np.linspace(1e-3, 0.2 * math.pi / dt, 2000)  # up to 0.2 of the Nyquist frequency
    _, hc = signal.freqs(num, den, worN=w)
    _, hd = signal.freqz(section[:3], [1.0, section[3], section[4]], worN=w * dt)
    return float(np.max(np.abs(hd - hc)) / np.max(np.abs(hc)))


@pytest.mark.parametrize("rate", RATES)
def test_washout_sections_within_one_percent(rate: float) -> None:
    dt = 1.0 / rate
    tune = load_platform("simacom_platform").washout
    d = design_washout(tune, dt)
    w, z = tune.roll_onset_frequency, tune.roll_onset_damping
    assert (
        _error((tune.roll_onset_gain, 0, 0), (1, 2 * z * w, w * w), np.array(d.roll_onset), dt)
        < 0.01
    )
    w, z = tune.tilt_frequency, tune.tilt_damping
    assert _error((w * w,), (1, 2 * z * w, w * w), np.array(d.tilt), dt) < 0.01
    w, z = tune.pitch_onset_frequency, tune.pitch_onset_damping
    assert (
        _error((tune.pitch_onset_gain, 0, 0), (1, 2 * z * w, w * w), np.array(d.pitch_onset), dt)
        < 0.01
    )
    w, z = tune.yaw_frequency, tune.yaw_damping
    assert _error((tune.yaw_gain, 0), (1, 2 * z * w, w * w), np.array(d.yaw), dt) < 0.01


@pytest.mark.parametrize("frequency", [0.3, 1.0, 5.0, 12.0])
def test_generic_sections_within_one_percent_at_100_hz(frequency: float) -> None:
    dt = 0.01  # corners up to 12 rad/s = 0.19 of the 62.8 rad/s band edge
    w, z = frequency, 0.7
    assert _error((1, 0, 0), (1, 2 * z * w, w * w), highpass2(1.0, w, z, dt), dt) < 0.01
    assert _error((w * w,), (1, 2 * z * w, w * w), lowpass2(1.0, w, z, dt), dt) < 0.01
    assert _error((w,), (1, w), tustin((w,), (1, w), dt), dt) < 0.01
