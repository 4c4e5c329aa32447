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


def test_a_virtual_riders_csv_probe_is_read_like_any_profile(tmp_path: Path) -> None:
    # the probe's file was never read: KeyError 'probe.csv' inside the run (exit 1, two lines,
    # an empty DIR.partial left behind)
    from motosim.io.runs import load_run

    (tmp_path / "probe.csv").write_text("t,tau_r\n0,0\n0.1,2\n0.2,0\n", encoding="utf-8")
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "s"\nduration = 0.3\n[rider]\nkind = "virtual"\n'
        'probe = { kind = "csv", file = "probe.csv", column = "tau_r" }\n'
        '[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    inputs = load_run(scenario)
    assert inputs.tables["probe.csv"]["tau_r"].tolist() == [0.0, 2.0, 0.0]
