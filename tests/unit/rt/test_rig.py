"""The virtual rig: plant, quantisation, the bus's imperfections and the injected faults."""

import math

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.model.handlebar import step_exact
from motosim.params import load_parameters
from motosim.rt.rig import Bar, RigFaults, RigRider, RigSettings, VirtualRig, parse_rig

pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

from motosim.io.can import handlebar_codecs

HB = load_parameters("simacom_handlebar", "handlebar")
CODECS = handlebar_codecs()
ST = CODECS.status


class FakeLink:
    """Frames the rig sends, and commands queued for it."""

    def __init__(self) -> None:
        self.sent: list[tuple[int, bytes]] = []
        self.inbox: list[tuple[int, bytes]] = []

    def send(self, frame_id: int, data: bytes) -> bool:
        self.sent.append((frame_id, data))
        return True

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        return self.inbox.pop(0) if self.inbox else None


def _rig(rider: float = 0.0, **kw: object) -> tuple[VirtualRig, FakeLink]:
    base: dict[str, object] = {
        "plant_rate": 10_000.0,
        "status_rate": 1000.0,
        "encoder_bits": 14,
        "current_noise": 0.0,
        "max_current": 30.0,
    }
    link = FakeLink()
    settings = RigSettings(**(base | kw))  # type: ignore[arg-type]
    rig = VirtualRig(
        HB,
        settings,
        CODECS,
        link,
        RigRider(np.full(100_000, rider), on_enable=False),
        np.random.default_rng(0),
    )
    return rig, link


def _status(link: FakeLink, *, strict: bool = True) -> np.ndarray:
    rows = []
    for frame_id, data in link.sent:
        if frame_id == ST.frame_id:
            out = np.zeros(len(ST.names))
            assert ST.decode(data, out) or not strict
            rows.append(out)
    return np.array(rows)


def _command(current: float, enable: bool = True) -> tuple[int, bytes]:
    values = np.zeros(len(CODECS.command.names))
    values[CODECS.position(CODECS.command, "current_command")] = current
    values[CODECS.position(CODECS.command, "enable")] = float(enable)
    return CODECS.command.frame_id, CODECS.command.encode(values)


def test_plant_is_eq_5_with_exact_stick_slip() -> None:
    # 3 N*m of rider torque for 0.1 s, no current: the same as step_exact at 0.1 ms steps
    rig, _ = _rig(rider=3.0)
    rig.advance_to(0.1)
    theta, omega = 0.0, 0.0
    for _ in range(1000):
        theta, omega = step_exact(theta, omega, 3.0, HB.J_eq, HB.beta_eq, HB.beta_s, 1e-4)
    assert rig.x[Bar.theta] == pytest.approx(theta, rel=1e-12) and rig.x[
        Bar.omega
    ] == pytest.approx(omega)


def test_current_command_acts_through_n_kt_and_the_drive_limit() -> None:
    rig, link = _rig()
    link.inbox.append(_command(100.0))  # beyond the 1 mA DBC range: saturated to 32.767 A
    rig.advance_to(0.001)
    assert rig.i_cmd == pytest.approx(32.767) and rig.x[Bar.i_m] == 30.0  # the drive's limit


def test_the_drives_current_loop_is_a_first_order_lag_of_its_time_constant() -> None:
    # [realtime.rig] current_time_constant = 0.01 s: a 10 A step command from t = 0 gives
    # 10 (1 - exp(-t / 0.01)) A (the lag discretised exactly at the plant step)
    rig, link = _rig(current_time_constant=0.01, command_timeout=1.0)
    link.inbox.append(_command(10.0))
    for t in (0.001, 0.01, 0.05):
        rig.advance_to(t)
        assert rig.x[Bar.i_m] == pytest.approx(10.0 * -math.expm1(-t / 0.01), rel=1e-9)


