"""Sharp (1971) lateral model against published and independently derived numbers.

Sources:
- [notes]: M, E0, E1, B_v of the standard machine from Sharp's Appendix 3 parameters, as an
  independent Kane's-method derivation of the model gives them (aerotinez/madsym,
  examples/sharpmotorcycle, sharpMotorcycleSS*.m; agreement 1e-13), and the eigenvalues and
  stability boundaries of that derivation.
- [S71]: R.S. Sharp, J. Mech. Eng. Sci. 13(5):316-329, 1971, Tables 1-3, model 1 (as
  transcribed in 0tmeF/MotoDynamics); speeds converted from ft/s.
"""

import numpy as np
import pytest

from motosim.model import sharp as model
from motosim.params import SharpParameters, derived_geometry

# [notes] section 6, rounded to 5 decimals there.
M_TOP = np.array(
    [
        [248.09635, 26.16929, 148.20024, 0.74730],
        [26.16929, 44.02043, 10.16983, 1.03188],
        [148.20024, 10.16983, 121.37409, 0.54989],
        [0.74730, 1.03188, 0.54989, 0.46022],
    ]
)
E0_REF = {
    (0, 6): -1,
    (0, 7): -1,
    (1, 6): 0.47976,
    (1, 7): -0.93470,
    (2, 4): -1453.34786,
    (2, 5): -123.76617,
    (3, 3): 6.77909,
    (3, 4): -123.76617,
    (3, 5): -56.21746,
    (3, 7): 0.11582,
    (4, 2): -1,
    (5, 3): -1,
    (6, 0): 15831.22073,
    (6, 1): -7595.11047,
    (7, 0): 11173.93270,
    (7, 1): 10444.28276,
    (7, 3): -1294.20958,
}
E1_REF = {
    (0, 1): 248.09635,
    (1, 1): 26.16929,
    (1, 2): -5.80493,
    (1, 3): -1.07086,
    (2, 1): 154.00517,
    (2, 3): 2.10032,
    (3, 1): 1.81816,
    (3, 2): -2.10032,
    (6, 4): -1325.57004,
    (6, 6): 1,
    (7, 4): -938.57476,
    (7, 5): -10381.04443,
    (7, 7): 1,
}
B_V_20 = np.array([0.00874, -0.05536, -0.01646, 2.30249, 0, 0, 0, 0])  # [notes], u = 20 m/s

# [S71] Tables 1-3 (model 1): speed [ft/s] -> capsize, weave, wobble eigenvalues.
SHARP_TABLE = {
    10: (-3.56, 2.01 + 1.63j, -5.20 + 55.70j),
    30: (-0.13, -3.36 + 4.56j, -6.42 + 55.50j),
    70: (0.08, -3.97 + 16.80j, -5.70 + 54.00j),
    130: (0.05, -1.13 + 20.40j, -2.24 + 55.60j),
}
FT = 0.3048


def _dense(entries: dict[tuple[int, int], float]) -> np.ndarray:
    out = np.zeros((8, 8))
    for (i, j), v in entries.items():
        out[i, j] = v
    return out


def test_mass_matrix_matches_reference(sharp: SharpParameters) -> None:
    M = model.mass_matrix(sharp)
    np.testing.assert_allclose(M[:4, :4], M_TOP, rtol=1e-6, atol=1e-5)  # 6 digits as printed
    np.testing.assert_allclose(M, M.T)
    assert M[4, 4] == M[5, 5] == 1.0
    np.testing.assert_allclose([M[6, 6], M[7, 7]], 0.24384, atol=1e-5)
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_stiffness_matrices_match_reference(sharp: SharpParameters) -> None:
    E0, E1 = model.stiffness_matrices(sharp)
    np.testing.assert_allclose(E0, _dense(E0_REF), atol=2e-5, rtol=1e-6)
    np.testing.assert_allclose(E1, _dense(E1_REF), atol=2e-5, rtol=1e-6)


