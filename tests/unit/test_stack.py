"""The compiled stack step against the library's reference implementations."""

import dataclasses

import numpy as np
import pytest

from motosim.control.torque_feedback import PAPER_CONTROLLER, discretize
from motosim.estimation.registry import ESTIMATORS, estimate
from motosim.model.handlebar import step_exact
from motosim.params import load_parameters
from motosim.sim.stack import Held, MotorcycleState, design_stack, new_data, reset, step

HB = load_parameters("simacom_handlebar", "handlebar")
BIKE = load_parameters("sharp1971", "sharp")


def _stack(controller=PAPER_CONTROLLER, *, name="walcott_zak", control=1000.0, measurement=1000.0):
    return design_stack(
        BIKE,
        ESTIMATORS[name](HB, 1.0 / measurement).kernel,
        controller,
        control_rate=control,
        measurement_rate=measurement,
        lipschitz=300.0,
        discretization="tustin",
        max_current=1e9,
        speed=20.0,
        true_torque=True,  # the motorcycle sees no torque: it stays upright, delta = 0
    )


def test_command_is_the_discretised_controller() -> None:
    model = _stack()
    data = new_data(model)
    reset(model, data, 0.0, 0.0)
    K = discretize(PAPER_CONTROLLER, 1e-3, "tustin")
    e = np.sin(np.arange(50) * 0.3)
    ours = [step(model, data, ek, 0.0, 0.0, 0.0, 0.0) for ek in e]
    xs, want = np.zeros(1), []
    for ek in e:
        want.append(float((K.C @ xs)[0] + K.D[0, 0] * ek))
        xs = K.A @ xs + K.B[:, 0] * ek
    np.testing.assert_allclose(ours, want, rtol=1e-12, atol=1e-12)
    assert np.all(data.motorcycle[: MotorcycleState.v_x] == 0.0)


def test_saturation_and_no_feedback() -> None:
    model = _stack()._replace(max_current=5.0)
    data = new_data(model)
    reset(model, data, 0.0, 0.0)
    assert step(model, data, 100.0, 0.0, 0.0, 0.0, 0.0) == -5.0
    open_loop = _stack(None)
    data = new_data(open_loop)
    reset(open_loop, data, 0.0, 0.0)
    assert not open_loop.feedback
    assert step(open_loop, data, 1.0, 0.0, 0.0, 0.0, 0.0) == 0.0


@pytest.mark.parametrize("name", sorted(ESTIMATORS))
def test_estimate_in_the_stack_is_the_estimator(name: str) -> None:
    # Without feedback the estimator is told current_error is the current: the stack must
    # then give the batch estimate of motosim.estimation.estimate, sample for sample.
    t = np.arange(0.0, 0.5, 1e-3)
    theta = 0.1 * np.sin(2 * np.pi * 1.5 * t)
    current = 2.0 * np.cos(2 * np.pi * 0.7 * t)
    _, want = estimate(name, t, theta, current, HB)
    model = _stack(None, name=name)
    data = new_data(model)
    reset(model, data, theta[0], current[0])
    ours = []
    for k in range(t.size):
        step(model, data, theta[k], current[k], 0.0, 0.0, 0.0)
        ours.append(data.held[Held.tau_r_hat])
    np.testing.assert_allclose(ours, want, rtol=1e-9, atol=1e-9)


def test_outputs_held_between_measurements() -> None:
    model = _stack(control=1000.0, measurement=100.0)
    assert model.measure_every == 10
    data = new_data(model)
    reset(model, data, 0.0, 0.0)
    commands = [step(model, data, 0.01 * (k + 1), 0.0, 0.0, 0.0, 0.0) for k in range(30)]
    for block in range(3):
        assert len(set(commands[10 * block : 10 * block + 10])) == 1
    assert commands[0] != commands[10] != commands[20]


def test_rates_must_be_whole_multiples() -> None:
    from motosim.errors import MotosimError

    with pytest.raises(MotosimError, match="whole number"):
        _stack(control=1000.0, measurement=300.0)


