"""The compiled stack step against the library's reference implementations."""

import numpy as np

from motosim.control.torque_feedback import PAPER_CONTROLLER, discretize
from motosim.sim.stack import stack_command


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
