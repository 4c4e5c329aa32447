"""The stack's settings against the buzz (:class:`motosim.sim.stack.Quiet`), each on what it
promises.

- The differentiator that knows the encoder's count (:func:`cell_step`) moves its rate by at
  most b q / h at a sample while its prediction stays within a count of the angle; a plain
  difference of the counts (the implicit super-twisting step) moves it by q / h, clipped to
  h lambda_0 L, at each count edge.
- The Dahl friction term (:func:`dahl_friction`) moves by about 2 beta_s A / x_0 on a wobble
  of amplitude A << x_0, where the tanh of the rate flips by 2 beta_s.
- A sticking handlebar (the same count for ``stick_samples`` measurements): the
  controller's state and the rider-torque estimate hold, and move again at the next count.
"""

import math

import numpy as np
import pytest

from motosim.control.torque_feedback import PAPER_CONTROLLER
from motosim.errors import MotosimError
from motosim.estimation.differentiator import LAMBDA_0, cell_step, std_step
from motosim.estimation.registry import ESTIMATORS
from motosim.params import load_parameters
from motosim.sim.stack import (
    NO_QUIET,
    Held,
    Quiet,
    dahl_friction,
    design_stack,
    new_data,
    reset,
    step,
)

HB = load_parameters("simacom_handlebar", "handlebar")
BIKE = load_parameters("sharp1971", "sharp")
Q = 2.0 * math.pi / 2**14  # the scenarios' default 14-bit encoder [rad]
H = 1e-3
L = 300.0  # the scenarios' default Lipschitz bound [rad/s^2]


def _rates(theta: np.ndarray, cell: bool, a: float = 0.5, b: float = 0.1) -> np.ndarray:
    counts = np.round(theta / Q) * Q
    z0, z1, out = counts[0], 0.0, []
    for f in counts:
        if cell:
            z0, z1 = cell_step(z0, z1, f, H, Q, a, b)
        else:
            z0, z1 = std_step(z0, z1, f, H, 1.5 * math.sqrt(L), LAMBDA_0 * L, True)
        out.append(z1)
    return np.array(out)


@pytest.mark.parametrize(
    "theta",
    [
        0.01 * np.arange(0.0, 4.0, H) + 1e-5,  # a slow creep: a count every 38 ms
        0.05 * np.sin(2.0 * np.pi * np.arange(0.0, 4.0, H)),  # a 1 Hz steer of 0.05 rad
    ],
    ids=["creep", "steer"],
)
def test_a_count_edge_moves_the_cell_rate_by_at_most_b_q_over_h(theta: np.ndarray) -> None:
    b = 0.1
    cell = _rates(theta, True, b=b)[1000:]
    plain = _rates(theta, False)[1000:]
    assert np.max(np.abs(np.diff(cell))) <= b * Q / H * (1.0 + 1e-9)
    # the plain difference jumps by the whole count at an edge, clipped to h lambda_0 L
    assert np.max(np.abs(np.diff(plain))) >= 0.99 * H * LAMBDA_0 * L


def test_a_consistent_count_adds_nothing() -> None:
    z0, z1 = cell_step(0.0, 0.1, 0.0, H, Q, 0.5, 0.1)  # 0.1 mrad on: inside +-q/2
    assert (z0, z1) == (pytest.approx(1e-4), 0.1)


def test_dahl_friction_barely_moves_on_a_wobble_and_reaches_beta_s_on_a_slide() -> None:
    beta_s, x0 = HB.beta_s, 1e-3
    t = np.arange(0.0, 1.0, H)
    amplitude = 1e-4  # the virtual motorcycle's wobble, 8.6 Hz, a quarter of a count
    rate = amplitude * 2.0 * np.pi * 8.6 * np.cos(2.0 * np.pi * 8.6 * t)
    friction, seen = 0.0, []
    for r in rate:
        friction = dahl_friction(friction, r * H, beta_s, x0, H, 0.0)
        seen.append(friction)
    assert np.ptp(seen) <= 2.0 * beta_s * 2.0 * amplitude / x0
    tanh = beta_s * np.tanh(rate / 0.002)  # the term it replaces flips at each reversal
    assert np.ptp(tanh) > 1.9 * beta_s
    for _ in range(5):  # 5 x_0 in one direction
        friction = dahl_friction(friction, x0, beta_s, x0, H, 0.0)
    assert friction == pytest.approx(beta_s, rel=math.exp(-4.0))
    released = dahl_friction(friction, 0.0, beta_s, x0, H, 0.1)
    assert released == pytest.approx(friction * math.exp(-H / 0.1))


def _stack(quiet: Quiet):  # type: ignore[no-untyped-def]
    return design_stack(
        BIKE,
        ESTIMATORS["walcott_zak"](HB, H).kernel,
        PAPER_CONTROLLER,
        control_rate=1000.0,
        measurement_rate=1000.0,
        lipschitz=L,
        discretization="tustin",
        max_current=30.0,
        speed=20.0,
        true_torque=True,
        handlebar=HB,
        rider_feedforward=True,
        quiet=quiet,
    )


def test_a_sticking_handlebar_holds_the_estimate_and_the_integral() -> None:
    """The handlebar held on one count 2 counts off the motorcycle's (upright) steer: the
    controller integrates that error and the estimate reads the current as rider torque
    unless both hold; they move again at the next count."""
    held = {}
    for label, quiet in (("off", NO_QUIET), ("on", NO_QUIET._replace(stick_samples=5))):
        model = _stack(quiet)
        data = new_data(model)
        reset(model, data, 0.0, 0.0)
        for _ in range(10):
            step(model, data, 2 * Q, 0.0, 0.0, 0.0, 0.0)
        before = data.controller.copy(), data.held[Held.tau_r_hat]
        for _ in range(1000):
            step(model, data, 2 * Q, 0.0, 0.0, 0.0, 0.0)
        after = data.controller.copy(), data.held[Held.tau_r_hat]
        held[label] = (np.max(np.abs(after[0] - before[0])), abs(after[1] - before[1]))
        if label == "on":
            step(model, data, 3 * Q, 0.0, 0.0, 0.0, 0.0)  # the next count: released
            assert np.max(np.abs(data.controller - after[0])) > 0.0
    assert held["on"] == (0.0, 0.0)
    assert held["off"][0] > 0.0 and held["off"][1] > 0.0


@pytest.mark.parametrize(
    ("field", "value"),
    [("quantum", -1.0), ("presliding", math.nan), ("release", 1e3), ("stick_samples", -1)],
)
def test_bad_settings_are_refused_naming_the_value(field: str, value: float) -> None:
    with pytest.raises(MotosimError, match=f"quiet {field} = "):
        _stack(NO_QUIET._replace(**{field: value}))


def test_cell_gains_are_checked_when_the_count_is_known() -> None:
    with pytest.raises(MotosimError, match=r"quiet rate_gain = 0\.0; expected a share"):
        _stack(Quiet(Q, 0.5, 0.0, 0.0, 0.0, 0))
