"""Bad logs and options raise one-line MotosimError; excitation and measurement basics."""

import dataclasses

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.identification import (
    MeasurementModel,
    chirp_voltage,
    drive_from_columns,
    excitation_run,
    identify,
    measure,
    plan_excitation,
    square_voltage,
)
from motosim.params import load_parameters
from motosim.timeseries import TimeSeries


@pytest.fixture(scope="module")
def log() -> TimeSeries:
    hb = load_parameters("simacom_handlebar", "handlebar")
    return excitation_run(hb, "chirp", 10.0, MeasurementModel(), np.random.default_rng(0))


def _with(log: TimeSeries, t=None, data=None, names=None) -> TimeSeries:
    return TimeSeries(
        log.t if t is None else t, log.data if data is None else data, names or log.names
    )


def _raises(log: TimeSeries, match: str) -> None:
    with pytest.raises(MotosimError, match=match) as info:
        identify(log, torque_per_amp=3.0, drive="current_sampled")
    assert "\n" not in str(info.value)


def test_missing_column(log):
    _raises(_with(log, names=("theta_h", "current", "u")), "no column 'i_m'")


def test_duplicated_time(log):
    t = log.t.copy()
    t[10] = t[9]
    _raises(_with(log, t=t), "duplicated")


def test_non_monotonic_time(log):
    t = log.t.copy()
    t[10], t[11] = t[11], t[10]
    _raises(_with(log, t=t), "decreasing")


def test_nan_sample(log):
    data = log.data.copy()
    data[20, 0] = np.nan
    _raises(_with(log, data=data), "'theta_h' is not finite at sample 20")


def test_too_few_samples(log):
    _raises(TimeSeries(log.t[:20], log.data[:20], log.names), "20 samples")


def test_handlebar_at_rest_is_too_poor(log):
    data = log.data.copy()
    data[:, 0] = 0.0
    _raises(_with(log, data=data), "excitation too poor")


def test_constant_speed_is_too_poor(log):
    # theta'' = 0 and sign = 1 everywhere: J_eq unidentifiable, beta_eq and beta_s collinear
    data = log.data.copy()
    data[:, 0] = 0.3 * log.t
    _raises(_with(log, data=data), "excitation too poor")


def test_unknown_method(log):
    with pytest.raises(MotosimError, match="method"):
        identify(log, torque_per_amp=3.0, method="magic")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "kwargs",
    [
        {"sample_rate": 0.0},
        {"counts_per_revolution": 0},
        {"counts_per_revolution": 2.5},
        {"pulley_ratio": -1.0},
        {"current_noise": float("nan")},
    ],
)
def test_measurement_model_validation(kwargs):
    with pytest.raises(MotosimError):
        MeasurementModel(**kwargs)


def test_signals():
    u = chirp_voltage(amplitude=3.0, f0=0.1, f1=2.0, duration=10.0, rate=100.0)
    assert u.t.size == 1001
    assert np.max(np.abs(u["u"])) <= 3.0
    s = square_voltage(amplitude=2.0, frequency=1.0, duration=2.0, rate=100.0)
    assert set(np.unique(s["u"])) == {-2.0, 2.0}
    assert np.mean(s["u"][:200]) == pytest.approx(0.0, abs=0.05)


def test_measure_quantises_and_is_seeded():
    t = np.linspace(0.0, 1.0, 10_001)
    truth = TimeSeries(t, np.column_stack([np.sin(t), np.cos(t), t]), ("theta_h", "i_m", "u"))
    model = MeasurementModel(current_noise=0.1)
    a = measure(truth, model, np.random.default_rng(1))
    b = measure(truth, model, np.random.default_rng(1))
    np.testing.assert_array_equal(a.data, b.data)
    steps = a["theta_h"] / model.angle_resolution
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    assert a.t.size == 101
    assert np.std(a["i_m"] - np.cos(a.t)) == pytest.approx(0.1, rel=0.3)


def test_excitation_run_columns():
    hb = load_parameters("simacom_handlebar", "handlebar")
    hb = dataclasses.replace(hb, beta_s=0.5)
    run = excitation_run(hb, "square", 2.0, MeasurementModel(), np.random.default_rng(2))
    assert run.names == ("theta_h", "i_m", "u")
    assert run.t.size == 201
    with pytest.raises(MotosimError, match="signal"):
        excitation_run(hb, "noise", 2.0, MeasurementModel(), np.random.default_rng(2))  # type: ignore[arg-type]


def test_plan_excitation_limits():
    # 2 pi f1 J/beta = 15 % where the sample rate allows; a tenth of the rate otherwise
    plan = plan_excitation(
        J_eq=0.06, beta_eq=9.0, beta_s=1.0, torque_per_amp=1.0, sample_rate=100.0, max_current=5.0
    )
    assert plan.inertia_share == pytest.approx(0.15)
    assert plan.amplitude == pytest.approx(4.0) and plan.notes == ()
    fast = plan_excitation(
        J_eq=0.015, beta_eq=15.0, beta_s=1.0, torque_per_amp=1.0, sample_rate=100.0, max_current=5.0
    )
    assert fast.f1 == pytest.approx(10.0) and "sample at" in fast.notes[0]
    with pytest.raises(MotosimError, match="2 beta_s"):
        plan_excitation(
            J_eq=0.06,
            beta_eq=9.0,
            beta_s=3.0,
            torque_per_amp=1.0,
            sample_rate=100.0,
            max_current=5.0,
        )


@pytest.mark.parametrize(
    ("names", "drive"),
    [
        (("theta_h", "i_m"), "current_sampled"),
        (("theta_h", "i_cmd"), "current_held"),
        (("theta_h", "i_m", "i_cmd"), "current_held"),
        (("theta_h", "i_m", "u"), "voltage_held"),
    ],
)
def test_drive_follows_the_columns(names, drive):
    assert drive_from_columns(names)[0] == drive


@pytest.mark.parametrize(
    ("names", "message"),
    [
        (("theta_h", "i_cmd", "u"), "give --drive current_held or --drive voltage_held"),
        (("theta_h", "u"), "no measured current i_m"),
        (("theta_h",), "no current column"),
    ],
)
def test_ambiguous_columns_name_the_option(names, message):
    with pytest.raises(MotosimError, match=message) as info:
        drive_from_columns(names)
    assert "\n" not in str(info.value)