def test_recorded_layout_recompiles_when_the_signal_table_changes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # The loop's columns are compile-time constants from motosim.signals.RECORDED; numba's
    # cache does not follow that module, so a changed table must trigger a recompilation of
    # the loop. The loop stands in here by what records its recompile() (numba's own, which
    # recompiles every signature the suite has compiled: minutes); the layout's key is
    # recompiled for real, and back.
    from numba.core import config

    from motosim.sim import closed_loop

    recompiled: list[bool] = []

    class Loop:
        def recompile(self) -> None:
            recompiled.append(True)

    monkeypatch.setattr(closed_loop, "_run_chunk", Loop())
    monkeypatch.setattr(closed_loop, "_run_chunk_unreferenced", Loop())
    closed_loop._ensure_current_layout()
    assert recompiled == []  # the compiled layout is the table's
    monkeypatch.setattr(closed_loop, "_LAYOUT_KEY", closed_loop._LAYOUT_KEY + 1)
    closed_loop._ensure_current_layout()
    assert closed_loop._compiled_layout_key() == closed_loop._LAYOUT_KEY
    assert recompiled == ([] if config.DISABLE_JIT else [True, True])  # uncompiled: nothing stale
    monkeypatch.undo()
    if not config.DISABLE_JIT:  # the key's cached code back to the table's
        closed_loop._compiled_layout_key.recompile()
    assert closed_loop._compiled_layout_key() == closed_loop._LAYOUT_KEY


def _cancelling(lead: float):
    """A frictionless handlebar's stack that cancels the estimated rider torque, predicted
    ``lead`` [s] ahead (0: the plain cancellation), at 1 kHz; the motorcycle stays upright."""
    hb = dataclasses.replace(HB, beta_s=0.0)
    model = design_stack(
        BIKE,
        ESTIMATORS["walcott_zak"](hb, 1e-3).kernel,
        PAPER_CONTROLLER,
        control_rate=1000.0,
        measurement_rate=1000.0,
        lipschitz=300.0,
        discretization="tustin",
        max_current=1e9,
        speed=20.0,
        true_torque=True,
        handlebar=hb,
        rider_feedforward=True,
        prediction_lead=lead,
    )
    return model, hb


def test_prediction_reaches_the_step() -> None:
    """From the same data, the predicted stack's command differs from the plain one's by the
    lead's torque, -T_d r / (N k_t) with r the held filtered rate of the estimate; without
    prediction the model carries no lead and the filter's states stay at zero."""
    plain, hb = _cancelling(0.0)
    assert not any(plain.prediction)
    predicted, _ = _cancelling(0.012)
    assert predicted.prediction.lead == 0.012
    data = new_data(predicted)
    reset(predicted, data, 0.0, 0.0)
    for k in range(200):
        step(predicted, data, 1e-4 * k, 0.0, 0.0, 0.0, 0.0)
    assert abs(data.held[Held.tau_r_hat_rate]) > 0.0
    twin = new_data(plain)
    for mine, other in zip(twin, data, strict=True):
        pairs = zip(mine, other, strict=True) if isinstance(mine, tuple) else [(mine, other)]
        for array, value in pairs:  # the RK4's scratch is a record of arrays
            array[...] = value
    lead = -0.012 * data.held[Held.tau_r_hat_rate] / hb.torque_per_amp
    ours = step(predicted, data, 0.02, 0.0, 0.0, 0.0, 0.0)
    theirs = step(plain, twin, 0.02, 0.0, 0.0, 0.0, 0.0)
    assert ours - theirs == pytest.approx(lead, rel=1e-9)


def _ramp_lag(model, hb, slope: float = 5.0, duration: float = 1.5) -> float:
    """Lag [s] of the torque the cancellation reads behind a rider torque ramp of ``slope``
    [N*m/s], at the end of ``duration`` [s]: the stack held by its feedback around the
    frictionless handlebar (integrated exactly, 10 sub-steps a period), the value it reads at
    a command against the rider's torque at that command's instant."""
    data = new_data(model)
    reset(model, data, 0.0, 0.0)
    theta = omega = 0.0
    h = model.dt
    n = round(duration / h)
    read = 0.0
    for k in range(n):
        current = step(model, data, theta, 0.0, 0.0, 0.0, 0.0)
        if k == n - 1:
            held = data.held  # the next command's
            read = held[Held.tau_r_hat] + model.prediction.lead * held[Held.tau_r_hat_rate]
        for j in range(10):
            t = (k + (j + 0.5) / 10) * h
            torque = slope * t + hb.torque_per_amp * current
            theta, omega = step_exact(theta, omega, torque, hb.J_eq, hb.beta_eq, 0.0, h / 10)
    return float((slope * n * h - read) / slope)


