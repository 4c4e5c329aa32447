"""Helpers of the command line: strict JSON, outputs refused unless --overwrite, progress."""

import json
import math
import os
import sys
from pathlib import Path

import pytest

from motosim.cli._common import (
    check_output,
    check_output_folder,
    print_json,
    show_progress,
    write_text,
)
from motosim.errors import MotosimError


def test_non_finite_numbers_print_as_null(capsys: pytest.CaptureFixture[str]) -> None:
    print_json({"gain_margin_db": math.inf, "poles": [[-1.0, math.nan]], "ok": 2.5})
    assert json.loads(capsys.readouterr().out) == {
        "gain_margin_db": None,
        "poles": [[-1.0, None]],
        "ok": 2.5,
    }


def test_outputs_are_refused_unless_overwrite(tmp_path: Path) -> None:
    existing = tmp_path / "a.toml"
    existing.write_text("old")
    with pytest.raises(MotosimError, match="exists; give --overwrite to replace it"):
        check_output(existing, overwrite=False)
    assert check_output(existing, overwrite=True) == existing
    with pytest.raises(MotosimError, match="does not exist; expected an existing folder"):
        check_output(tmp_path / "no" / "a.toml", overwrite=True)
    with pytest.raises(MotosimError, match="is a folder; expected a file name"):
        check_output(tmp_path, overwrite=True)
    with pytest.raises(MotosimError, match="--out is empty"):
        check_output("", overwrite=True)
    with pytest.raises(MotosimError, match="is not empty; give --overwrite"):
        check_output_folder(tmp_path, overwrite=False)
    assert check_output_folder(tmp_path / "new", overwrite=False) == tmp_path / "new"


def test_write_text_is_whole_or_nothing(tmp_path: Path) -> None:
    target = tmp_path / "a.toml"
    target.write_text("old")
    write_text(target, "new")
    assert target.read_text() == "new" and [p.name for p in tmp_path.iterdir()] == ["a.toml"]
    (tmp_path / "sub").mkdir()
    blocked = tmp_path / "sub" / "b.toml"
    os.chmod(tmp_path / "sub", 0o500)
    try:
        if os.access(tmp_path / "sub", os.W_OK):
            pytest.skip("running as a user who writes anywhere (root)")
        with pytest.raises(MotosimError, match="cannot write"):
            write_text(blocked, "x")
    finally:
        os.chmod(tmp_path / "sub", 0o700)


def test_progress_only_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys.stderr, "isatty", lambda: False)
    assert not show_progress()
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    assert show_progress() and not show_progress(quiet=True)
