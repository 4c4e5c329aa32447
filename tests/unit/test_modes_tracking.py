"""``motosim.model.sharp.track_modes``: naming and following the modes of any lateral spectrum.

The classifier promises: the modes are named at the reference speed (wobble the oscillatory
pair of highest frequency, weave the next, capsize the real eigenvalue nearest zero) and
followed continuously, so a weave whose frequency passes the wobble's keeps its name; what it
reports are the exact eigenvalues at the requested speeds, whatever their order or number in
the spectrum; a malformed spectrum is refused in one line. The spectra here are analytic, so
the right answer is known exactly.
"""

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.params import SharpParameters


def _crossing(v: np.ndarray) -> np.ndarray:
    """A capsize, a weave whose frequency (1.5 v rad/s) passes a fixed 40 rad/s wobble at
    26.67 m/s, and a fast real tyre lag; shuffled out of order."""
    v = np.asarray(v, dtype=float)[:, None]
    wobble = -3.0 + 40j + 0.0 * v
    weave = -1.0 + 1.5j * v
    rows = np.hstack([weave.conj(), -50.0 - v + 0j, wobble, 0.01 * v + 0j, weave, wobble.conj()])
    return rows


def test_a_weave_that_passes_the_wobble_keeps_its_name() -> None:
    speeds = np.array([5.0, 20.0, 26.0, 27.5, 40.0])
    table = sharp_model.track_modes(speeds, _crossing)
    np.testing.assert_array_equal(table.weave, -1.0 + 1.5j * speeds)
    np.testing.assert_array_equal(table.wobble, np.full(speeds.size, -3.0 + 40j))
    np.testing.assert_array_equal(table.capsize, 0.01 * speeds + 0j)
    # every row sorted by real part, the six eigenvalues kept
    assert table.eigenvalues.shape == (5, 6)
    assert np.all(np.diff(table.eigenvalues.real, axis=1) >= 0)


def test_the_reference_speed_names_the_modes_where_they_are_distinct() -> None:
    # named at 40 m/s the faster pair is the 60 rad/s one: the names follow that choice
    table = sharp_model.track_modes([10.0, 40.0], _crossing, reference_speed=40.0)
    np.testing.assert_array_equal(table.wobble, [-1.0 + 15j, -1.0 + 60j])
    np.testing.assert_array_equal(table.weave, [-3.0 + 40j, -3.0 + 40j])


def test_modes_is_track_modes_of_sharps_eigenvalues(sharp: SharpParameters) -> None:
    speeds = [3.0, 12.0, 33.0]
    ours = sharp_model.modes(sharp, speeds)
    direct = sharp_model.track_modes(speeds, lambda at: sharp_model.eigenvalues(sharp, at))
    for name in sharp_model.MODE_NAMES:
        np.testing.assert_array_equal(ours.mode(name), direct.mode(name))
    np.testing.assert_array_equal(ours.eigenvalues, sharp_model.eigenvalues(sharp, speeds))


@pytest.mark.parametrize(
    ("spectrum", "match"),
    [
        (lambda v: np.zeros((len(v), 2), complex), r"shape \(\d+, 2\).*expected \(\d+, n\)"),
        (lambda v: np.zeros(len(v), complex), r"shape \(\d+,\) at \d+ speeds"),
        (lambda v: np.full((len(v), 5), np.nan), "not finite"),
        (lambda v: -np.ones((len(v), 5)) + 0j, "expected two oscillatory modes and a real one"),
    ],
)
def test_a_malformed_spectrum_is_refused_in_one_line(spectrum: object, match: str) -> None:
    with pytest.raises(MotosimError, match=match) as info:
        sharp_model.track_modes([10.0], spectrum)  # type: ignore[arg-type]
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("speed", [0.5, 151.0, float("nan")])
def test_a_speed_out_of_range_is_refused(speed: float) -> None:
    with pytest.raises(MotosimError, match="speed"):
        sharp_model.track_modes([speed], _crossing)
