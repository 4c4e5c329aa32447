"""The virtual rig's plant with the rider's hands on it (:mod:`motosim.sim.hands`)."""

import numpy as np
import pytest

from motosim.model.handlebar import step_exact
from motosim.params import load_parameters
from motosim.rt.rig import Bar, RigRider, RigSettings, VirtualRig
from motosim.sim.hands import NO_ARMS, Arms

pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import handlebar_codecs

HB = load_parameters("simacom_handlebar", "handlebar")
SETTINGS = RigSettings(
    plant_rate=10_000.0,
    status_rate=1000.0,
    encoder_bits=14,
    current_noise=0.0,
    max_current=30.0,
)


class _Link:
    def send(self, frame_id: int, data: bytes) -> bool:
        return True

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        return None


def _rig(rider: float, arms: Arms, off: np.ndarray | None = None) -> VirtualRig:
    return VirtualRig(
        HB,
        SETTINGS,
        handlebar_codecs(),
        _Link(),
        RigRider(np.full(100_000, rider), on_enable=False, arms=arms, hands_off=off),
        np.random.default_rng(0),
    )


def test_rig_hands_are_the_simulators_plant() -> None:
    """3 N*m of active torque through firm hands about 0.05 rad: the arms' inertia and
    damping added to the handlebar's, their spring taken at each 0.1 ms sub-step's midpoint
    (as the simulator's plant takes it at each step's)."""
    J_a, c_a, k_a, hold = 0.1, 4.0, 50.0, 0.05
    rig = _rig(3.0, Arms(J_a, c_a, k_a, hold))
    rig.advance_to(0.5)
    theta, omega = 0.0, 0.0
    for _ in range(5000):
        torque = 3.0 - k_a * (theta + 0.5e-4 * omega - hold)
        theta, omega = step_exact(
            theta, omega, torque, HB.J_eq + J_a, HB.beta_eq + c_a, HB.beta_s, 1e-4
        )
    assert rig.x[Bar.theta] == pytest.approx(theta, rel=1e-12)
    assert rig.x[Bar.omega] == pytest.approx(omega, abs=1e-12)


def test_rig_without_hands_is_unchanged_and_hands_off_removes_the_rider() -> None:
    plain = _rig(3.0, NO_ARMS)
    plain.advance_to(0.2)
    theta, omega = 0.0, 0.0
    for _ in range(2000):
        theta, omega = step_exact(theta, omega, 3.0, HB.J_eq, HB.beta_eq, HB.beta_s, 1e-4)
    assert plain.x[Bar.theta] == theta and plain.x[Bar.omega] == omega
    off = _rig(3.0, Arms(0.1, 4.0, 50.0, 0.0), np.array([[0.0, 1.0]]))
    off.advance_to(0.2)
    # nobody holds it, no current: at rest
    assert off.x[Bar.theta] == 0.0 and off.x[Bar.omega] == 0.0
