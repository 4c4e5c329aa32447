"""rt-check's verdict against the real-time targets and the advice a run's fault gets."""

import json
import math

import numpy as np
import pytest

from motosim.rt.check import Targets, advice, verdict
from motosim.rt.loop import TimingStats, timing_stats
from motosim.rt.privileges import Privilege


def _stats(wake: float, compute: float, missed: int, rate: float = 1000.0) -> TimingStats:
    served = 1000 - missed
    return timing_stats(
        rate, np.full(served, wake), np.full(served, compute), periods=1000, missed=missed
    )


def test_the_verdict_checks_each_target_at_its_limit() -> None:
    # the targets: wake-up p99 100 us, 0.1 % missed, compute p99 a fifth of the period
    assert verdict(_stats(100e-6, 200e-6, 1)).passed
    checks = verdict(_stats(101e-6, 201e-6, 2)).checks
    assert [c.name for c in checks] == ["wake-up p99", "missed deadlines", "compute p99"]
    assert [c.passed for c in checks] == [False, False, False]
    assert checks[0].line() == "FAIL wake-up p99 101 us > 100 us"
    assert checks[1].line() == "FAIL missed deadlines 0.2 % > 0.1 %"
    # the compute's limit follows the period: 2 ms at 100 Hz
    assert verdict(_stats(50e-6, 1.9e-3, 0, rate=100.0)).passed


def test_a_loop_that_served_nothing_fails() -> None:
    stats = timing_stats(1000.0, np.zeros(0), np.zeros(0), periods=0, missed=0)
    assert not verdict(stats).passed


def test_targets_are_checked() -> None:
    from motosim.errors import MotosimError

    with pytest.raises(MotosimError, match=r"wake_p99 = 0\.0; expected a value in"):
        Targets(wake_p99=0.0)


@pytest.mark.parametrize(
    ("stats", "code"), [(_stats(20e-6, 5e-6, 0), 0), (_stats(20e-6, 5e-6, 400), 1)]
)
def test_rt_check_exits_0_on_pass_and_1_on_fail(
    stats: TimingStats,
    code: int,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import motosim.rt.check
    from motosim.cli.main import main

    monkeypatch.setattr(motosim.rt.check, "check_timing", lambda *a, **k: stats)
    assert main(["rt-check", "--duration", "1"]) == code
    out = capsys.readouterr().out
    word = "PASS" if code == 0 else "FAIL"
    assert f"verdict: {word}" in out and "PASS wake-up p99 20 us <= 100 us" in out
    assert main(["rt-check", "--duration", "1", "--json"]) == code
    payload = json.loads(capsys.readouterr().out)
    assert payload["verdict"]["pass"] is (code == 0)
    assert [c["name"] for c in payload["verdict"]["checks"]][1] == "missed deadlines"


def test_a_watchdog_fault_of_a_punctual_loop_blames_the_rig_or_the_bus() -> None:
    lines = advice(_stats(20e-6, 5e-6, 0), "WATCHDOG", asked_all=True)
    assert len(lines) == 1 and "the rig or the bus, not this loop" in lines[0]
    assert "--fifo" not in lines[0] and "motorcycle" not in lines[0]


def test_a_late_loop_is_told_the_privileges_only_when_they_were_not_given() -> None:
    late = _stats(20e-6, 5e-6, 50)  # 5 % missed
    plain = advice(late, "WATCHDOG", asked_all=False)
    assert len(plain) == 1 and "give --fifo 80 --cpu 1 --mlock" in plain[0]
    given = advice(
        late, "WATCHDOG", asked_all=True, privileges=(Privilege("SCHED_FIFO 80", True, "applied"),)
    )
    assert "give --fifo" not in given[0] and "under --fifo, --cpu and --mlock" in given[0]
    refused = advice(
        late, "NONE", asked_all=True, privileges=(Privilege("SCHED_FIFO 80", False, "EPERM"),)
    )
    assert "refused: SCHED_FIFO 80" in refused[0]


def test_no_drive_asks_whether_the_rig_runs_on_the_bus() -> None:
    lines = advice(_stats(20e-6, 5e-6, 0), "NO_DRIVE", asked_all=False, bus="udp_multicast")
    assert lines == [
        "no status frame came from the drive: is motosim rig (or the drive) running on --bus "
        "udp_multicast, the same bus and multicast group as this run?"
    ]
    assert advice(_stats(20e-6, 5e-6, 0), "NONE", asked_all=False) == []
    assert not math.isnan(_stats(20e-6, 5e-6, 0).wake_p99)
