"""The ``motosim`` command end to end: params and modes, and their one-line errors."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.model import sharp as model
from motosim.params import SharpParameters


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_params_list_and_show(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "params", "list", "--json")
    assert code == 0
    assert {s["name"] for s in json.loads(out)} >= {"sharp1971", "simacom_handlebar"}
    code, out, _ = _run(capsys, "params", "show", "simacom_handlebar", "--json")
    values = json.loads(out)
    assert code == 0
    assert values["J_eq"] == 0.0415 and values["beta_eq"] == 13.956 and values["beta_s"] == 1.734
    assert {"N", "k_t"} <= set(values)
    code, out, _ = _run(capsys, "params", "show", "sharp1971")
    assert code == 0 and "Appendix 3" in out and "wheelbase" in out


def test_modes_json(capsys: pytest.CaptureFixture[str], sharp: SharpParameters) -> None:
    # the JSON carries the library's eigenvalues, which tests/reference pins to Sharp's tables
    code, out, _ = _run(capsys, "modes", "--speeds", "3,5,10", "--json")
    payload = json.loads(out)
    assert code == 0
    assert payload["speeds"] == [3.0, 5.0, 10.0]
    eig = np.array(payload["eigenvalues"])
    assert eig.shape == (3, 8, 2)
    want = model.eigenvalues(sharp, [3.0, 5.0, 10.0])
    np.testing.assert_allclose(eig[..., 0] + 1j * eig[..., 1], want)
    assert set(payload["modes"]) == {"capsize", "weave", "wobble"}
    assert payload["modes"]["weave"]["stable"] == [False, False, True]


def test_modes_table_and_plot(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    fig = tmp_path / "modes.png"
    code, out, _ = _run(capsys, "modes", "--range", "2:20:2", "--plot", str(fig))
    assert code == 0
    assert out.count("\n") > 10 and "unstable: weave" in out
    assert fig.stat().st_size > 10_000
    assert [p.name for p in tmp_path.iterdir()] == ["modes.png"]  # no temporary left
    code, _, err = _run(capsys, "modes", "--range", "2:20:2", "--plot", str(fig))
    assert code == 2 and "exists; give --overwrite to replace it" in err
    assert _run(capsys, "modes", "--speeds", "3", "--plot", str(fig), "--overwrite")[0] == 0
    code, _, err = _run(capsys, "modes", "--plot", str(tmp_path / "figs" / "m.png"))
    assert code == 2 and "does not exist; expected an existing folder" in err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["modes", "--speeds", "0.2"], "speed = 0.2 m/s; expected a finite forward speed >= 1"),
        (["modes", "--speeds", "-3"], "speed = -3 m/s"),
        (["modes", "--speeds", "a,b"], "--speeds 'a,b'; expected comma-separated numbers"),
        (["modes", "--range", "2:60"], "--range '2:60'; expected start:stop:step"),
        (["modes", "--range", "2:60:0"], "expected finite start <= stop and a step > 0"),
        (["modes", "--params", "nowhere.toml"], "no such parameter file or packaged set"),
        (["modes", "--params", "simacom_handlebar"], "expected a sharp parameter set"),
        (["modes", "--plot", "x.gif"], "figure file 'x.gif'; expected a name ending in"),
        (["modes", "--speeds", "3", "--range", "2:3:1"], "not allowed with argument"),
        (["params", "show", "nothing"], "no such parameter file or packaged set"),
    ],
)
def test_one_line_errors(capsys: pytest.CaptureFixture[str], argv: list[str], message: str) -> None:
    code, out, err = _run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_bad_parameter_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    text = Path(__file__).parents[2] / "src/motosim/params/data/sharp1971.toml"
    bad = tmp_path / "bad.toml"
    bad.write_text(text.read_text().replace("value = 30.647196", "value = -30.6"))
    code, _, err = _run(capsys, "modes", "--params", str(bad))
    assert code == 2
    assert "m_f = -30.6; expected a finite number >= 2 and <= 150 [kg]" in err


def test_console_script_exit_code() -> None:
    """The installed command itself exits 2 without a traceback."""
    proc = subprocess.run(
        [sys.executable, "-m", "motosim.cli.main", "modes", "--speeds", "nan"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith("motosim: error:")
    assert "Traceback" not in proc.stderr


def test_python_dash_m_and_a_light_help() -> None:
    """``python -m motosim`` works; ``--help`` imports no subcommand, NumPy or SciPy."""
    script = (
        "import sys\n"
        "from motosim.cli.main import main\n"
        "code = main(['--help'])\n"
        "heavy = [m for m in ('numpy', 'scipy', 'h5py', 'motosim.cli.modes') if m in sys.modules]\n"
        "print(code, heavy)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.stdout.strip().endswith("0 []"), done.stdout[-300:]
    done = subprocess.run(
        [sys.executable, "-m", "motosim", "modes", "--speeds", "3", "--json"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0 and json.loads(done.stdout)["speeds"] == [3.0]


def test_every_command_has_its_help(capsys: pytest.CaptureFixture[str]) -> None:
    from motosim.cli.main import COMMANDS

    for name in COMMANDS:
        assert main([name, "--help"]) == 0, name
        assert f"usage: motosim {name}" in capsys.readouterr().out


def test_every_command_module_registers_the_help_main_lists() -> None:
    import argparse
    import importlib

    from motosim.cli.main import COMMANDS

    for name, (module, text) in COMMANDS.items():
        sub = argparse.ArgumentParser().add_subparsers()
        importlib.import_module(module).register(sub)
        helps = {action.dest: action.help for action in sub._choices_actions}
        assert helps[name] == text, name


def test_an_internal_error_is_one_line_exit_1(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from motosim.cli import params as params_command

    def broken(args: object) -> int:
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(params_command, "_list", broken)
    assert main(["params", "list"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("motosim: internal error: ZeroDivisionError: float division by zero")
    assert err.count("\n") == 1
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "params", "list"])
