"""``motosim design`` end to end and the design file round trip."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.io.design_file import read_design


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_design_json_and_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    out_file = tmp_path / "design.toml"
    code, out, _ = _run(capsys, "design", "--json", "--starts", "4", "--out", str(out_file))
    assert code == 0
    report = json.loads(out)
    c = report["controller"]
    assert c["gamma"] <= 1.02 * report["gamma_min"]
    assert c["analysis"]["discrete_stable"] == {"zoh": True, "tustin": True}
    assert report["paper_controller"]["gamma"] == pytest.approx(2.5585, abs=2e-4)
    design = read_design(out_file)
    assert design.rate == 1000.0
    assert design.handlebar.J_eq == 0.0415
    # the file's continuous controller is the reported num/den
    s = 5.0j
    k = design.controller
    k_ss = (k.C @ np.linalg.solve(s * np.eye(k.n_states) - k.A, k.B) + k.D)[0, 0]
    k_tf = np.polyval(c["num"], s) / np.polyval(c["den"], s)
    assert k_ss == pytest.approx(k_tf, rel=1e-9)
    assert set(design.controller_discrete) == {"zoh", "tustin"}
    # the whole sampled stack at 10, 20 and 30 m/s: stable, margins, the +/-50 %/+/-30 % grid
    stack = report["stack"]
    assert [a["speed"] for a in stack] == [10.0, 20.0, 30.0]
    for a in stack:
        assert a["stable"]
        assert a["gain_margin_db"] >= 6.0 and a["phase_margin_deg"] >= 45.0
        assert a["grid"]["points"] == 27
        # the predicted cancellation, the default at 1 kHz: T_d the estimate filter's delay
        # at 1 Hz (11.7 ms, scripts/grid_failures.py)
        assert 0.011 < a["prediction_lead_s"] < 0.0125


def test_design_at_the_can_rate(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(
        capsys, "design", "--json", "--starts", "2", "--rate", "100", "--speeds", "15"
    )
    assert code == 0
    report = json.loads(out)
    assert report["controller"]["analysis"]["discrete_stable"]["zoh"]
    (stack,) = report["stack"]
    assert stack["speed"] == 15.0 and stack["stable"]
    # the predicted cancellation, the default at the paper's 100 Hz too: T_d the estimate
    # filter's delay at 1 Hz (28.2 ms at 20 m/s, scripts/grid_failures.py --rates 100)
    assert 0.026 < stack["prediction_lead_s"] < 0.030


def test_design_with_a_latency_shows_the_margins_kept(capsys: pytest.CaptureFixture[str]) -> None:
    # 100 Hz status frames read 5.5 ms old (5 ms on the bus, half a 1 kHz loop's period):
    # the stack designed for a fresh sample loses its margins (unstable, in the sampled loop
    # analysis; PM 24 deg, 7 deg with the plain cancellation); accounting for the age keeps
    # 7.6 dB and 49 deg at 20 m/s with the plain cancellation, 6.9 dB and 48 deg with the
    # predicted one, the default at 100 Hz
    code, out, _ = _run(
        capsys,
        "design",
        "--json",
        "--starts",
        "1",
        "--rate",
        "100",
        "--speeds",
        "20",
        "--latency",
        "0.0055",
    )
    assert code == 0
    (stack,) = json.loads(out)["stack"]
    assert stack["measurement_delay_s"] == 0.0055
    assert stack["stable"] and stack["gain_margin_db"] >= 6.0
    # the prediction's lead is the fresh-sample stack's (28.2 ms), the one motosim run
    # builds before accounting for the age, not the delayed stack's (33.7 ms)
    assert 0.027 < stack["prediction_lead_s"] < 0.0295
    assert stack["phase_margin_deg"] >= 45.0
    fresh = stack["unaccounted"]
    assert fresh["measurement_delay_s"] == 0.0055
    assert not fresh["stable"] or fresh["phase_margin_deg"] < 45.0


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["design", "--bandwidth", "500"], "at most a fifth of the 1000 Hz control rate"),
        (["design", "--order", "-1"], "--order -1; expected an integer from 0 to 3"),
        (["design", "--integral-corner", "0"], "integral_corner = 0.0; expected a fraction"),
        (["design", "--speeds", "100"], "--speeds"),
        (["design", "--handlebar", "sharp1971"], "expected a handlebar parameter set"),
        (["design", "--latency", "0.002"], "--latency"),  # beyond one 1 kHz period
    ],
)
def test_bad_options(capsys: pytest.CaptureFixture[str], argv: list[str], message: str) -> None:
    code, _, err = _run(capsys, *argv)
    assert code == 2 and message in err and err.count("\n") == 1


def test_bad_design_file(tmp_path: Path) -> None:
    from motosim.errors import MotosimError

    bad = tmp_path / "d.toml"
    bad.write_text("[design]\nrate = 1000.0\n[extra]\n")
    with pytest.raises(MotosimError, match="unknown table"):
        read_design(bad)
    bad.write_text("[design]\nrate = -1.0\n")
    with pytest.raises(MotosimError, match=r"rate = -1\.0"):
        read_design(bad)


def test_design_explains_the_paper_controller_beside_ours(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = _run(capsys, "design", "--starts", "1", "--speeds", "20")
    assert code == 0
    text = " ".join(out.split())
    # each column and row said, and why eq. (26) reads as it does: its crossover on this
    # handlebar, 0.09 rad/s (docs/paper.md), is where its tracking bandwidth ends
    assert "ours, just designed, beside the paper's published eq. (26)" in text
    assert "tracking bandwidth: where theta_h / delta falls 3 dB" in text
    assert "inf: integral action holds the angle against a steady torque" in text
    crossover = float(text.split("its loop crosses over at ")[1].split()[0])
    assert crossover == pytest.approx(0.09 / (2 * 3.141592653589793), rel=0.05)
    assert "evaluated as published, not broken" in text


def test_design_for_a_grip_analyses_the_stack_held_and_let_go(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """``--grip relaxed``: the stack designed for the rider's hands keeps at 20 m/s, 1 kHz,
    the classical margins (6 dB, 45 deg) held by the relaxed grip and let go; the report
    says which grip, and prints both."""
    code, out, _ = _run(
        capsys, "design", "--json", "--starts", "2", "--speeds", "20", "--grip", "relaxed"
    )
    assert code == 0
    report = json.loads(out)
    assert report["grip"] == "relaxed"
    (stack,) = report["stack"]
    for a in (stack, stack["hands_off"]):
        assert a["stable"]
        assert a["gain_margin_db"] >= 6.0 and a["phase_margin_deg"] >= 45.0
    code, out, _ = _run(capsys, "design", "--starts", "2", "--speeds", "20", "--grip", "firm")
    assert code == 0
    assert "designed for and held by the firm grip" in out and "hands off: stable True" in out


def test_a_design_file_for_a_grip_is_refused_at_once(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """A design file holds the design for the handlebar alone: ``--out`` with a grip is
    refused in one line (exit 2) before any design."""
    code, _, err = _run(capsys, "design", "--grip", "relaxed", "--out", str(tmp_path / "d.toml"))
    assert code == 2
    assert "--out with --grip relaxed" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "d.toml").exists()
