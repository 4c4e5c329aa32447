"""Issue 11's targets on handlebars simulated independently of motosim, through the CLI.

The logs come from :mod:`independent_rig` (Heun's method at 5 us with Karnopp's stick rule,
no motosim code): a continuous measured current (a 0.1-4 Hz chirp of 4 A, 5 mA noise),
a 14-bit encoder, Coulomb friction, 60 s at 100 Hz or 20 s at 1 kHz, the handlebar already
moving when the log starts and the encoder at an arbitrary offset. They are identified as
the issue's harness does: ``motosim identify LOG.csv --ratio 1 --torque-constant 1 --json``.

Targets (issue 11): beta_eq and beta_s within 3 %, J_eq within 10 % at 100 Hz and 5 % at
1 kHz, for J/beta from 1.5 to 13 ms with the default options; the true value inside the
reported 95 % interval in at least 9 of 10 cases.
"""

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from independent_rig import rig_log, write_csv

from motosim.cli.main import main

# (J_eq kg*m^2, beta_eq N*m*s/rad, beta_s N*m): J/beta 1.5, 3.0, 6.7 and 13.3 ms; the first
# and third are the 1 kHz and 100 Hz examples (J 0.028, beta 18.5; J 0.06, beta 9)
HANDLEBARS = {
    "1.5ms": (0.028, 18.5, 1.0),
    "3ms": (0.045, 15.0, 2.0),
    "6.7ms": (0.06, 9.0, 1.0),
    "13ms": (0.08, 6.0, 0.5),
}
RATES = {100.0: (60.0, 0.10), 1000.0: (20.0, 0.05)}  # rate: (duration s, J_eq tolerance)
NAMES = ("J_eq", "beta_eq", "beta_s")
COUNT = 2.0 * math.pi / 2**14  # one count of the 14-bit encoder [rad]


def _identify(capsys: pytest.CaptureFixture[str], path: Path, *extra: str) -> dict[str, object]:
    with pytest.raises(SystemExit) as info:
        sys.exit(
            main(
                ["identify", str(path), "--ratio", "1", "--torque-constant", "1", "--json", *extra]
            )
        )
    out, err = capsys.readouterr()
    assert info.value.code in (0, None), err
    report: dict[str, Any] = json.loads(out)
    return report


def _log(tmp_path: Path, name: str, hb: tuple[float, float, float], rate: float, seed: int) -> Path:
    J, beta, beta_s = hb
    t, theta, current = rig_log(
        J=J,
        beta=beta,
        beta_s=beta_s,
        sample_rate=rate,
        duration=RATES[rate][0],
        amplitude=4.0,
        seed=seed,
        theta0=0.2 + 0.1 * seed * COUNT,  # encoder offset, a different count phase per seed
        omega0=0.3,  # moving when the log starts
    )
    path = tmp_path / f"{name}.csv"
    write_csv(str(path), t, theta, current)
    return path


def _inside(report: dict[str, Any], name: str, truth: float) -> bool:
    lo, hi = report[f"{name}_ci95"]
    return bool(lo <= truth <= hi)


@pytest.mark.parametrize("rate", sorted(RATES))
@pytest.mark.parametrize("case", sorted(HANDLEBARS))
def test_targets_with_default_options(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str, rate: float
) -> None:
    hb = HANDLEBARS[case]
    report = _identify(capsys, _log(tmp_path, case, hb, rate, seed=1))
    assert report["drive"] == "current_sampled"  # i_m only: a measured continuous current
    errors = [abs(float(report[k]) / v - 1.0) for k, v in zip(NAMES, hb, strict=True)]
    assert errors[0] < RATES[rate][1]
    assert errors[1] < 0.03
    assert errors[2] < 0.03
    assert report["units"] == {"J_eq": "kg*m^2", "beta_eq": "N*m*s/rad", "beta_s": "N*m"}


@pytest.mark.parametrize("case", ["1.5ms", "13ms"])
def test_intervals_cover_the_truth(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str
) -> None:
    # 10 logs that differ in current noise and encoder phase: the true value inside the
    # 95 % interval in at least 9 of 10 (issue 11); measured 10/10/10 and 9/9/9 at 100 Hz
    hb = HANDLEBARS[case]
    inside = np.zeros(3, dtype=int)
    for seed in range(10):
        report = _identify(capsys, _log(tmp_path, f"{case}-{seed}", hb, 100.0, seed))
        inside += [_inside(report, k, v) for k, v in zip(NAMES, hb, strict=True)]
    assert np.all(inside >= 9), inside


