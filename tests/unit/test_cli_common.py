"""Helpers of the command line: JSON output stays strict whatever the numbers."""

import json
import math

import pytest

from motosim.cli._common import print_json


def test_non_finite_numbers_print_as_null(capsys: pytest.CaptureFixture[str]) -> None:
    print_json({"gain_margin_db": math.inf, "poles": [[-1.0, math.nan]], "ok": 2.5})
    assert json.loads(capsys.readouterr().out) == {
        "gain_margin_db": None,
        "poles": [[-1.0, None]],
        "ok": 2.5,
    }
