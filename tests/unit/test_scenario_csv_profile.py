"""A scenario's CSV profile without the expected columns: the message says what to fix in
the file (``motosim simulate`` has no ``--columns`` option, which identify and estimate do)."""

from pathlib import Path

import pytest

from motosim.cli.main import main


def test_a_csv_profile_without_its_columns_is_refused_with_advice_for_the_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "torque.csv").write_text("time,torque\n0,0\n1,2\n2,0\n", encoding="utf-8")
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "s"\nduration = 1.0\n[rider]\nkind = "torque"\n'
        'profile = { kind = "csv", file = "torque.csv", column = "tau" }\n',
        encoding="utf-8",
    )
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing column 't'" in err
    assert "--columns" not in err
    assert "header" in err and "column = " in err
