"""Control design: H-infinity norm against SLICOT, and the first-order synthesis time."""

import numpy as np

from motosim.control import hinf_norm, ncfsyn
from motosim.control.torque_feedback import design_torque_feedback
from motosim.params import load_parameters
from timing import best


def _random_stable(rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    A = rng.normal(size=(n, n))
    A -= (np.max(np.linalg.eigvals(A).real) + 0.1) * np.eye(n)
    return A, rng.normal(size=(n, 2)), rng.normal(size=(2, n)), rng.normal(size=(2, 2))


def run() -> dict[str, float]:
    """Seconds per H-infinity norm (ours and AB13DD) and per first-order design."""
    rng = np.random.default_rng(0)
    systems = [_random_stable(rng, 8) for _ in range(50)]
    ours = best(lambda: [hinf_norm(*s) for s in systems]) / len(systems)
    out = {"hinf_norm, 8 states 2x2 [ms]": 1e3 * ours}
    try:
        from slycot import ab13dd

        def oracle(A, B, C, D):  # type: ignore[no-untyped-def]
            return ab13dd("C", "I", "N", "D", A.shape[0], 2, 2, A, np.eye(A.shape[0]), B, C, D)

        theirs = best(lambda: [oracle(*s) for s in systems]) / len(systems)
        out["slycot ab13dd, same systems [ms]"] = 1e3 * theirs
        out["ours / ab13dd"] = ours / theirs
    except ImportError:
        out["slycot ab13dd"] = float("nan")
    hb = load_parameters("simacom_handlebar", "handlebar")
    design = design_torque_feedback(hb, rng=np.random.default_rng(0))
    full = best(lambda: ncfsyn(*_shaped(design)))
    first = best(lambda: design_torque_feedback(hb, rng=np.random.default_rng(0)), repeat=1)
    out["first-order design of the handlebar loop [s]"] = first
    out["full-order ncfsyn on the same shaped plant [s]"] = full
    out["first-order gamma / full-order gamma_min"] = design.gamma / design.gamma_min
    return out


def _shaped(design):  # type: ignore[no-untyped-def]
    from motosim.control.torque_feedback import _weight, handlebar_plants, series

    hb = load_parameters("simacom_handlebar", "handlebar")
    G_s = series(_weight(design.weight_gain, design.weight_corner), handlebar_plants(hb)[0])
    return G_s.A, G_s.B, G_s.C, G_s.D
