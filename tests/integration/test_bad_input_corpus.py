"""A generated corpus of bad inputs: each is refused in one line, exit 2, no traceback, no hang.

Generated, not listed: every field of every packaged parameter file and of a design file is
mutated one at a time (missing, NaN, inf, -1, 0, 1e300, a 400-digit integer, a string, a list,
a table), the files are re-encoded and resized (binary, Latin-1, UTF-16, NUL, 2 MB, deep
nesting), and every option of params, modes, design and paper is set at its edges. A new
field or option therefore comes with its refusals or fails here. The random bytes use a fixed
seed. Everything runs in-process through :func:`motosim.cli.main.main`.
"""

import math
import re
import time
from collections.abc import Iterator
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motosim.cli.main import COMMANDS, main
from motosim.errors import MotosimError
from motosim.io.design_file import read_design
from motosim.params import (
    HandlebarParameters,
    MultibodyParameters,
    SharpParameters,
    TyreParameters,
    list_parameter_sets,
)

SEED = 16
HANG = 10.0  # s: a case that takes longer is a hang, whatever the machine
DESIGN = Path(__file__).parents[1] / "data" / "design_simacom.toml"

# name -> (TOML text of the value, the Python value, or None when not a number)
MUTATIONS: dict[str, tuple[str, float | None]] = {
    "nan": ("nan", math.nan),
    "inf": ("inf", math.inf),
    "minus_inf": ("-inf", -math.inf),
    "minus_one": ("-1", -1.0),
    "zero": ("0", 0.0),
    "huge": ("1e300", 1e300),
    "tiny": ("1e-300", 1e-300),
    "400_digits": ("1" + "0" * 399, None),
    "string": ('"12.5"', None),
    "list": ("[1.0, 2.0]", None),
    "table": ("{ value = 1.0 }", None),
    "boolean": ("true", None),
}
_VALUE_LINE = re.compile(r"^value = .*$", re.MULTILINE)


def _packaged(name: str) -> str:
    path = resources.files("motosim.params") / "data" / f"{name}.toml"
    return path.read_text(encoding="utf-8")


def _specs(text: str) -> dict[str, Any]:
    model = re.search(r'^model = "(\w+)"', text, re.MULTILINE)
    assert model is not None
    kinds = {
        "sharp": SharpParameters,
        "handlebar": HandlebarParameters,
        "tyre": TyreParameters,
        "multibody": MultibodyParameters,
    }
    return kinds[model.group(1)].SPECS


def _mutate_parameter(text: str, name: str, mutation: str) -> str:
    """The file with the value of ``name`` mutated (or its table removed)."""
    head = f"[parameters.{name}]\n"
    start = text.index(head)
    end = text.find("\n[", start + len(head))
    end = len(text) if end < 0 else end + 1
    if mutation == "missing":
        return text[:start] + text[end:]
    block = _VALUE_LINE.sub(f"value = {MUTATIONS[mutation][0]}", text[start:end], count=1)
    return text[:start] + block + text[end:]


def _parameter_cases() -> Iterator[Any]:
    for set_name in list_parameter_sets():
        text = _packaged(set_name)
        for name, spec in _specs(text).items():
            for mutation in ("missing", *MUTATIONS):
                number = MUTATIONS[mutation][1] if mutation in MUTATIONS else None
                if number is not None and spec.admits(number):
                    continue  # a legal value (e.g. C_rxz = -1): not a bad input
                yield pytest.param(
                    set_name, _mutate_parameter(text, name, mutation), id=f"{name}-{mutation}"
                )
        for key in ("name", "model", "title", "source"):
            for mutation in ("400_digits", "list", "table", "boolean", "huge"):
                bad = re.sub(
                    rf"^{key} = .*$",
                    f"{key} = {MUTATIONS[mutation][0]}",
                    text,
                    count=1,
                    flags=re.MULTILINE,
                )
                yield pytest.param(set_name, bad, id=f"set.{key}-{mutation}")
        yield pytest.param(set_name, text.replace("[set]", "[sett]"), id="set-misspelled")
        yield pytest.param(set_name, text.replace("[parameters.", "[parameter."), id="params-typo")
        yield pytest.param(set_name, text.replace('model = "', 'model = ["') + "]", id="model-list")


