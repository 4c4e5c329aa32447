"""The one TOML reader and the one number check refuse bad input in one line naming it."""

import math
from pathlib import Path

import pytest

from motosim.errors import MotosimError
from motosim.params.checks import check_number
from motosim.params.toml import MAX_DEPTH, read_toml


def _refused(path: Path, *, max_bytes: int = 1_000_000) -> str:
    with pytest.raises(MotosimError) as info:
        read_toml(path, what="test file", max_bytes=max_bytes)
    text = str(info.value)
    assert "\n" not in text and str(path) in text
    return text


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\x89PNG\r\n\x1a\n\x00\x00", "is not UTF-8 text (byte 0x89 at offset 0)"),
        ("a = 'caf\u00e9'\n".encode("latin-1"), "is not UTF-8 text (byte 0xe9 at offset 8)"),
        ("a = 1\n".encode("utf-16"), "is UTF-16 text; expected UTF-8"),
        (b"a = [1,\n", "not valid TOML"),
        (b"a = " + b"[" * 3000 + b"]" * 3000, "nested more than"),
        (b"a = 1" + b"0" * 399, "a = an integer of 400 digits; expected an integer"),
        (b"a = 1" + b"0" * 5000, "not valid TOML: Exceeds the limit"),
        (b"[x]\ny = [1.0, 1e300]\n", "x.y[1] = 1e+300; expected a number of magnitude"),
        (b"[x]\ny = nan\n", "x.y = nan; expected a finite number"),
        (b"[x]\ny = -inf\n", "x.y = -inf; expected a finite number"),
    ],
)
def test_refused_content(tmp_path: Path, content: bytes, message: str) -> None:
    path = tmp_path / "f.toml"
    path.write_bytes(content)
    assert message in _refused(path)


def test_deep_tables_refused(tmp_path: Path) -> None:
    path = tmp_path / "f.toml"
    path.write_text("[" + ".".join(["k"] * (MAX_DEPTH + 3)) + "]\nv = 1\n", encoding="utf-8")
    assert f"nested more than {MAX_DEPTH} levels deep" in _refused(path)


def test_size_checked_before_reading(tmp_path: Path) -> None:
    path = tmp_path / "f.toml"
    path.write_bytes(b"# " + b"x" * 200 + b"\n")
    assert "is 203 bytes; expected at most 100 bytes" in _refused(path, max_bytes=100)


def test_missing_and_directory(tmp_path: Path) -> None:
    assert "no such test file" in _refused(tmp_path / "none.toml")
    assert "is a directory" in _refused(tmp_path)


def test_utf8_with_bom_accepted(tmp_path: Path) -> None:
    path = tmp_path / "f.toml"
    path.write_bytes("\ufeffa = 'é'\n".encode())
    assert read_toml(path, what="test file") == {"a": "é"}


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (True, "x = True is a boolean"),
        ("1.0", "x = '1.0' is a string"),
        ([1.0], "x = [1.0] is a list"),
        ({"v": 1}, "x = {'v': 1} is a table"),
        (10**400, "x = an integer of 401 digits; expected a finite number >= 0 and <= 1 [m]"),
        (math.nan, "x = nan; expected"),
        (-1e-300, "x = -1e-300; expected a finite number >= 0 and <= 1 [m]"),
    ],
)
def test_check_number_refuses(value: object, message: str) -> None:
    with pytest.raises(MotosimError) as info:
        check_number(value, where="x", lower=0.0, upper=1.0, unit="m")
    assert message in str(info.value)


def test_check_number_open_bounds() -> None:
    assert check_number(1, where="x", lower=0.0, lower_closed=False) == 1.0
    with pytest.raises(MotosimError, match=r"x = 0.0; expected a finite number > 0 and < 2"):
        check_number(0.0, where="x", lower=0.0, upper=2.0, lower_closed=False, upper_closed=False)
