"""CSV logs: round trip and the one-line errors for bad files."""

from pathlib import Path

import numpy as np
import pytest

from motosim.errors import MotosimError, MotosimWarning
from motosim.io import log_timing, parse_columns, read_log, read_rig_log, resample, write_log
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


# --- logs from a real rig (issue 11, deliverable 0) ---

N_RIG = 200


def _rig_rows(sep: str = ",", decimal: str = ".", scale=(1.0, 1.0, 1.0), jitter=None) -> str:
    rows = []
    for k in range(N_RIG):
        t = k * 0.01 + (jitter[k] if jitter is not None else 0.0)
        values = (t * scale[0], 0.2 * np.sin(3 * t) * scale[1], np.cos(3 * t) * scale[2])
        rows.append(sep.join(repr(float(v)).replace(".", decimal) for v in values))
    return "\n".join(rows) + "\n"


def _rig(tmp_path: Path, text: str, columns=None, encoding="utf-8"):
    path = tmp_path / "rig.csv"
    path.write_bytes(text.encode(encoding))
    return read_rig_log(path, required=("theta_h", "i_m"), columns=columns)


def _check_rig(log) -> None:
    t = np.arange(N_RIG) * 0.01
    np.testing.assert_allclose(log.series.t, t, atol=1e-12)
    np.testing.assert_allclose(log.series["theta_h"], 0.2 * np.sin(3 * t), atol=1e-12)
    np.testing.assert_allclose(log.series["i_m"], np.cos(3 * t), atol=1e-12)


@pytest.mark.parametrize(
    ("header", "sep", "decimal", "prefix"),
    [
        ("t;theta_h;i_m", ";", ",", ""),  # German Excel: semicolon and decimal comma
        ("t\ttheta_h\ti_m", "\t", ".", ""),  # tab separated
        ("t,theta_h,i_m", ",", ".", "\ufeff"),  # Excel "CSV UTF-8" byte-order mark
        ("t [s],theta_h [rad],i_m (A)", ",", ".", "# logged by the rig\n# 100 Hz\n\n"),
        ('"t [s]";"theta_h [rad]";"i_m [A]"', ";", ",", ""),  # quoted header
    ],
)
def test_rig_formats(tmp_path: Path, header: str, sep: str, decimal: str, prefix: str) -> None:
    _check_rig(_rig(tmp_path, prefix + header + "\n" + _rig_rows(sep, decimal)))


def test_units_in_the_header_are_converted(tmp_path: Path) -> None:
    text = "t [ms],theta_h (deg),i_m [mA]\n" + _rig_rows(scale=(1e3, 180.0 / np.pi, 1e3))
    _check_rig(_rig(tmp_path, text))


def test_column_mapping_with_units(tmp_path: Path) -> None:
    text = "time,angle_deg,cur,extra\n" + "".join(
        line + ",7\n" for line in _rig_rows(scale=(1.0, 180.0 / np.pi, 1.0)).splitlines()
    )
    mapping = parse_columns("t=time,theta_h=angle_deg:deg,i_m=cur:A")
    log = _rig(tmp_path, text, columns=mapping)
    _check_rig(log)
    assert log.series.names == ("theta_h", "i_m", "extra")


@pytest.mark.parametrize(
    ("text", "columns", "message"),
    [
        # every refusal names the likely cause and the way to say what the column is
        ("t,theta_h,i_m\n" + _rig_rows(scale=(1e3, 1.0, 1.0)), None, "milliseconds"),
        ("t,theta_h,i_m\n" + _rig_rows(scale=(1.0, 180 / np.pi * 10, 1.0)), None, "degrees"),
        ("t,theta_h,i_m\n" + _rig_rows(scale=(1.0, 1.0, 1e3)), None, "milliamperes"),
        ("t,theta_h,i_m\n" + _rig_rows(), "t=time", "'time', which is not a column"),
        ("t,theta_h,i_m\n" + _rig_rows(), "theta_h=theta_h:kg", "unit 'kg'"),
        ("t [s],theta_h [A],i_m\n" + _rig_rows(), None, "theta_h given in A"),
        ("t,theta_h,current\n" + _rig_rows(), None, "--columns i_m=NAME"),
    ],
)
def test_rig_refusals(tmp_path: Path, text: str, columns, message: str) -> None:
    with pytest.raises(MotosimError) as info:
        _rig(tmp_path, text, columns=parse_columns(columns) if columns else None)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_latin1_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(MotosimError) as info:
        _rig(tmp_path, "t,theta_h (°),i_m\n" + _rig_rows(), encoding="latin-1")
    assert "not UTF-8" in str(info.value) and "line 1" in str(info.value)


def test_jitter_is_reported_and_resampled(tmp_path: Path) -> None:
    # a CAN log: +/-2 ms of jitter on a 10 ms period, float32 time stamps
    rng = np.random.default_rng(0)
    jitter = rng.uniform(-0.002, 0.002, N_RIG)
    jitter[0] = jitter[-1] = 0.0
    text = "t,theta_h,i_m\n" + _rig_rows(jitter=jitter)
    with pytest.warns(MotosimWarning, match=r"periods deviate by up to \d+ % .* 10 ms period"):
        log = _rig(tmp_path, text)
    assert log.timing.resampled and 0.1 < log.timing.jitter < 0.5
    assert log.series.t.size == N_RIG
    np.testing.assert_allclose(np.diff(log.series.t), 0.01, rtol=1e-9)
    # linear interpolation of 0.2 sin(3 t) at 10 ms: error below 0.2 * 9 * 0.01^2 / 8
    t = log.series.t
    np.testing.assert_allclose(log.series["theta_h"], 0.2 * np.sin(3 * t), atol=3e-5)


def test_dropped_frames_are_filled_and_long_gaps_refused(tmp_path: Path) -> None:
    lines = _rig_rows().splitlines()
    one_dropped = "t,theta_h,i_m\n" + "\n".join(lines[:50] + lines[51:]) + "\n"
    log = _rig(tmp_path, one_dropped)
    assert log.timing.gaps == 1 and log.timing.resampled
    assert log.series.t.size == N_RIG
    assert "1 gap(s) up to 0.02 s" in log.timing.describe()
    long_gap = "t,theta_h,i_m\n" + "\n".join(lines[:50] + lines[60:]) + "\n"
    with pytest.raises(MotosimError, match=r"0.11 s without samples after t = 0.49 s"):
        _rig(tmp_path, long_gap)


def test_parse_columns_errors() -> None:
    for text, message in (("theta_h", "SIGNAL=COLUMN"), ("t=a,t=b", "twice"), (",", "expected")):
        with pytest.raises(MotosimError, match=message):
            parse_columns(text)


def test_log_timing_and_resample() -> None:
    timing = log_timing(np.array([0.0, 0.01, 0.02, 0.04, 0.05]))
    assert timing.period == pytest.approx(0.01) and timing.gaps == 1
    series = TimeSeries(np.array([0.0, 0.5, 2.0]), np.array([[0.0], [1.0], [4.0]]), ("x",))
    out = resample(series, 1.0)
    np.testing.assert_allclose(out.t, [0.0, 1.0, 2.0])
    np.testing.assert_allclose(out["x"], [0.0, 2.0, 4.0])
