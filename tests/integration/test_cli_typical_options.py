"""Legal but implausible option values are accepted with one warning line, like files.

Every numeric option that sets a speed, a duration, a rate, a noise, an amplitude or a
bandwidth has a typical range in :data:`motosim.cli._common.TYPICAL_OPTIONS`; a value outside
it (but legal) prints ``motosim: warning: ...`` once and the command goes on; a value outside
the legal range is still refused in one line, without the warning.
"""

import argparse
import importlib
import inspect
from pathlib import Path

import pytest

from motosim.cli._common import TYPICAL_OPTIONS
from motosim.cli.main import COMMANDS, build_parser, main

_KINDS = ("speed", "duration", "rate", "noise", "amplitude", "bandwidth")


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = build_parser(command)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            chosen: argparse.ArgumentParser = action.choices[command]
            return chosen
    raise AssertionError(command)


def _numeric_options(command: str) -> set[str]:
    """The options of ``command`` that take a number (or list of numbers) of those kinds."""
    found = set()
    for action in _subparser(command)._actions:
        names = [n for n in action.option_strings if n.startswith("--")]
        if not names or not any(k in names[0] for k in _KINDS):
            continue
        if action.type in (float, int) or names[0] in ("--speeds", "--range"):
            found.add(names[0])
    return found


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_speed_duration_rate_noise_option_has_a_typical_range(command: str) -> None:
    options = _numeric_options(command)
    typed = {option for (cmd, option) in TYPICAL_OPTIONS if cmd == command}
    assert options <= typed, f"{command}: no typical range for {sorted(options - typed)}"
    assert typed <= {n for a in _subparser(command)._actions for n in a.option_strings}
    # ... and the command warns about each of them
    module = importlib.import_module(COMMANDS[command][0])
    source = inspect.getsource(module)
    for option in typed:
        assert f'"{option}"' in source and f'warn_atypical("{command}"' in source, option


@pytest.mark.parametrize(
    ("argv", "warned"),
    [
        (["modes", "--speeds", "1,80"], "--speeds 1, 80 m/s are legal but outside the typical 2"),
        (["modes", "--range", "58:64:2"], "--range 62, 64 m/s are legal but outside"),
        (["rt-check", "--rate", "50", "--duration", "0.01"], "--rate 50 Hz is legal"),
    ],
)
def test_an_atypical_option_warns_once_and_the_command_goes_on(
    argv: list[str], warned: str, capsys: pytest.CaptureFixture[str]
) -> None:
    # rt-check's exit code is its verdict against the targets (1: not met); the warning is
    # what is tested
    assert main(argv) in ((0, 1) if argv[0] == "rt-check" else (0,))
    lines = capsys.readouterr().err.splitlines()
    assert any(line.startswith(f"motosim: warning: {warned}") for line in lines), lines
    assert len(lines) == len(set(lines))  # each once
    assert all(line.startswith("motosim: warning: ") for line in lines)


def test_excite_warns_for_long_noisy_runs_and_refuses_absurd_ones(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "x.csv"
    argv = ["excite", "--duration", "900", "--rate", "20", "--current-noise", "2", "--out"]
    assert main([*argv, str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert [line.split(" is legal")[0] for line in err] == [
        "motosim: warning: --duration 900 s",
        "motosim: warning: --rate 20 Hz",
        "motosim: warning: --current-noise 2 A",
    ]
    assert main(["excite", "--duration", "1e7", "--out", str(tmp_path / "y.csv")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("motosim: error: --duration")


def test_fidelity_warns_at_a_speed_outside_the_validated_range(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # refused outside the rider's schedule (3-60 m/s); warned between 55 and 60 m/s
    assert main(["fidelity", "--speed", "70"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "warning" not in err
