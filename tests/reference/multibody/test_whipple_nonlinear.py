"""The rigid-contact model along trajectories: energy, the constraints, the generated code.

Rolling without slip does no work and the benchmark bicycle has no damping, so a free coast
conserves kinetic plus potential energy exactly (with knife-edge wheels and with toroidal
ones); the integrated speeds must keep satisfying
the rolling constraints and the coordinates the ground contact of both wheels.
"""

import dataclasses
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from motosim.model import _generated_whipple as gen
from motosim.model import whipple
from motosim.params import MultibodyParameters, load_parameters

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def bike() -> MultibodyParameters:
    return load_parameters("benchmark_bicycle", "multibody")


def _coast(
    bike: MultibodyParameters, h: float, duration: float
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    q, u = whipple.upright_state(bike, 4.0)  # below the weave speed: a growing weave
    u[3] = 0.5  # roll rate [rad/s]
    q[4] = whipple.pitch(bike, q[3], q[6])
    u = whipple.dependent_speeds(bike, q, u)
    qs, us = [q], [u]
    for _ in range(round(duration / h)):
        q, u = whipple.rk4_step(bike, q, u, h)
        qs.append(q)
        us.append(u)
    return qs, us


@pytest.mark.parametrize("crowns", [(0.0, 0.0), (0.03, 0.02)], ids=["knife-edge", "toroidal"])
def test_free_coast_conserves_energy(
    bike: MultibodyParameters, crowns: tuple[float, float]
) -> None:
    bike = dataclasses.replace(bike, t_R=crowns[0], t_F=crowns[1])
    qs, us = _coast(bike, 1e-3, 5.0)
    energies = np.array([whipple.energy(bike, q, u) for q, u in zip(qs, us, strict=True)])
    kinetic = energies[0] - whipple.energy(bike, qs[0], np.zeros(8))
    assert max(abs(q[3]) for q in qs) > 0.1  # the machine did move: the weave grew
    drift = np.max(np.abs(energies - energies[0])) / kinetic
    assert drift < 1e-9, drift


@pytest.mark.parametrize("crowns", [(0.0, 0.0), (0.03, 0.02)], ids=["knife-edge", "toroidal"])
def test_constraints_hold_along_the_coast(
    bike: MultibodyParameters, crowns: tuple[float, float]
) -> None:
    bike = dataclasses.replace(bike, t_R=crowns[0], t_F=crowns[1])
    qs, us = _coast(bike, 1e-3, 5.0)
    p = whipple.moore_parameters(bike)
    for q, u in zip(qs[::100], us[::100], strict=True):
        height, _ = gen.holonomic(p, q)
        assert abs(height[0]) < 1e-9
        np.testing.assert_allclose(gen.constraint_matrix(p, q) @ u, 0.0, atol=1e-9)


def test_upright_straight_running_is_an_equilibrium(bike: MultibodyParameters) -> None:
    q, u = whipple.upright_state(bike, 5.0)
    assert u[0] == pytest.approx(5.0, abs=1e-12)  # the rear contact moves forward at 5 m/s
    np.testing.assert_allclose(whipple.accelerations(bike, q, u), 0.0, atol=1e-12)


def test_steer_torque_steers_and_then_leans_the_other_way(bike: MultibodyParameters) -> None:
    """Countersteering, the benchmark's linear model predicts it: a right steer torque
    steers right at once and leans the bicycle left."""
    q, u = whipple.upright_state(bike, 5.0)
    torques = whipple.Torques(steer=1.0)
    for _ in range(300):
        q, u = whipple.rk4_step(bike, q, u, 1e-3, torques)
    assert q[6] > 0.0 and q[3] < 0.0


def test_regenerating_reproduces_the_committed_code() -> None:
    """``scripts/derive_multibody.py --check`` rederives the equations (a few seconds)."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "derive_multibody.py"), "--check"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert time.perf_counter() - start < 120.0
