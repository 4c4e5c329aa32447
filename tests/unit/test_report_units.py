"""The summary numbers shown to a person: SI converted at the edge, the unit written."""

import math

import pytest

from motosim.report.units import METRICS, shown, summary_lines
from motosim.sim.metrics import run_metrics


def test_angles_read_in_degrees_counts_as_integers_flags_as_words() -> None:
    assert shown("rms_tracking_error", math.radians(0.0376)) == ("0.0376", "deg")
    assert shown("rms_rate_error", math.radians(2.0)) == ("2", "deg/s")
    assert shown("samples", 1e4) == ("10000", "")
    assert shown("complete", 1.0) == ("yes", "")
    assert shown("tracking_rms_fraction", 0.0399) == ("3.99", "%")
    assert shown("rms_tau_r_error", 1.179) == ("1.179", "N*m")
    assert shown("min_speed", 20.0) == ("20", "m/s")
    assert shown("status", "ok") == ("ok", "")


def test_every_number_a_run_summarises_has_its_unit() -> None:
    import numpy as np

    t = np.linspace(0.0, 4.0, 401)
    columns = {
        name: np.sin(t + k)
        for k, name in enumerate(
            (
                "tau_r",
                "tau_r_hat",
                "theta_h",
                "delta",
                "theta_h_dot",
                "theta_h_dot_hat",
                "phi",
                "e_y",
                "v_x",
                "i_m",
            )
        )
    }
    columns["v_x"] = np.full_like(t, 20.0)
    summary = run_metrics(t, columns.get, complete=True, max_current=30.0)
    assert set(summary) <= set(METRICS), set(summary) - set(METRICS)


@pytest.mark.parametrize(
    ("key", "si", "line"),
    [
        ("rms_tracking_error", 0.0006569, "rms_tracking_error 0.03764 deg"),
        ("max_abs_phi", 0.2322, "max_abs_phi 13.3 deg"),
        ("samples", 1e4, "samples 10000"),
    ],
)
def test_simulate_prints_the_unit(key: str, si: float, line: str) -> None:
    (printed,) = summary_lines({key: si})
    assert " ".join(printed.split()) == line


def test_a_campaign_rows_other_columns_are_shown_as_they_are() -> None:
    # motosim campaign --rerun prints its row: factors, None, strings, the campaign's metrics
    row = {
        "J_eq": 0.0415,
        "failed_at": None,
        "design": "d0",
        "max_abs_i_m": 3.25,
        "max_abs_tracking_error": math.radians(1.5),
        "index": 3,
    }
    assert [" ".join(line.split()) for line in summary_lines(row)] == [
        "J_eq 0.0415",
        "failed_at None",
        "design d0",
        "max_abs_i_m 3.25 A",
        "max_abs_tracking_error 1.5 deg",
        "index 3",
    ]
