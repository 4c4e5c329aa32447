"""Platform files: the packaged default and one-line errors on bad files."""

import math
import tomllib
from importlib import resources
from pathlib import Path

import pytest

from motosim.cueing.platform import list_platforms, load_platform, parse_platform
from motosim.errors import MotosimError


def _default() -> dict:
    text = (resources.files("motosim.cueing") / "data" / "simacom_platform.toml").read_text()
    return tomllib.loads(text)


def test_default_platform_has_the_simacom_ranges() -> None:
    # Arioui et al., IEEE/ASME Trans. Mechatronics 15(5), 2010: roll +/-20, pitch +/-10,
    # yaw +/-15 deg, rates up to 30 deg/s.
    cfg = load_platform("simacom_platform")
    p = cfg.platform
    assert [round(math.degrees(a.angle), 9) for a in p.axes] == [20.0, 10.0, 15.0]
    assert all(round(math.degrees(a.rate), 9) == 30.0 for a in p.axes)
    assert "simacom_platform" in list_platforms()
    assert cfg.washout.tilt_rate < math.radians(3.6)  # below the pitch threshold


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["axes"]["roll"].update(angle_deg=-5.0), r"\[axes.roll\] angle = .*expected"),
        (lambda d: d["axes"]["roll"].update(speed=1.0), "unknown key 'speed' in \\[axes.roll\\]"),
        (
            lambda d: d["axes"]["pitch"].pop("rate_deg_s"),
            "missing key 'rate_deg_s' in \\[axes.pitch\\]",
        ),
        (lambda d: d["washout"].update(tilt_frequency=float("nan")), "tilt_frequency = nan"),
        (lambda d: d["mpc"].update(horizon=2.5), "horizon = 2.5; expected an integer"),
        (lambda d: d.update(extra={}), r"unknown table \[extra\]"),
        (lambda d: d.pop("head"), r"missing table \[head\]"),
    ],
)
def test_bad_values_are_one_line_errors(edit, message: str) -> None:
    data = _default()
    edit(data)
    with pytest.raises(MotosimError, match=message) as info:
        parse_platform(data, origin="my.toml")
    assert "\n" not in str(info.value) and str(info.value).startswith("my.toml: ")


def test_missing_file_and_bad_toml(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match="no such platform file"):
        load_platform(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[platform\n")
    with pytest.raises(MotosimError, match="not valid TOML"):
        load_platform(bad)