def test_input_matrix_matches_reference(sharp: SharpParameters) -> None:
    lin = model.linearize(sharp, 20.0)
    np.testing.assert_allclose(lin.B[:, 0], B_V_20, atol=1e-5)
    assert lin.input_names == ("tau_r",)
    assert lin.state_names == model.STATE_NAMES


def test_derived_geometry(sharp: SharpParameters) -> None:
    d = derived_geometry(sharp)
    # [notes] section 4 and sharp1971-params.json "derived"
    assert d["j"] == pytest.approx(0.467177, abs=1e-6)
    assert d["k"] == pytest.approx(0.853889, abs=1e-6)
    assert d["l"] == pytest.approx(0.934701, abs=1e-6)
    assert d["m_eq"] == pytest.approx(267.141393, abs=1e-5)
    # static front load from the geometry: -1006.7 N against Sharp's Z_f = -1005.3 N
    z_f = -sharp.g * (sharp.m_r * sharp.b + sharp.m_f * (sharp.b + d["k"])) / d["wheelbase"]
    assert z_f == pytest.approx(sharp.Z_f, rel=0.002)


@pytest.mark.parametrize("speed_fts", sorted(SHARP_TABLE))
def test_published_eigenvalues(sharp: SharpParameters, speed_fts: int) -> None:
    capsize, weave, wobble = SHARP_TABLE[speed_fts]
    table = model.modes(sharp, [speed_fts * FT])
    assert table.capsize[0].real == pytest.approx(capsize, abs=0.06)
    for got, want in ((table.weave[0], weave), (table.wobble[0], wobble)):
        assert got.real == pytest.approx(want.real, abs=0.06)
        assert got.imag == pytest.approx(want.imag, abs=0.06)


def test_qualitative_picture(sharp: SharpParameters) -> None:
    speeds = np.arange(5.0, 60.01, 0.25)
    table = model.modes(sharp, speeds)
    # capsize turns unstable near 11 m/s ([notes] 8.2: 10.82 m/s)
    first_unstable = speeds[np.argmax(table.capsize.real > 0)]
    assert 10.5 <= first_unstable <= 11.25
    assert np.all(table.capsize[speeds > 11.25].real > 0)
    # weave: unstable below 5.93 m/s, frequency rising with speed, 0.3 to 3.5 Hz
    weave_f = model.ModeTable.frequency_hz(table.weave)
    assert np.all(np.diff(weave_f) > 0)
    assert table.weave[0].real > 0 and np.all(table.weave[speeds >= 6.0].real < 0)
    # wobble: 8.6 to 9.7 Hz, unstable only above 55.4 m/s
    wobble_f = model.ModeTable.frequency_hz(table.wobble)
    assert np.all((wobble_f > 8.0) & (wobble_f < 10.0))
    unstable = speeds[table.wobble.real > 0]
    assert unstable.size and 55.0 <= unstable.min() <= 55.75


def test_no_steering_damper_destabilises_wobble(sharp: SharpParameters) -> None:
    from dataclasses import replace

    # [notes] 8.2: with K = 0 the wobble is +3.95 +/- 54.2j at 30 m/s
    table = model.modes(replace(sharp, K=0.0), [30.0])
    assert table.wobble[0].real == pytest.approx(3.95, abs=0.05)
    assert table.wobble[0].imag == pytest.approx(54.2, abs=0.1)


def test_modes_followed_continuously(sharp: SharpParameters) -> None:
    """A coarse list of speeds names the modes as a fine sweep through them does."""
    coarse = [2.0, 3.0, 5.0, 7.0, 10.0, 40.0, 60.0]
    fine = model.modes(sharp, np.arange(2.0, 60.01, 0.5))
    got = model.modes(sharp, coarse)
    for name in model.MODE_NAMES:
        want = fine.mode(name)[np.searchsorted(fine.speeds, coarse)]
        np.testing.assert_allclose(got.mode(name), want, atol=1e-9)
