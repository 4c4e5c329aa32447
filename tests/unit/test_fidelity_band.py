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


def test_plot_feel_marks_a_multisine_lines_and_not_a_welch_grid() -> None:
    """A multisine's ~20 lines are marked (the lines between them are not measured); a
    Welch estimate's hundreds of bins are drawn as curves."""
    from motosim.plotting.closed_loop import plot_feel
    from motosim.sim.fidelity import FeelResponse

    for m, marked in ((20, True), (300, False)):
        f = np.geomspace(0.1, 3.0, m)
        h = 1.0 / (1.0 + 2j * np.pi * f)
        feel = FeelResponse(f, h, h, h, np.ones(m))
        lines = plot_feel(feel, speed=20.0).axes[0].get_lines()
        assert [line.get_marker() not in ("None", None, "") for line in lines] == [
            False,
            marked,
            marked,
        ]
