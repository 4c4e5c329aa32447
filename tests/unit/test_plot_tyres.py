"""Smoke test of the tyre figure on both kinds of tyre."""

from motosim.model.tyres import linear_tyre_coefficients, tyre_coefficients
from motosim.params import load_parameters
from motosim.plotting import plot_tyre


def test_plot_tyre_draws_three_panels() -> None:
    front = tyre_coefficients(load_parameters("sel2004_front_120_70_zr17", "tyre"))
    fig = plot_tyre(front, loads=(1100.0,), cambers_deg=(0.0, 30.0), title="front")
    assert len(fig.axes) == 3
    linear = linear_tyre_coefficients(
        nominal_load=1000.0,
        cornering_stiffness=11000.0,
        camber_stiffness=900.0,
        slip_stiffness=20000.0,
        relaxation_length=0.24,
        radius=0.3,
    )
    assert len(plot_tyre(linear).axes) == 3