def test_without_commands_the_drive_stops_the_torque() -> None:
    rig, link = _rig(command_timeout=0.01)
    link.inbox.append(_command(5.0))
    rig.advance_to(0.005)
    assert rig.x[Bar.i_m] == 5.0
    rig.advance_to(0.03)
    assert rig.x[Bar.i_m] == 0.0


def test_status_frames_quantise_like_the_encoder_and_the_dbc() -> None:
    rig, link = _rig(rider=3.0)
    rig.advance_to(0.05)
    rows = _status(link)
    angle = rows[:, ST.index("ANGLE")]
    quantum = 2 * math.pi / 2**14
    assert rows.shape[0] == 51  # one at t = 0, then every millisecond
    assert np.all(np.abs(angle / quantum - np.round(angle / quantum)) * quantum <= 5e-6 + 1e-12)
    assert np.all(np.diff(rows[:, ST.index("COUNTER")]) % 15 == 1)


@pytest.mark.parametrize(
    ("faults", "check"),
    [
        (RigFaults(frozen_encoder=0.02), lambda a, i: np.ptp(a[25:]) == 0.0 and np.ptp(a) > 0),
        (RigFaults(sign_flip=0.02), lambda a, i: np.all(a[25:] < 0) and np.all(a[5:15] > 0)),
        (
            RigFaults(current_offset_at=0.02, current_offset=1.5),
            lambda a, i: np.all(i[:20] == 0.0) and np.allclose(i[25:], 1.5),
        ),
    ],
)
def test_sensor_faults(faults: RigFaults, check: object) -> None:
    rig, link = _rig(rider=3.0, faults=faults)
    rig.advance_to(0.05)
    rows = _status(link)
    assert check(rows[:, ST.index("ANGLE")], rows[:, ST.index("CURRENT")])  # type: ignore[operator]


def test_frame_faults_bad_checksum_estop_drive_fault() -> None:
    rig, link = _rig(faults=RigFaults(bad_checksum=0.01, estop=0.02, drive_fault=0.03))
    rig.advance_to(0.05)
    status = [d for i, d in link.sent if i == ST.frame_id]
    bad = [k for k, d in enumerate(status) if not ST.decode(d, np.zeros(len(ST.names)))]
    assert bad == [10]  # one frame, at 10 ms
    estops = [d for i, d in link.sent if i == CODECS.estop.frame_id]
    out = np.zeros(len(CODECS.estop.names))
    assert len(estops) == 1 and CODECS.estop.decode(estops[0], out)
    assert out[CODECS.position(CODECS.estop, "estop_signal")] == 1.0
    flags = _status(link, strict=False)[:, ST.index("DRIVE_FAULT")]
    assert np.all(flags[:30] == 0.0) and np.all(flags[30:] == 1.0)  # from 30 ms


def test_loss_bursts_stale_and_duplicates_are_counted() -> None:
    rig, link = _rig(loss=0.1, burst_enter=0.02, burst_leave=0.3, stale=0.05, duplicate=0.05)
    rig.advance_to(2.0)
    counters = _status(link)[:, ST.index("COUNTER")]
    steps = np.diff(counters) % 15
    assert rig.frames_dropped > 200  # 10 % random plus bursts of about 3 frames
    assert np.sum(steps == 0) > 50  # stale or duplicated: the counter did not move
    assert len(link.sent) + rig.frames_dropped > 2001


def test_latency_delays_delivery() -> None:
    rig, link = _rig(latency=0.0025)
    rig.advance_to(0.002)
    assert link.sent == []
    rig.advance_to(0.003)
    assert len(link.sent) == 1


def test_jitter_never_reorders_one_identifier() -> None:
    # 1 kHz status frames with 2 ms of latency and 0.5 ms of jitter: delays differ by more
    # than a frame period, yet the frames arrive in the order sent, as one CAN node sends
    # them, with their arrivals spread out (not all at the latency)
    rig, link = _rig(latency=0.002, jitter=0.0005)
    arrivals = []
    for k in range(1, 2001):
        before = len(link.sent)
        rig.advance_to(k * 1e-4)
        arrivals += [k * 1e-4] * (len(link.sent) - before)
    counters = _status(link)[:, ST.index("COUNTER")]
    assert counters.size > 190 and np.all(np.diff(counters) % 15 == 1)
    assert np.ptp(np.diff(arrivals)) > 1.5e-3


