"""The compiled stack step against the library's reference implementations."""

import numpy as np

from motosim.control.torque_feedback import PAPER_CONTROLLER, discretize
from motosim.model import sharp as model
from motosim.params import SharpParameters, derived_geometry
from motosim.sim.stack import bike_rk4, stack_command


def test_bike_step_matches_the_reference_simulation(sharp: SharpParameters) -> None:
    """bike_rk4 (A_v frozen over each 1 ms step) against model.sharp.simulate (A_v per stage)."""
    h, n = 1e-3, 3000
    t = np.arange(n + 1) * h
    torque = np.where(t < 0.3, 3.0, 0.0)
    ref = model.simulate(sharp, t, initial_speed=15.0, rider_torque=torque, drive_torque=200.0)
    A0, A1, Bv = model._state_space_parts(sharp)
    d = derived_geometry(sharp)
    z = np.zeros(12)
    z[8] = 15.0
    work = np.zeros((13, 12))
    for k in range(n):
        bike_rk4(z, work, A0, A1, Bv, torque[k], 200.0 / d["r_D"], d["m"], d["m_eq"], 1.0, h)
    # freezing the speed inside each step costs 2e-4 relative after 3 s of 2.7 m/s^2 accelerating
    np.testing.assert_allclose(z, ref.data[-1], rtol=1e-3, atol=1e-9 * np.abs(ref.data).max())


def test_controller_step_is_the_discretised_controller() -> None:
    K = discretize(PAPER_CONTROLLER, 1e-3, "tustin")
    x = np.zeros(1)
    e = np.sin(np.arange(50) * 0.3)
    ours = [stack_command(x, K.A, K.B, K.C, K.D, ek, 0.0, 1e9, True, np.zeros(1)) for ek in e]
    xs, want = np.zeros(1), []
    for ek in e:
        want.append(float((K.C @ xs)[0] + K.D[0, 0] * ek))
        xs = K.A @ xs + K.B[:, 0] * ek
    np.testing.assert_allclose(ours, want, rtol=1e-12, atol=1e-12)
    # saturation, and no current at all in the open loop of Fig. 9
    assert stack_command(x, K.A, K.B, K.C, K.D, 100.0, 0.0, 5.0, True, np.zeros(1)) == -5.0
    assert stack_command(x, K.A, K.B, K.C, K.D, 1.0, 0.0, 5.0, False, np.zeros(1)) == 0.0
