"""Coupled Sharp + eq. (2) simulation: compiled fixed-step RK4 against scipy's solve_ivp."""

import numpy as np
from scipy.integrate import solve_ivp

from motosim.model import sharp as model
from motosim.params import derived_geometry, load_parameters
from timing import best


def run() -> dict[str, float]:
    """10 s of a 20 m/s run with a rider-torque pulse and braking, 1 ms steps."""
    p = load_parameters("sharp1971", "sharp")
    t = np.arange(0.0, 10.0, 1e-3)
    torque = np.where(t < 0.5, 2.0, 0.0)
    brake = np.where(t > 5.0, 300.0, 0.0)
    model.simulate(p, t[:10], initial_speed=20.0)  # compile
    ours = best(
        lambda: model.simulate(p, t, initial_speed=20.0, rider_torque=torque, brake_torque=brake)
    )
    M = model.mass_matrix(p)
    E0, E1 = model.stiffness_matrices(p)
    Minv = np.linalg.inv(M)
    A0, A1, Bv = -Minv @ E0, -Minv @ E1, Minv @ model.input_matrix(p)
    d = derived_geometry(p)

    def rhs(time_s: float, z: np.ndarray) -> np.ndarray:
        k = min(int(time_s / 1e-3), t.size - 1)
        x, v = z[:8], z[8]
        acc = (-brake[k] / d["r_D"] + d["m"] * x[1] * x[0]) / d["m_eq"]
        return np.concatenate([A0 @ x + v * (A1 @ x) + Bv * torque[k], [acc]])

    z0 = np.zeros(9)
    z0[8] = 20.0
    baseline = best(
        lambda: solve_ivp(rhs, (0.0, 10.0), z0, t_eval=t, method="RK45", max_step=1e-3),
        repeat=1,
    )
    return {
        "compiled RK4 steps/s": t.size / ours,
        "solve_ivp RK45 (max_step 1 ms) samples/s": t.size / baseline,
        "speed-up over solve_ivp": baseline / ours,
    }
