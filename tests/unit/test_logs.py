"""CSV logs: round trip and the one-line errors for bad files."""

from pathlib import Path

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io import read_log, write_log
from motosim.timeseries import TimeSeries


def test_round_trip(tmp_path: Path) -> None:
    t = np.arange(20) * 0.01
    data = np.column_stack([np.sin(t), np.cos(t) / 3])
    path = write_log(tmp_path / "sub" / "run.csv", TimeSeries(t, data, ("theta_h", "i_m")))
    back = read_log(path, required=("theta_h", "i_m"))
    np.testing.assert_array_equal(back.t, t)
    np.testing.assert_array_equal(back.data, data)
    assert path.read_text().splitlines()[0] == "t,theta_h,i_m"


def _csv(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "log.csv"
    path.write_text(text)
    return path


GOOD_ROWS = "".join(f"{k * 0.01},{k * 0.1},0.5\n" for k in range(12))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("t,theta_h\n" + GOOD_ROWS, "missing column 'i_m'"),
        ("t,theta_h,i_m\n0,1,2\n", "1 samples; expected at least 10"),
        ("t,theta_h,i_m\n" + GOOD_ROWS + "0.2,nan,0\n", "nan; expected a finite number"),
        ("t,theta_h,i_m\n" + GOOD_ROWS + "0.2,x,0\n", "'x' is not a number"),
        ("t,theta_h,i_m\n" + GOOD_ROWS + "0.11,1,0\n", "time repeats at line 14"),
        ("t,theta_h,i_m\n" + GOOD_ROWS + "0.05,1,0\n", "time goes back at line 14"),
        ("t,theta_h,i_m\n" + GOOD_ROWS + "0.2,1\n", "line 14 has 2 fields; expected 3"),
        ("t,t,i_m,theta_h\n" + GOOD_ROWS, "duplicated column names"),
    ],
)
def test_bad_logs(tmp_path: Path, text: str, message: str) -> None:
    with pytest.raises(MotosimError) as info:
        read_log(_csv(tmp_path, text), required=("theta_h", "i_m"))
    assert message in str(info.value) and "\n" not in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match="no such log file"):
        read_log(tmp_path / "none.csv", required=())
