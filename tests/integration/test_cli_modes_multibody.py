"""``motosim modes`` on a multibody set with tyres: the same JSON as for Sharp's machine."""

import json
import sys

import numpy as np
import pytest

from motosim.cli.main import main
from motosim.model import tyred


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as info:
        sys.exit(main(list(argv)))
    out, err = capsys.readouterr()
    return int(info.value.code or 0), out, err


def test_a_multibody_set_gets_the_modes_of_its_tyred_model(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, _ = _run(capsys, "modes", "--speeds", "10,30", "--json")
    sharp = json.loads(out)
    assert code == 0
    argv = ("modes", "--params", "sel2004_motorcycle", "--speeds", "10,30", "--json")
    code, out, _ = _run(capsys, *argv)
    ours = json.loads(out)
    assert code == 0
    assert ours.keys() == sharp.keys() and ours["modes"].keys() == sharp["modes"].keys()
    assert ours["params"] == "sel2004_motorcycle"
    table = tyred.lateral_modes(tyred.load_model("sel2004_motorcycle"), [10.0, 30.0])
    for name in ("capsize", "weave", "wobble"):
        mode = ours["modes"][name]
        assert mode.keys() == sharp["modes"][name].keys()
        np.testing.assert_allclose([complex(*z) for z in mode["eigenvalue"]], table.mode(name))
    # the default model follows the set's kind: --model multibody is the same table
    code, out, _ = _run(capsys, *argv, "--model", "multibody")
    assert code == 0 and json.loads(out) == ours


def test_the_table_names_the_unstable_wobble(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _run(capsys, "modes", "--params", "sel2004_motorcycle", "--speeds", "20,40")
    rows = out.splitlines()[2:]
    assert code == 0 and len(rows) == 2
    assert "wobble" not in rows[0] and rows[1].endswith("unstable: capsize, wobble")


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (("--params", "sel2004_motorcycle", "--model", "sharp1971"), ("sharp1971", "multibody")),
        (("--params", "benchmark_bicycle"), ("benchmark_bicycle", "without tyres")),
        (("--params", "sel2004_front_120_70_zr17"), ("tyre parameter set", "expected")),
    ],
)
def test_a_set_the_model_cannot_take_is_refused_in_one_line(
    capsys: pytest.CaptureFixture[str], argv: tuple[str, ...], words: tuple[str, ...]
) -> None:
    code, out, err = _run(capsys, "modes", *argv)
    assert code == 2 and out == ""
    assert len(err.splitlines()) == 1 and all(word in err for word in words)
