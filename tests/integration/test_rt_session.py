"""The real-time session end to end: the rig and the session on python-can's virtual bus, in
one process on a simulated clock (the rig advanced to each deadline before the period), the
recorder in its own process writing the result.

What the session promises: one loop run whose end is a stop request inside it (the torque
fades out at the duration, or on a stop, and the run ends once it is zero), the result's rows
one per period served, the :class:`~motosim.rt.session.Outcome` naming why the run ended.
"""

import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import handlebar_codecs, open_link
from motosim.io.results import load_result
from motosim.rt.clock import SimulatedClock
from motosim.rt.config import load_realtime, parse_safety, within_safety
from motosim.rt.lockstep import ideal_rig
from motosim.rt.rig import RigRider, VirtualRig
from motosim.rt.safety import State
from motosim.rt.session import Ending, RealtimeSession, RunOptions, SessionConfig
from motosim.sim import build_stack

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "realtime_square.toml"

_channels = itertools.count()


@pytest.fixture(scope="module")
def designed() -> tuple[Any, Any, Any]:
    """The square scenario's run within its safety limits, its stack designed, the limits."""
    inputs, realtime = load_realtime(str(SCENARIO), safety=True)
    limits = parse_safety(realtime["safety"], origin="test")
    inputs = within_safety(inputs, limits)
    return inputs, build_stack(inputs), limits


def _session(
    designed: tuple[Any, Any, Any], folder: Path, duration: float, stop_at: float = math.inf
) -> tuple[RealtimeSession, Any]:
    """A session against a virtual rig on a channel of its own; the rig's link."""
    inputs, model, limits = designed
    bus = f"virtual:session{next(_channels)}"
    sc = inputs.scenario
    drive = open_link(bus)
    rate = sc.rates.plant
    tau = sc.rider.profile.sample(np.arange(round(30.0 * rate) + 1) / rate, inputs.tables)
    rig = VirtualRig(
        inputs.true_handlebar,
        ideal_rig(sc),
        handlebar_codecs(),
        drive,
        RigRider(tau),
        np.random.default_rng(0),
    )
    clock = SimulatedClock()
    config = SessionConfig(
        inputs,
        model,
        limits,
        bus,
        folder,
        {"test": True},
        duration,
        RunOptions(wait="python"),
    )
    session = RealtimeSession(config, clock)

    def advance(t: float) -> None:
        rig.advance_to(t)
        if t >= stop_at:
            session.request_stop()

    clock.listen(advance)
    return session, drive


def test_a_session_fades_the_torque_out_at_its_duration_in_one_loop_run(
    designed: tuple[Any, Any, Any], tmp_path: Path
) -> None:
    # 2 s at 1 kHz, then the 0.5 s fade-out (fade_in of realtime_square.toml), in the same
    # loop run: its periods go on past the duration, none missed (a simulated clock)
    session, drive = _session(designed, tmp_path / "run", 2.0)
    try:
        with session:
            session.prepare()
            assert session.open() is None  # no live view
            outcome = session.run()
    finally:
        drive.close()
    assert outcome.ending is Ending.COMPLETED and outcome.counters.fault == "NONE"
    stats = outcome.stats
    assert stats.missed == 0 and stats.periods == stats.served
    assert 2500 <= stats.served <= 2505  # the duration's 2000 periods and the 0.5 s fade
    result = load_result(tmp_path / "run")
    assert result.complete and result.t.size == stats.served
    assert result["i_m"][-1] == 0.0 and outcome.counters.state == State.IDLE.name
    assert result.t[-1] > 2.49 and np.max(np.abs(result["i_m"])) > 0.0
    # the fade-out: each current after the duration within the envelope times the clamp
    after = result.t >= 2.0
    envelope = np.linspace(1.0, 0.0, after.sum() + 1)[1:]
    assert np.all(np.abs(result["i_m"][after]) <= envelope * 10.0 + 1e-9)
    assert outcome.report["timing"]["served"] == stats.served
    assert outcome.report["ending"] == "completed"


def test_a_stop_request_fades_the_torque_out_and_ends_the_run_stopped(
    designed: tuple[Any, Any, Any], tmp_path: Path
) -> None:
    session, drive = _session(designed, tmp_path / "run", 5.0, stop_at=1.5)
    try:
        with session:
            session.prepare()
            session.open()
            outcome = session.run()
    finally:
        drive.close()
    assert outcome.ending is Ending.STOPPED
    result = load_result(tmp_path / "run")
    assert not result.complete  # stopped before its duration: closed partial
    assert result["i_m"][-1] == 0.0 and 1.99 < result.t[-1] < 2.1  # 0.5 s of fade
    assert result.t.size == outcome.stats.served


def test_an_emergency_stop_before_the_runner_is_built_is_kept(
    designed: tuple[Any, Any, Any], tmp_path: Path
) -> None:
    # Ctrl-C twice while the stack loads: the command's handler calls the session's
    # emergency stop before the runner exists; the run then zeroes the torque at once
    session, drive = _session(designed, tmp_path / "run", 5.0)
    try:
        with session:
            session.emergency_stop()
            session.prepare()
            session.open()
            outcome = session.run()
    finally:
        drive.close()
    assert outcome.ending is Ending.STOPPED and outcome.counters.fault == "ESTOP_KEY"
    assert outcome.stats.served < 300  # the linger after the fault, not the 5 s


def test_the_config_refuses_a_duration_out_of_range(designed: tuple[Any, Any, Any]) -> None:
    from motosim.errors import MotosimError

    inputs, model, limits = designed
    with pytest.raises(MotosimError, match=r"duration = nan s; expected seconds in \(0, 86400\]"):
        SessionConfig(inputs, model, limits, "virtual", Path("x"), {}, math.nan)
    with pytest.raises(MotosimError, match="pace = 'frames'; expected 'clock' or 'bus'"):
        RunOptions(pace="frames")  # type: ignore[arg-type]
