"""Every value of every shipped scenario mutated: a scenario or a one-line error, nothing else.

The mutations are those of the bad-input corpus (missing, NaN, infinities, -1, 0, 1e300, a
400-digit integer, a string, a list, a table); each is applied to one value at a time of the
parsed document, which then goes through :func:`motosim.sim.parse_scenario`.
"""

import copy
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from motosim.errors import MotosimError
from motosim.params.toml import read_toml
from motosim.sim import Scenario, parse_scenario

ROOT = Path(__file__).parents[2]
FILES = sorted((ROOT / "scenarios").rglob("*.toml"))
MISSING = object()
MUTATIONS: list[Any] = [
    MISSING,
    math.nan,
    math.inf,
    -math.inf,
    -1,
    0,
    1e300,
    10**400,
    "text",
    [1.0, "a"],
    {"x": 1},
]


def _leaves(node: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _leaves(value, (*path, key))
    else:
        yield path


def _cases() -> Iterator[Any]:
    for file in FILES:
        document = read_toml(file, what="scenario file")
        if "realtime" in document:  # read by motosim run, dropped by load_scenario
            del document["realtime"]
        for path in _leaves(document):
            for k, value in enumerate(MUTATIONS):
                yield pytest.param(
                    file, document, path, value, id=f"{file.stem}-{'.'.join(map(str, path))}-{k}"
                )


@pytest.mark.parametrize(("file", "document", "path", "value"), list(_cases()))
def test_mutated_scenario(
    file: Path, document: dict[str, Any], path: tuple[Any, ...], value: Any
) -> None:
    mutated = copy.deepcopy(document)
    parent = mutated
    for key in path[:-1]:
        parent = parent[key]
    if value is MISSING:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    try:
        scenario = parse_scenario(mutated, origin=file.name)
    except MotosimError as err:
        text = str(err)
        assert "\n" not in text and text.startswith(file.name), text
        assert len(text) < 400, text
        return
    assert isinstance(scenario, Scenario)
