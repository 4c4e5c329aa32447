"""excite, estimate and identify: absurd options and existing outputs refused in one line."""

from pathlib import Path

import pytest

from motosim.cli.main import main


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--duration", "1e300"], "--duration = 1e+300; expected a finite number > 0"),
        (["--duration", "3000", "--rate", "100000"], "samples; expected at most"),
        (["--seed", "-1"], "--seed -1; expected an integer 0 to 2^63 - 1"),
        (["--seed", "1" + "0" * 60], "--seed an integer of 61 digits"),
        (["--amplitude", "1e300"], "--amplitude = 1e+300"),
        (["--rate", "0"], "--rate = 0.0"),
        (["--f1", "1e9"], "--f1 = 1000000000.0"),
        (["--current-noise", "nan"], "--current-noise = nan"),
    ],
)
def test_excite_refuses_absurd_options(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, args: list[str], message: str
) -> None:
    assert main(["excite", *args, "--out", str(tmp_path / "run.csv")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and err.startswith("motosim: error:")
    assert not (tmp_path / "run.csv").exists()


def test_outputs_are_not_replaced_silently(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    log = tmp_path / "run.csv"
    assert main(["excite", "--duration", "2", "--out", str(log)]) == 0
    before = log.read_bytes()
    assert main(["excite", "--duration", "3", "--out", str(log)]) == 2
    assert "exists; give --overwrite" in capsys.readouterr().err
    assert log.read_bytes() == before
    estimate = tmp_path / "est.csv"
    estimate.write_text("keep")
    assert main(["estimate", str(log), "--out", str(estimate)]) == 2
    assert estimate.read_text() == "keep"
    params = tmp_path / "hb.toml"
    params.write_text("keep")
    assert main(["identify", str(log), "--out", str(params)]) == 2
    assert params.read_text() == "keep"
    assert main(["excite", "--duration", "3", "--out", str(log), "--overwrite"]) == 0
    assert log.read_bytes() != before