def _encoded_cases() -> Iterator[Any]:
    rng = np.random.default_rng(SEED)
    text = _packaged("simacom_handlebar")
    yield pytest.param(text.encode("utf-16"), id="utf-16")
    yield pytest.param(text.encode("utf-16-le"), id="utf-16-le-no-bom")
    yield pytest.param(("# é\n" + text).encode("latin-1"), id="latin-1")
    yield pytest.param(rng.integers(0, 256, 4096, dtype=np.uint8).tobytes(), id="binary")
    yield pytest.param(b"\x00" * 100, id="nul-bytes")
    yield pytest.param(b"", id="empty")
    yield pytest.param(text.encode() + b"# " + b"x" * 2_000_000 + b"\n", id="2-MB")
    yield pytest.param(b"a = " + b"[" * 100_000 + b"]" * 100_000, id="deep-array")
    yield pytest.param(("[" + ".".join(["k"] * 500) + "]\n").encode(), id="deep-tables")
    yield pytest.param(b"x = " + b"9" * 5000, id="5000-digits")
    yield pytest.param(b'x = "' + b"y" * 900_000 + b'"', id="huge-string")


def _check_refused(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    start = time.monotonic()
    code = main(argv)
    elapsed = time.monotonic() - start
    out, err = capsys.readouterr()
    assert code == 2, (argv[:3], out[-300:], err[-300:])
    assert err.startswith("motosim: error: ") and err.count("\n") == 1, err[-500:]
    assert "Traceback" not in err and len(err) < 2_000
    assert elapsed < HANG, f"{argv[:3]} took {elapsed:.1f} s"
    return err


@pytest.mark.parametrize(("set_name", "text"), list(_parameter_cases()))
def test_parameter_files(
    set_name: str, text: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / f"{set_name}.toml"
    path.write_text(text, encoding="utf-8")
    err = _check_refused(["params", "show", str(path)], capsys)
    assert str(path) in err


@pytest.mark.parametrize("content", list(_encoded_cases()))
def test_encodings_and_sizes(
    content: bytes, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "p.toml"
    path.write_bytes(content)
    assert str(path) in _check_refused(["params", "show", str(path)], capsys)
    assert str(path) in _check_refused(["modes", "--params", str(path)], capsys)


def _design_keys(text: str) -> Iterator[tuple[str, str]]:
    """(table, key) of every value line of the design file."""
    table = ""
    for line in text.splitlines():
        if line.startswith("["):
            table = line.strip("[]")
        elif " = " in line:
            yield table, line.split(" = ")[0]


def _design_mutants(
    text: str, mutations: tuple[str, ...] = ("missing", *MUTATIONS)
) -> Iterator[tuple[str, str, str, str]]:
    """(mutated text, table, key, mutation) for every value line of a design file."""
    for table, key in _design_keys(text):
        for mutation in mutations:
            start = text.index(f"[{table}]\n")
            line = re.compile(rf"^{key} = .*$", re.MULTILINE)
            found = line.search(text, start)
            assert found is not None
            new = "" if mutation == "missing" else f"{key} = {MUTATIONS[mutation][0]}"
            bad = text[: found.start()] + new + text[found.end() :]
            old = found.group(0).split(" = ", 1)[1]
            value = MUTATIONS[mutation][0] if mutation in MUTATIONS else ""
            same_kind = any(
                old.startswith(kind) and value.startswith(kind) for kind in ('"', "[", "true")
            ) or (old == "false" and value == "true")
            yield bad, table, key, mutation if not same_kind else "same-kind"


def _design_cases() -> Iterator[Any]:
    for bad, table, key, mutation in _design_mutants(DESIGN.read_text(encoding="utf-8")):
        yield pytest.param(bad, table, key, mutation, id=f"{table}.{key}-{mutation}")


_MAY_PASS = {"minus_one", "zero", "tiny", "missing", "same-kind"}
"""Mutations that can be legal for some keys (dead_zone = 0, an informative key missing, a
string for a string, a list for a list, a boolean for a boolean)."""


def _check_design(text: str, table: str, key: str, mutation: str, path: Path) -> None:
    path.write_text(text, encoding="utf-8")
    start = time.monotonic()
    message = ""
    try:
        read_design(path)
    except MotosimError as err:
        message = str(err)
    assert time.monotonic() - start < HANG
    if message:
        assert "\n" not in message and str(path) in message
    else:
        assert mutation in _MAY_PASS, f"[{table}] {key} = {mutation} was accepted"


@pytest.mark.parametrize(("text", "table", "key", "mutation"), list(_design_cases()))
def test_design_files(text: str, table: str, key: str, mutation: str, tmp_path: Path) -> None:
    _check_design(text, table, key, mutation, tmp_path / "design.toml")


@pytest.fixture(scope="module")
def fresh_design(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A design file written now by ``motosim design --out`` (first order, one start)."""
    path = tmp_path_factory.mktemp("design") / "fresh.toml"
    argv = ["design", "--order", "1", "--starts", "1", "--speeds", "20", "--json"]
    assert main([*argv, "--out", str(path)]) == 0
    return path.read_text(encoding="utf-8")


def test_the_design_fixture_has_the_keys_motosim_design_writes(fresh_design: str) -> None:
    # the packaged fixture above stands for what `motosim design` writes today
    assert list(_design_keys(fresh_design)) == list(_design_keys(DESIGN.read_text("utf-8")))


@pytest.mark.parametrize("mutation", ["missing", *MUTATIONS])
def test_a_design_file_written_by_motosim_design_mutated(
    mutation: str, fresh_design: str, tmp_path: Path
) -> None:
    path = tmp_path / "as_written.toml"
    path.write_text(fresh_design, encoding="utf-8")
    read_design(path)  # as written: accepted
    cases = list(_design_mutants(fresh_design, (mutation,)))
    assert len(cases) > 30
    for text, table, key, kind in cases:
        _check_design(text, table, key, kind, tmp_path / "design.toml")


_BIG = "1" + "0" * 399
_EDGES = ("", "nan", "inf", "-inf", "-1", "0", "1e300", "-1e300", _BIG, "x", "1,", ",")


def _option_cases(tmp: Path) -> Iterator[list[str]]:
    existing = tmp / "exists.png"
    folder = tmp / "folder"
    yield []
    yield ["--bogus"]
    for command in COMMANDS:
        yield [command, "--bogus-option"]
    yield ["nonsense"]
    yield ["mdoes"]
    yield ["params"]
    yield ["params", "list", "extra"]
    yield ["params", "show"]
    yield ["params", "show", "sharp1917"]
    yield ["params", "show", str(folder)]
    for value in (*_EDGES, "1e6", "0.5", "151", ",".join(["3"] * 20_001), "3," * 5000 + "x"):
        yield ["modes", "--speeds", value]
    for value in (*_EDGES, "1:150:0.001", "0:1e9:1", "5:1:1", "1:2:0", "1:2:-1", "1:2:nan", _BIG):
        yield ["modes", "--range", value]
    for value in ("x.gif", "", str(existing), str(tmp / "no" / "m.png"), str(folder)):
        yield ["modes", "--speeds", "3", "--plot", value]
    yield ["modes", "--params", "simacom_handlebar"]
    for option in ("--order", "--starts", "--seed"):
        for value in ("-1", "x", "1.5", _BIG, "100000", "nan"):
            if (option, value) != ("--seed", "100000"):
                yield ["design", option, value]
    for option in ("--rate", "--bandwidth"):
        for value in _EDGES:
            yield ["design", option, value]
    yield ["design", "--rate", "100", "--bandwidth", "50"]
    for value in (str(folder), str(tmp / "no" / "d.toml"), str(existing)):
        yield ["design", "--out", value]
    yield ["design", "--handlebar", "sharp1971"]
    yield ["paper"]
    for value in (str(tmp), str(existing), str(tmp / "no" / "paper")):
        yield ["paper", "--out", value]


def test_options_at_their_edges(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "exists.png").write_bytes(b"\x89PNG")
    (tmp_path / "folder").mkdir()
    cases = list(_option_cases(tmp_path))
    assert len(cases) > 100
    failures = []
    for argv in cases:
        try:
            _check_refused(argv, capsys)
        except AssertionError as err:
            failures.append(f"{argv[:4]}: {str(err)[:200]}")
    assert not failures, "\n".join(failures)
