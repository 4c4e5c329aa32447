"""The feel's frequency band is inclusive at its ends whatever the rounding of Welch's bins."""

import numpy as np

from motosim.sim.fidelity import FeelResponse


def test_worst_includes_a_bin_that_rounds_below_the_band_edge():
    # Welch's bins are k * fs / nperseg: the 0.1 Hz bin of a 20000-sample segment at 1 kHz
    # comes out as 0.09999999999987778 Hz; it is the band's edge and must be counted.
    f = np.array([2 * 1e3 / 20000 * (1 - 1.2e-12), 0.15, 3.0])
    model = np.ones(3, dtype=np.complex128)
    rendered = np.array([10 ** (-8 / 20), 1.0, 1.0], dtype=np.complex128)
    feel = FeelResponse(f, rendered, model, model, np.ones(3))
    magnitude, _ = feel.worst(0.1, 3.0)
    assert abs(magnitude - 8.0) < 1e-9
