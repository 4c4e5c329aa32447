"""Reference numbers for the estimation designs.

Sources: an independent scipy computation of the Lyapunov route of Walcott & Zak (1987), as
eqs. (13)-(14) of Nehaoua, Arioui & Mammar (2012) state it (poles (-40, -60), Q = I:
L = [[0, -276.289], [40, 1]], P = diag(0.008333, 0.0125), F = [0, 0.2008]), for Table I
(J_eq = 0.0415 kg*m^2, beta_eq = 13.956 N*m*s/rad); and, for the differentiator, Levant's
implicit Euler discretisation (Acary & Brogliato, Systems & Control Letters 59, 2010), run
independently
(signal 0.3 sin 2 pi t + 0.1 sin 6 pi t, implicit STD RMS 0.132 rad/s at 100 Hz and
0.013 rad/s at 1 kHz after 1 s, equal to the backward difference).
"""

import numpy as np
import pytest

from motosim.estimation.differentiator import differentiate
from motosim.estimation.walcott_zak import design
from motosim.params import load_parameters


def test_lyapunov_route_matches_reference_notes():
    hb = load_parameters("simacom_handlebar", "handlebar")
    # our poles are ordered (rate error, angle error); the notes' design has the rate error
    # at -60 and the angle error at -40
    g = design(hb, poles=(-60.0, -40.0))
    np.testing.assert_allclose(g.L, [[0.0, -276.289], [40.0, 1.0]], atol=5e-4)  # notes 4.2
    np.testing.assert_allclose(g.P, np.diag([0.008333, 0.0125]), atol=5e-7)  # notes 4.2
    np.testing.assert_allclose(g.F, [0.0, 0.2008], atol=5e-5)  # notes 4.2


@pytest.mark.parametrize(("rate", "rms"), [(100.0, 0.132), (1000.0, 0.013)])
def test_differentiator_rms_matches_reference_notes(rate, rms):
    h = 1.0 / rate
    t = np.arange(0.0, 3.0, h)
    f = 0.3 * np.sin(2 * np.pi * t) + 0.1 * np.sin(6 * np.pi * t)
    df = 0.6 * np.pi * np.cos(2 * np.pi * t) + 0.6 * np.pi * np.cos(6 * np.pi * t)
    z = differentiate(f, h, 60.0)
    late = t >= 1.0
    assert np.sqrt(np.mean((z - df)[late] ** 2)) == pytest.approx(rms, abs=5e-4)  # notes 3.3