def test_the_predicted_cancellation_lags_less_on_a_ramp() -> None:
    """What the lead promises: on a rider torque ramp the plain cancellation reads the
    estimate about the estimate filter's delay late (11.7 ms at 1 kHz, its phase at 1 Hz as
    ``scripts/grid_failures.py`` prints it), the predicted one, T_d = that delay ahead,
    within a small fraction of it (the low-pass and notch have unit gain at zero frequency,
    so the lead's own ramp lag is T_d exactly once they settle)."""
    from motosim.sim.loop_analysis import prediction_lead

    plain, hb = _cancelling(0.0)
    lead = prediction_lead(plain, hb)
    assert 0.011 < lead < 0.0125
    predicted, _ = _cancelling(lead)
    lag_plain = _ramp_lag(plain, hb)
    lag_predicted = _ramp_lag(predicted, hb)
    assert 0.010 < lag_plain < 0.013
    assert abs(lag_predicted) < 0.1 * lag_plain


@pytest.mark.parametrize("delay", [0.0005, 0.005, 0.01])
def test_the_prediction_over_a_measurements_age_is_the_handlebars_own(delay: float) -> None:
    # eq. (5) without friction, J theta'' + beta theta' = tau: from a rate r0 the angle
    # moves r0 (1 - exp(-a d)) / a in d (a = beta / J), under a held torque tau it moves
    # tau / beta (d - (1 - exp(-a d)) / a): closed forms, against the record's matrix
    # exponentials; a handlebar sliding steadily (tau = beta r0) moves r0 d
    from motosim.sim.stack import account_for_delay

    model = account_for_delay(_stack(measurement=100.0), delay, HB)
    a = HB.beta_eq / HB.J_eq
    per_rate = -np.expm1(-a * delay) / a
    assert model.delay.age == delay and model.delay.carried == pytest.approx(delay / 0.01)
    assert model.delay.per_rate == pytest.approx(per_rate, rel=1e-12)
    assert model.delay.per_torque == pytest.approx((delay - per_rate) / HB.beta_eq, rel=1e-9)
    both = model.delay.per_rate + HB.beta_eq * model.delay.per_torque
    assert both == pytest.approx(delay, rel=1e-12)


def test_a_fresh_measurement_and_a_delay_beyond_one_step() -> None:
    from motosim.errors import MotosimError
    from motosim.sim.stack import account_for_delay

    model = _stack(measurement=100.0)
    assert not np.any(model.delay)  # designed for a fresh sample: nothing is predicted
    assert not np.any(account_for_delay(model, 0.0, HB).delay)
    for bad in (-1e-3, 0.011, float("nan")):
        with pytest.raises(MotosimError, match="expected 0 to one measurement step"):
            account_for_delay(model, bad, HB)


def test_the_prediction_over_a_measurements_age_takes_the_observers_friction_width() -> None:
    # the dry friction's tanh in the prediction is the observer's own (its friction_width),
    # so that the two read the same rate as sliding; an estimator without one: the default
    from motosim.estimation.walcott_zak import (
        ObserverSettings,
        WalcottZakObserver,
        design_with,
    )
    from motosim.sim.stack import DELAY_FRICTION_WIDTH, account_for_delay

    settings = dataclasses.replace(ObserverSettings.for_step(0.01), friction_width=0.02)
    kernel = WalcottZakObserver(design_with(HB, settings), 0.01).kernel
    model = design_stack(
        BIKE,
        kernel,
        PAPER_CONTROLLER,
        control_rate=1000.0,
        measurement_rate=100.0,
        lipschitz=300.0,
        max_current=30.0,
        speed=20.0,
    )
    assert account_for_delay(model, 0.005, HB).delay.friction_width == 0.02
    other = account_for_delay(_stack(name="inverse_dynamics", measurement=100.0), 0.005, HB)
    assert other.delay.friction_width == DELAY_FRICTION_WIDTH
