"""Helpers of the command line: strict JSON, outputs refused unless --overwrite, progress."""

import errno
import json
import math
import os
import re
import sys
import tempfile
from pathlib import Path

import pytest

from motosim.cli._common import (
    check_folder_target,
    check_input,
    check_output,
    check_output_folder,
    check_result_input,
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


def test_inputs_are_refused_for_what_they_are(tmp_path: Path) -> None:
    (tmp_path / "a").symlink_to("b")
    (tmp_path / "b").symlink_to("a")
    (tmp_path / "dangling").symlink_to("gone.toml")
    (tmp_path / "bin.csv").write_bytes(b"t,x\n0,\x00")
    (tmp_path / "latin1.csv").write_bytes("t,x\n# caf\xe9\n".encode("latin-1"))
    (tmp_path / "utf16.toml").write_bytes("x = 1".encode("utf-16"))
    (tmp_path / "ok.toml").write_text("x = 1  # caf\u00e9\n", encoding="utf-8")
    cases = {
        "a": "a: is a symbolic link loop (it leads back to itself); expected a scenario file",
        "dangling": "is a symbolic link to gone.toml, which does not exist",
        "missing.toml": "missing.toml: no such scenario file",
        ".": "is a directory; expected a scenario file",
        "bin.csv": "is binary (a NUL byte at offset 6)",
        "latin1.csv": "is not UTF-8 text (byte 0xe9 at offset 9)",
        "utf16.toml": "is UTF-16 text; expected UTF-8",
    }
    for name, message in cases.items():
        with pytest.raises(MotosimError, match=re.escape(message)):
            check_input(tmp_path / name, "scenario file", text=True)
    assert check_input(tmp_path / "ok.toml", "scenario file", text=True) == tmp_path / "ok.toml"
    with pytest.raises(MotosimError, match="is a file; expected a result folder"):
        check_input(tmp_path / "ok.toml", "result folder", folder=True)
    with pytest.raises(MotosimError, match="no such result folder"):
        check_result_input(tmp_path / "run")
    (tmp_path / "run.partial").mkdir()  # a stopped run: its reader names where its rows are
    assert check_result_input(tmp_path / "run") == tmp_path / "run"


def test_a_text_sample_cut_inside_a_character_is_not_refused(tmp_path: Path) -> None:
    path = tmp_path / "long.csv"
    path.write_bytes(b"a" * 65_535 + "\u00e9".encode())  # the two bytes across the sample's end
    assert check_input(path, "log file", text=True) == path


def test_an_output_named_with_a_trailing_slash_is_a_folder(tmp_path: Path) -> None:
    with pytest.raises(MotosimError, match=r"--out new/ ends in /, which names a folder"):
        check_output("new/", overwrite=True)
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("folder", ["/proc", "/sys"])
def test_an_output_where_no_file_can_be_made_is_refused_at_once(folder: str) -> None:
    if not os.path.isdir(folder):
        pytest.skip(f"no {folder} here")
    with pytest.raises(MotosimError, match=f"cannot write in the folder {folder}"):
        check_output(f"{folder}/o.csv", overwrite=True)
    with pytest.raises(MotosimError, match=f"cannot write in the folder {folder}"):
        check_output_folder(f"{folder}/out", overwrite=True)


def test_a_read_only_mount_is_found_by_the_probe(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def read_only(*args: object, **kwargs: object) -> None:
        raise OSError(errno.EROFS, "Read-only file system")

    monkeypatch.setattr(tempfile, "mkstemp", read_only)
    with pytest.raises(MotosimError, match=r"cannot write in the folder .* \(Read-only file sys"):
        check_output(tmp_path / "o.csv", overwrite=True)
    with pytest.raises(MotosimError, match="Read-only file system"):
        check_folder_target(tmp_path / "out", "--out", "a result folder")


def test_the_probe_leaves_nothing_behind(tmp_path: Path) -> None:
    check_output(tmp_path / "o.csv", overwrite=True)
    check_output_folder(tmp_path / "out", overwrite=True)
    assert list(tmp_path.iterdir()) == []


def test_an_input_this_user_may_not_read_is_named_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "s.toml"
    path.write_text("x = 1\n", encoding="utf-8")
    monkeypatch.setattr(os, "access", lambda *args, **kwargs: False)  # root reads anything
    with pytest.raises(MotosimError, match=r"s.toml: cannot read the scenario file: Permission"):
        check_input(path, "scenario file", text=True)
