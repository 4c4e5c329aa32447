"""Limit manager: zero violations on a stress corpus, no overshoot across neutral."""

import numpy as np
import pytest

from motosim.cueing.limits import actuator_response, apply_limits, design_limits
from motosim.cueing.platform import Platform, load_platform

DT = 0.01
N = 2000


@pytest.fixture(scope="module")
def platform() -> Platform:
    return load_platform("simacom_platform").platform


def _corpus() -> list[np.ndarray]:
    """Abrupt inputs: steps, square waves, impulses, noise, chirps, far beyond the limits."""
    rng = np.random.default_rng(13)
    t = np.arange(N) * DT
    out = []
    for amplitude in (0.05, 0.5, 3.0):
        out.append(np.where(t > 1.0, amplitude, 0.0))
        out.append(amplitude * np.sign(np.sin(2 * np.pi * rng.uniform(0.1, 5.0) * t)))
        spikes = np.zeros(N)
        spikes[rng.integers(0, N, 20)] = amplitude * rng.choice([-1.0, 1.0], 20)
        out.append(spikes)
        out.append(amplitude * rng.standard_normal(N))
        out.append(amplitude * np.sin(2 * np.pi * (0.05 + 2.0 * t) * t))
        out.append(np.cumsum(rng.normal(0.0, amplitude * 0.05, N)))
        out.append(amplitude * rng.choice([-1.0, 1.0], N // 50).repeat(50))
    return out


def _violations(x: np.ndarray, limit: float, rate: float, accel: float) -> int:
    tol = 1e-9
    v = np.diff(np.concatenate([[0.0, 0.0], x])) / DT  # from neutral rest
    a = np.diff(v) / DT
    return int(
        np.sum(np.abs(x) > limit * (1 + tol))
        + np.sum(np.abs(v) > rate * (1 + tol))
        + np.sum(np.abs(a) > accel * (1 + tol) + 1e-6)
    )


def test_zero_violations_on_the_stress_corpus(platform: Platform) -> None:
    design = design_limits(platform, DT)
    total = 0
    for signal in _corpus():
        targets = np.column_stack([signal, signal, signal])
        out = apply_limits(design, targets)
        for j, axis in enumerate(platform.axes):
            total += _violations(out[:, j], axis.angle, axis.rate, axis.accel)
            achieved = actuator_response(platform, DT, out)
            total += _violations(achieved[:, j], axis.angle, axis.rate, axis.accel)
    assert total == 0


def test_held_target_is_reached_without_overshoot(platform: Platform) -> None:
    design = design_limits(platform, DT)
    targets = np.zeros((N, 3))
    targets[10:] = [0.2, 0.1, -0.15]
    out = apply_limits(design, targets)
    np.testing.assert_allclose(out[-1], [0.2, 0.1, -0.15], atol=1e-12)
    assert np.all(out[:, 0] <= 0.2 + 1e-12) and np.all(out[:, 2] >= -0.15 - 1e-12)


def test_return_to_neutral_never_crosses_it(platform: Platform) -> None:
    design = design_limits(platform, DT)
    rng = np.random.default_rng(5)
    for _ in range(20):  # one-signed inputs that drop to neutral abruptly, at any speed
        signal = np.abs(rng.normal(0.0, 0.3, N // 20)).repeat(20)
        signal[rng.integers(0, N, 30)] = 0.0
        out = apply_limits(design, np.column_stack([signal, signal, -signal]))
        assert np.all(out[:, :2] >= 0.0) and np.all(out[:, 2] <= 0.0)


def test_never_moves_away_from_a_held_neutral(platform: Platform) -> None:
    design = design_limits(platform, DT)
    targets = np.zeros((N, 3))
    targets[:300] = 0.17  # a cue, then neutral held: the approach is monotonic
    out = apply_limits(design, targets)
    tail = out[300:, 0]
    assert np.all(np.diff(tail) <= 1e-15) and tail[-1] == 0.0


def test_zero_violations_with_wild_target_rates(platform: Platform) -> None:
    # the feed-forward rate is a hint: whatever it says, the limits hold
    design = design_limits(platform, DT)
    rng = np.random.default_rng(7)
    total = 0
    for signal in _corpus():
        targets = np.column_stack([signal, signal, signal])
        rates = rng.normal(0.0, 5.0, targets.shape)
        out = apply_limits(design, targets, rates)
        for j, axis in enumerate(platform.axes):
            total += _violations(out[:, j], axis.angle, axis.rate, axis.accel)
    assert total == 0


def test_a_planned_ramp_is_followed_without_lag(platform: Platform) -> None:
    # a ramp at 10 deg/s from rest, within the rate and acceleration limits, with its rate
    design = design_limits(platform, DT)
    t = np.arange(150) * DT  # 12.5 deg at the end, within the 20 deg roll limit
    speed = np.radians(10.0) * np.minimum(t / 0.5, 1.0)  # reached at 20 deg/s^2
    ramp = np.cumsum(speed) * DT
    targets = np.column_stack([ramp, 0 * t, 0 * t])
    rates = np.column_stack([speed, 0 * t, 0 * t])
    followed = apply_limits(design, targets, rates)[:, 0]
    braked = apply_limits(design, targets)[:, 0]
    assert np.max(np.abs(followed - ramp)) < np.radians(0.05)
    assert np.max(np.abs(braked - ramp)) > np.radians(0.2)  # braking towards each sample lags


def test_a_planned_sweep_through_neutral_is_not_stopped_there(platform: Platform) -> None:
    # a planned roll x = A (cos wt - cos 2wt) from rest, through neutral both ways (A = 3 deg,
    # w = 2.5 rad/s: rate <= 23 deg/s, acceleration <= 5 A w^2 = 94 deg/s^2, within the
    # limits), with its rate: followed without braking to a stop at each crossing of neutral
    design = design_limits(platform, DT)
    t = np.arange(600) * DT
    a, w = np.radians(3.0), 2.5
    plan = a * (np.cos(w * t) - np.cos(2 * w * t))
    speed = a * w * (2 * np.sin(2 * w * t) - np.sin(w * t))
    zero = 0 * t
    followed = apply_limits(
        design, np.column_stack([plan, zero, zero]), np.column_stack([speed, zero, zero])
    )[:, 0]
    assert np.max(np.abs(followed - plan)) < np.radians(0.05)
    assert np.max(np.abs(np.diff(followed, 2))) / DT**2 < np.radians(100.0)
