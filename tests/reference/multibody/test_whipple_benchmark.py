"""The rigid-contact multibody model against the benchmark bicycle's published numbers.

References: Meijaard, Papadopoulos, Ruina & Schwab (2007), "Linearized dynamics equations for
the balance and steer of a bicycle: a benchmark and review", Proc. R. Soc. A 463:1955-1982
(Table 1 the parameters, Table 2 the eigenvalues, weave and capsize speeds, and the numerical
matrices M, C1, K0, K2 it prints for Table 1's bicycle); Basu-Mandal, Chatterjee &
Papadopoulos (2007), "Hands-free circular motions of a benchmark bicycle", Proc. R. Soc. A
463:1983-2003, Table 1 (a general state and its accelerations). The linearisation is not a
separate derivation: it is the nonlinear model's exact (complex-step) Jacobian.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from motosim.model import whipple
from motosim.params import MultibodyParameters, load_parameters


@pytest.fixture(scope="module")
def bike() -> MultibodyParameters:
    return load_parameters("benchmark_bicycle", "multibody")


# Meijaard et al. (2007), Table 2: eigenvalues at v = 0, 1, ..., 10 m/s (the same digits as
# libbicycle's src/tests/benchmark_eigenvalues.h). Per speed: the capsize branch (real), the
# weave pair (real, imaginary; below the bifurcation speed two real roots) and the castering
# root.
TABLE_2 = {
    0: [-3.13164324790656, 3.13164324790656, -5.53094371765393, 5.53094371765393],
    1: [
        -3.13423125066578,
        3.52696170990070 + 0.80774027519930j,
        3.52696170990070 - 0.80774027519930j,
        -7.11008014637442,
    ],
    2: [
        -3.07158645641514,
        2.68234517512745 + 1.68066296590675j,
        2.68234517512745 - 1.68066296590675j,
        -8.67387984831735,
    ],
    3: [
        -2.63366137253667,
        1.70675605663975 + 2.31582447384325j,
        1.70675605663975 - 2.31582447384325j,
        -10.35101467245920,
    ],
    4: [
        -1.42944427361326,
        0.41325331521125 + 3.07910818603206j,
        0.41325331521125 - 3.07910818603206j,
        -12.15861426576450,
    ],
    5: [
        -0.32286642900409,
        -0.77534188219585 + 4.46486771378823j,
        -0.77534188219585 - 4.46486771378823j,
        -14.07838969279820,
    ],
    6: [
        -0.00406690076970,
        -1.52644486584142 + 5.87673060598709j,
        -1.52644486584142 - 5.87673060598709j,
        -16.08537123098030,
    ],
    7: [
        0.10268170574766,
        -2.13875644258362 + 7.19525913329805j,
        -2.13875644258362 - 7.19525913329805j,
        -18.15788466125262,
    ],
    8: [
        0.14327879765713,
        -2.69348683581097 + 8.46037971396931j,
        -2.69348683581097 - 8.46037971396931j,
        -20.27940894394569,
    ],
    9: [
        0.15790184030917,
        -3.21675402252485 + 9.69377351531791j,
        -3.21675402252485 - 9.69377351531791j,
        -22.43788559040858,
    ],
    10: [
        0.16105338653172,
        -3.72016840437287 + 10.90681139476287j,
        -3.72016840437287 - 10.90681139476287j,
        -24.62459635017404,
    ],
}
WEAVE_SPEED = 4.29238253634111  # Meijaard et al. 2007, Table 2 (a), v_w [m/s]
CAPSIZE_SPEED = 6.02426201538837  # Meijaard et al. 2007, Table 2 (a), v_c [m/s]


def _eigenvalues(bike: MultibodyParameters, speed: float) -> np.ndarray:
    return np.sort_complex(np.linalg.eigvals(whipple.linearize(bike, speed)))


@pytest.mark.parametrize("speed", sorted(TABLE_2))
def test_eigenvalues_match_meijaard_table_2(bike: MultibodyParameters, speed: int) -> None:
    expected = np.sort_complex(np.array(TABLE_2[speed], dtype=complex))
    np.testing.assert_allclose(_eigenvalues(bike, speed), expected, atol=1e-8, rtol=0)


def test_weave_and_capsize_speeds_match_table_2(bike: MultibodyParameters) -> None:
    def weave_real(v: float) -> float:
        ev = _eigenvalues(bike, v)
        return float(max(ev[np.abs(ev.imag) > 1e-9].real))

    def capsize(v: float) -> float:
        ev = _eigenvalues(bike, v)
        real = ev[np.abs(ev.imag) < 1e-9].real
        return float(real[np.argmin(np.abs(real))])

    weave = brentq(weave_real, 4.0, 4.5, xtol=1e-13)
    cap = brentq(capsize, 5.5, 6.5, xtol=1e-13)
    assert abs(weave - WEAVE_SPEED) < 1e-8
    assert abs(cap - CAPSIZE_SPEED) < 1e-8


def test_benchmark_matrices_match_meijaard(bike: MultibodyParameters) -> None:
    # Meijaard et al. 2007: the numerical M, C1, K0, K2 of the benchmark bicycle (Table 1)
    published = {
        "M": [[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]],
        "C1": [[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]],
        "K0": [[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]],
        "K2": [[0.0, 76.59734589573222], [0.0, 2.65431523794604]],
    }
    got = whipple.benchmark_matrices(bike)._asdict()
    for name, value in published.items():
        np.testing.assert_allclose(got[name], value, atol=1e-10, rtol=0, err_msg=name)


def test_benchmark_matrices_match_dynamicisttoolkit(bike: MultibodyParameters) -> None:
    """Oracle: DynamicistToolKit's closed-form benchmark matrices (Meijaard's appendix A)."""
    bicycle = pytest.importorskip("dtk.bicycle")
    M, C1, K0, K2 = bicycle.benchmark_matrices()
    got = whipple.benchmark_matrices(bike)
    for name, ours, theirs in (
        ("M", got.M, M),
        ("C1", got.C1, C1),
        ("K0", got.K0, K0),
        ("K2", got.K2, K2),
    ):
        np.testing.assert_allclose(ours, theirs, atol=1e-11, rtol=0, err_msg=name)


# Basu-Mandal, Chatterjee & Papadopoulos (2007), Table 1: the benchmark bicycle in a general
# state (their coordinates: rear wheel centre x, y, z; yaw theta, lean psi, pitch phi, rear
# wheel betar, steer psif, front wheel betaf) and the accelerations it has there.
BASU_STATE = {
    "x": 0.0,
    "y": 0.0,
    "z": 0.2440472102925,
    "theta": 0.0,
    "psi": 0.9501292851472,
    "phi": 3.1257073014894,
    "psif": 0.2311385135743,
    "betar": 0.0,
    "betaf": 0.0,
    "xd": -2.8069345714545,
    "yd": -0.1480982396001,
    "zd": 0.1058778746261,
    "thetad": 0.7830033527065,
    "psid": 0.6068425835418,
    "phid": -0.0119185528069,
    "psifd": 0.4859824687093,
    "betard": 8.9129896614890,
    "betafd": 8.0133620584155,
}
BASU_ACCELERATIONS = {
    "xdd": -0.5041626315047,
    "ydd": -0.3449706619454,
    "zdd": -1.4604528332980,
    "thetadd": 0.8353281706379,
    "psidd": -7.8555281128244,
    "phidd": 0.1205543897884,
    "psifdd": -4.6198904039403,
    "betardd": 1.8472554144217,
    "betafdd": 2.4548072904550,
}


def _basu_to_moore(b: dict[str, float], rr: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """Basu-Mandal's coordinates and rates in Moore's: their z is up, their lean is measured
    from the ground plane, their pitch from the ground backwards; the rear wheel centre is
    (q1 - rr sin q3 sin q4, q2 + rr cos q3 sin q4, -rr cos q4) in Moore's ground axes."""
    q = np.array(
        [
            0.0,
            0.0,
            -b["theta"],
            math.pi / 2 - b["psi"],
            math.pi - b["phi"] + lam,
            -b["betar"],
            -b["psif"],
            -b["betaf"],
        ]
    )
    u = np.array(
        [0.0, 0.0, -b["thetad"], -b["psid"], -b["phid"], -b["betard"], -b["psifd"], -b["betafd"]]
    )
    s3, c3, s4, c4 = math.sin(q[2]), math.cos(q[2]), math.sin(q[3]), math.cos(q[3])
    q[0] = rr * s3 * s4 - b["x"]
    q[1] = b["y"] - rr * c3 * s4
    u[0] = rr * (c3 * s4 * u[2] + s3 * c4 * u[3]) - b["xd"]
    u[1] = b["yd"] - rr * (-s3 * s4 * u[2] + c3 * c4 * u[3])
    return q, u