def test_a_late_tick_sends_the_newest_status_frame_not_a_backlog() -> None:
    # the rig's process ticking at the status rate; a tick 2.5 periods late (not catching
    # up): of the frames sampled at 7, 8 and 9 ms (due 0.3 ms later), only the newest due
    # by 9.5 ms, the one of 9 ms, is sent, and the two others counted late; on time again,
    # every frame is sent (those of 10 to 13 ms by 14 ms)
    rig, link = _rig(latency=0.0003)
    for k in range(1, 8):
        rig.advance_to(k * 1e-3)
    sent = len(link.sent)
    rig.advance_to(0.0095, catch_up=False)
    assert rig.frames_late == 2 and len(link.sent) == sent + 1
    counters = _status(link)[:, ST.index("COUNTER")]
    assert (counters[-1] - counters[-2]) % 15 == 3  # the alive counter shows the gap
    for k in range(10, 15):
        rig.advance_to(k * 1e-3)
    assert rig.frames_late == 2 and len(link.sent) == sent + 1 + 4


def test_bus_off_sends_nothing_for_its_duration() -> None:
    rig, link = _rig(bus_off_at=0.01, bus_off_duration=0.02)
    rig.advance_to(0.05)
    assert len(link.sent) == 51 - 20 and rig.frames_dropped == 20


def test_parse_rig_checks_keys_and_types() -> None:
    base = {
        "plant_rate": 1e4,
        "status_rate": 1e3,
        "encoder_bits": 14,
        "current_noise": 0.0,
        "max_current": 30.0,
    }
    s = parse_rig({"loss": 0.01, "faults": {"sign_flip": 2}}, base=base)
    assert s.loss == 0.01 and s.faults.sign_flip == 2.0
    with pytest.raises(MotosimError, match="unknown key 'lost'"):
        parse_rig({"lost": 0.1}, base=base)
    with pytest.raises(MotosimError, match="expected a probability"):
        parse_rig({"loss": 1.5}, base=base)
    with pytest.raises(MotosimError, match="multiple of"):
        parse_rig({"status_rate": 3000.0}, base=base)
    # a negative bus-off was accepted as none
    with pytest.raises(MotosimError, match=r"rig bus_off_duration = -1\.0; expected .* >= 0"):
        parse_rig({"bus_off_at": 1.0, "bus_off_duration": -1.0}, base=base)


def test_nothing_is_compiled_when_the_run_starts() -> None:
    # The run's first enabled command starts the rider's profile. The rig compiles (or loads
    # from numba's cache) its plant for the profile's own type when it is made: compiling it
    # then stalled the rig's status frames for milliseconds and tripped the run's 3-period
    # watchdog at its start. A read-only profile (as build_rig gives it) is another type.
    from motosim.rt import rig as rig_module

    profile = np.full(100_000, 3.0)
    profile.flags.writeable = False
    link = FakeLink()
    settings = RigSettings(
        plant_rate=10_000.0,
        status_rate=1000.0,
        encoder_bits=14,
        current_noise=0.0,
        max_current=30.0,
    )
    rig = VirtualRig(HB, settings, CODECS, link, RigRider(profile), np.random.default_rng(0))
    rig_module._plant_steps.disable_compile()  # a compile (or cache load) now raises
    try:
        rig.advance_to(0.01)  # the drive idle, from power-on: no rider yet
        assert rig.x[Bar.theta] == 0.0
        link.inbox.append(_command(0.0))  # the run's first enabled command
        rig.advance_to(0.02)
    finally:
        rig_module._plant_steps.disable_compile(False)
    assert rig.x[Bar.theta] > 0.0  # the rider's 3 N*m turned the handlebar
