"""The platform output of the real-time loop, lock-step against the rig and the platform twin.

lane_change_20 (the repository's scenario), shortened, runs through the real-time loop with
the virtual rider at the rig (as in test_rt_offline.py) and a platform stage sending UDP
datagrams on localhost, or PF_COMMAND frames on the run's bus that the rig hands over, to a
:class:`PlatformTwin`. The platform's roll command must be the
offline washout's (:func:`motosim.cueing.cue`) of the same ride, and what the twin does must
keep the platform's limits.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motosim.cueing import TELBAN_CARDULLO_2005, cue, load_platform
from motosim.rt.fused import LoopColumn
from motosim.rt.platform import (
    PlatformCanSender,
    PlatformOutput,
    PlatformSender,
    PlatformTwin,
    PlatformValue,
)
from motosim.rt.stack import CompiledStack

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import platform_codecs
from motosim.rt.lockstep import Lockstep, free_limits


@pytest.mark.parametrize("medium", ["udp", "can"])
def test_platform_commands_reach_the_twin_within_the_limits(medium: str) -> None:
    from motosim.io.runs import load_run

    full = load_run(Path(__file__).parents[2] / "scenarios" / "lane_change_20.toml")
    inputs = dataclasses.replace(full, scenario=dataclasses.replace(full.scenario, duration=5.0))
    sc = inputs.scenario
    rate = sc.rates.control
    limits = free_limits(rate)
    config = load_platform("simacom_platform")
    can = medium == "can"  # PF_COMMAND frames on the run's bus, or UDP datagrams
    twin = PlatformTwin(
        config.platform,
        1.0 / rate,
        None if can else ("127.0.0.1", 0),
        codecs=platform_codecs() if can else None,
    )
    platform = PlatformOutput(config, 1.0 / rate, CompiledStack.names, send_every=10)
    # the rig's virtual rider steers by the state stream the runner publishes over UDP
    lock = Lockstep(inputs, limits, channel="rt_platform", platform=platform)
    if can:
        platform.sender = PlatformCanSender(lock.host, platform_codecs())
        lock.rig.on_frame = twin.receive_frame
    else:
        assert twin.address is not None
        platform.sender = PlatformSender(twin.address)
    achieved = []

    def listen(t: float) -> None:  # after the rig's own advance
        twin.advance_to(t)
        achieved.append(twin.achieved.copy())

    lock.clock.listen(listen)
    rows = lock.run()
    runner = lock.runner
    twin.close()
    assert platform.sender is not None
    platform.sender.close()
    assert runner.counters().fault == "NONE"
    assert twin.frames == platform.sequence == round(sc.duration * 100) and twin.lost == 0
    # the loop's roll command is the offline washout of the same ride, within 0.05 deg (the
    # loop's backward difference for v_x' against the offline central one does not touch roll)
    from motosim.timeseries import TimeSeries

    names = ("v_x", "v_y", "psi_dot", "phi_dot", "phi")
    ride = TimeSeries(
        rows[:, LoopColumn.t],
        np.column_stack([rows[:, runner.names.index(n)] for n in names]),
        names,
    )
    offline = cue(config, ride, TELBAN_CARDULLO_2005, algorithm="washout")
    last = round(sc.duration * rate) - 1
    if can:  # the last frame's command, quantised at 1e-4 rad
        roll_rt = twin.command[PlatformValue.roll]
    else:
        roll_rt = twin.last.angles[0] if twin.last is not None else np.nan
    roll_offline = offline.commands["phi_s"][last - (last % 10)]
    assert abs(roll_rt - roll_offline) < np.radians(0.05)
    # the platform moved (a lane change leans the motorcycle ~10 deg) within its limits
    angles = np.array(achieved)
    assert np.max(np.abs(angles[:, 0])) > np.radians(2.0)
    dt = 1.0 / rate
    for j, axis in enumerate(config.platform.axes):
        v = np.diff(angles[:, j]) / dt
        assert np.max(np.abs(angles[:, j])) <= axis.angle
        assert np.max(np.abs(v)) <= axis.rate * (1 + 1e-9)
        assert np.max(np.abs(np.diff(v) / dt)) <= axis.accel * (1 + 1e-9) + 1e-6
