"""Classical washout: what each channel promises in the time domain."""

import math

import numpy as np
import pytest

from motosim.cueing.platform import WashoutTuning, load_platform
from motosim.cueing.washout import apply_washout, design_washout
from motosim.errors import MotosimError

DT = 0.01


@pytest.fixture
def tuning() -> WashoutTuning:
    return load_platform("simacom_platform").washout


def _run(tuning: WashoutTuning, phi=0.0, theta=0.0, a_x=0.0, psi_dot=0.0, n=3000) -> np.ndarray:
    inputs = np.zeros((n, 4))
    inputs[100:] = [phi, theta, a_x, psi_dot]  # a step after 1 s
    return apply_washout(design_washout(tuning, DT), inputs)


def test_small_lean_is_sustained_at_the_scale(tuning: WashoutTuning) -> None:
    out = _run(tuning, phi=0.05)
    level = tuning.roll_sustained
    expected = level * math.tanh(tuning.roll_scale * 0.05 / level)  # 0.3 % below linear
    assert out[-1, 0] == pytest.approx(expected, rel=1e-6)  # the onset washed out
    assert out[101, 0] > tuning.roll_scale * 0.05  # the onset adds to the first instants


def test_large_lean_saturates_softly_below_the_sustained_level(tuning: WashoutTuning) -> None:
    out = _run(tuning, phi=math.radians(45.0))
    expected = tuning.roll_sustained * math.tanh(
        tuning.roll_scale * math.radians(45) / tuning.roll_sustained
    )
    assert out[-1, 0] == pytest.approx(expected, rel=1e-3)
    assert out[-1, 0] < tuning.roll_sustained


def test_tilt_coordination_reaches_asin_and_respects_the_rate_limit(tuning: WashoutTuning) -> None:
    out = _run(tuning, a_x=-2.0, n=6000)
    assert out[-1, 1] == pytest.approx(math.asin(-2.0 / 9.81), rel=1e-3)
    assert np.max(np.abs(np.diff(out[:, 1]))) / DT <= tuning.tilt_rate * (1 + 1e-9)


def test_yaw_and_pitch_onsets_wash_out(tuning: WashoutTuning) -> None:
    out = _run(tuning, psi_dot=0.3, theta=0.05, n=6000)
    assert abs(out[-1, 2]) < 1e-4 and abs(out[-1, 1]) < 1e-4
    assert np.max(out[:, 2]) > 0.01  # but a yaw cue in the right direction first


def test_visual_horizon_completes_the_platform_roll(tuning: WashoutTuning) -> None:
    rng = np.random.default_rng(1)
    inputs = np.zeros((500, 4))
    inputs[:, 0] = np.cumsum(rng.normal(0.0, 0.01, 500))
    out = apply_washout(design_washout(tuning, DT), inputs)
    np.testing.assert_allclose(
        out[:, 0] + out[:, 3], tuning.horizon_gain * inputs[:, 0], atol=1e-15
    )


def test_corner_above_a_fifth_of_nyquist_is_refused(tuning: WashoutTuning) -> None:
    with pytest.raises(MotosimError, match="roll_onset_frequency = 1 rad/s"):
        design_washout(tuning, 1.0)  # 0.2 * pi rad/s band edge at 1 Hz, yaw corner 1 rad/s
