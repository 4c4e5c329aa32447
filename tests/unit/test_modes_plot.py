"""``plot_mode_comparison``: every model's three modes, one line style per model."""

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.params import SharpParameters
from motosim.plotting import plot_mode_comparison


def test_each_model_draws_its_modes_in_its_own_style(sharp: SharpParameters) -> None:
    speeds = np.arange(3.0, 40.0, 1.0)
    table = sharp_model.modes(sharp, speeds)
    fig = plot_mode_comparison({"linear": table, "again": table})
    ax_re, ax_f = fig.axes
    assert [line.get_label() for line in ax_f.get_lines()] == [
        "weave, linear",
        "wobble, linear",
        "weave, again",
        "wobble, again",
    ]
    # the real parts: three modes per model, the zero line last
    re_lines = ax_re.get_lines()
    assert len(re_lines) == 7
    assert {line.get_linestyle() for line in re_lines[:3]} == {"-"}
    assert {line.get_linestyle() for line in re_lines[3:6]} == {"--"}
    np.testing.assert_allclose(re_lines[1].get_ydata(), table.weave.real)
    np.testing.assert_allclose(
        ax_f.get_lines()[1].get_ydata(), np.abs(table.wobble.imag) / (2 * np.pi)
    )


@pytest.mark.parametrize("count", [0, 5])
def test_no_table_or_too_many_is_refused(sharp: SharpParameters, count: int) -> None:
    table = sharp_model.modes(sharp, [10.0])
    with pytest.raises(MotosimError, match=f"{count} tables; expected 1 to 4"):
        plot_mode_comparison({str(k): table for k in range(count)})