def _moore_to_basu_accelerations(
    q: np.ndarray, u: np.ndarray, ud: np.ndarray, rr: float
) -> dict[str, float]:
    s3, c3, s4, c4 = math.sin(q[2]), math.cos(q[2]), math.sin(q[3]), math.cos(q[3])
    X_dd = ud[0] - rr * (
        -s3 * s4 * u[2] ** 2
        + 2 * c3 * c4 * u[2] * u[3]
        + c3 * s4 * ud[2]
        - s3 * s4 * u[3] ** 2
        + s3 * c4 * ud[3]
    )
    Y_dd = ud[1] + rr * (
        -c3 * s4 * u[2] ** 2
        - 2 * s3 * c4 * u[2] * u[3]
        - s3 * s4 * ud[2]
        - c3 * s4 * u[3] ** 2
        + c3 * c4 * ud[3]
    )
    return {
        "xdd": -X_dd,
        "ydd": Y_dd,
        "zdd": rr * (-c4 * u[3] ** 2 - s4 * ud[3]),
        "thetadd": -ud[2],
        "psidd": -ud[3],
        "phidd": -ud[4],
        "betardd": -ud[5],
        "psifdd": -ud[6],
        "betafdd": -ud[7],
    }


def test_basu_mandal_table_1(bike: MultibodyParameters) -> None:
    q, u = _basu_to_moore(BASU_STATE, bike.r_R, bike.lam)
    # the table's state is on the constraints: its pitch and dependent rates are ours
    assert abs(whipple.pitch(bike, q[3], q[6]) - q[4]) < 1e-12
    np.testing.assert_allclose(whipple.dependent_speeds(bike, q, u), u, atol=1e-12, rtol=0)
    assert abs(bike.r_R * math.cos(q[3]) - BASU_STATE["z"]) < 1e-12
    ud = whipple.accelerations(bike, q, u)
    got = _moore_to_basu_accelerations(q, u, ud, bike.r_R)
    for name, value in BASU_ACCELERATIONS.items():
        assert abs(got[name] - value) < 1e-9, (name, got[name], value)


def test_basu_mandal_conversion_matches_dynamicisttoolkit(bike: MultibodyParameters) -> None:
    """Oracle: DynamicistToolKit's own Basu-Mandal to Moore conversion of Table 1's state."""
    bicycle = pytest.importorskip("dtk.bicycle")
    theirs = bicycle.basu_to_moore_input(bicycle.basu_table_one_input(), bike.r_R, bike.lam)
    q, u = _basu_to_moore(BASU_STATE, bike.r_R, bike.lam)
    np.testing.assert_allclose(q, [theirs[f"q{i}"] for i in range(1, 9)], atol=1e-12)
    np.testing.assert_allclose(u, [theirs[f"u{i}"] for i in range(1, 9)], atol=1e-12)
    moore = {f"q{i}": q[i - 1] for i in range(1, 9)} | {f"u{i}": u[i - 1] for i in range(1, 9)}
    ud = whipple.accelerations(bike, q, u)
    moore |= {f"u{i}p": ud[i - 1] for i in range(1, 9)}
    basu = bicycle.moore_to_basu(moore, bike.r_R, bike.lam)
    for name, value in BASU_ACCELERATIONS.items():
        assert abs(basu[name] - value) < 1e-9, (name, basu[name], value)