def test_current_delay_option(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # one sample of CAN latency on the current at 100 Hz: --current-delay puts it back
    J, beta, beta_s = HANDLEBARS["6.7ms"]
    t, theta, current = rig_log(
        J=J, beta=beta, beta_s=beta_s, sample_rate=100.0, duration=60.0, amplitude=4.0
    )
    late = np.concatenate([[current[0]], current[:-1]])  # logged one sample late
    path = tmp_path / "late.csv"
    write_csv(str(path), t, theta, late)
    report = _identify(capsys, path, "--current-delay", "0.01")
    assert abs(float(report["J_eq"]) / J - 1.0) < 0.10
    assert abs(float(report["beta_eq"]) / beta - 1.0) < 0.03
    assert abs(float(report["beta_s"]) / beta_s - 1.0) < 0.03


def test_weak_inertia_is_reported(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    # a 1.5 ms handlebar at 100 Hz under a slow 0.1-2 Hz chirp: J theta'' is about 2 % of the
    # torque, J_eq is not identifiable to 10 %, and the tool says so and covers the truth
    J, beta, beta_s = HANDLEBARS["1.5ms"]
    t, theta, current = rig_log(
        J=J, beta=beta, beta_s=beta_s, sample_rate=100.0, duration=60.0, amplitude=2.0, f1=2.0
    )
    path = tmp_path / "slow.csv"
    write_csv(str(path), t, theta, current)
    report = _identify(capsys, path)
    warnings = report["warnings"]
    assert isinstance(warnings, list) and any("weakly identified" in w for w in warnings)
    assert "excite up to" in warnings[0]
    assert _inside(report, "J_eq", J)


@pytest.mark.parametrize("case", ["1.5ms", "13ms"])
def test_planned_excitation_identifies_all_three(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, case: str
) -> None:
    # motosim excite --plan from rough values 30 % off, then the rig runs the planned chirp:
    # no weak-inertia warning, J_eq within 10 % and the frictions within 3 % at 100 Hz
    J, beta, beta_s = HANDLEBARS[case]
    rough = [f"{1.3 * J:g}", f"{0.7 * beta:g}", f"{1.3 * beta_s:g}"]
    with pytest.raises(SystemExit):
        sys.exit(
            main(
                [
                    "excite",
                    "--plan",
                    "--max-current",
                    "6",
                    "--inertia",
                    rough[0],
                    "--damping",
                    rough[1],
                    "--dry-friction",
                    rough[2],
                    "--ratio",
                    "1",
                    "--torque-constant",
                    "1",
                    "--counts",
                    "16384",
                    "--pulley-ratio",
                    "1",
                    "--json",
                ]
            )
        )
    plan = json.loads(capsys.readouterr().out)
    t, theta, current = rig_log(
        J=J,
        beta=beta,
        beta_s=beta_s,
        sample_rate=100.0,
        duration=plan["duration"],
        amplitude=plan["amplitude"],
        f0=plan["f0"],
        f1=plan["f1"],
        seed=4,
    )
    path = tmp_path / "planned.csv"
    write_csv(str(path), t, theta, current)
    report = _identify(capsys, path)
    assert report["warnings"] == []
    assert abs(report["J_eq"] / J - 1.0) < 0.10
    assert abs(report["beta_eq"] / beta - 1.0) < 0.03
    assert abs(report["beta_s"] / beta_s - 1.0) < 0.03


def test_friction_smooth_near_zero_speed(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # a rig whose dry friction is beta_s tanh(theta_h' / 1e-3 rad/s), not exact Coulomb: the
    # targets hold and the intervals (with their model allowance) still cover the truth
    for case, hb in HANDLEBARS.items():
        J, beta, beta_s = hb
        t, theta, current = rig_log(
            J=J,
            beta=beta,
            beta_s=beta_s,
            sample_rate=100.0,
            duration=60.0,
            amplitude=4.0,
            friction_width=1e-3,
        )
        path = tmp_path / f"smooth-{case}.csv"
        write_csv(str(path), t, theta, current)
        report = _identify(capsys, path)
        errors = [abs(report[k] / v - 1.0) for k, v in zip(NAMES, hb, strict=True)]
        assert errors[0] < 0.10 and errors[1] < 0.03 and errors[2] < 0.03, case
        assert all(_inside(report, k, v) for k, v in zip(NAMES, hb, strict=True)), case
