"""The virtual rig: the true handlebar and its drive on the bus, for runs without hardware.

:class:`VirtualRig` answers the frames of the DBC as a real drive does, so that the loop of
``motosim run`` cannot tell it from hardware:

- the true handlebar of eq. (5), integrated in plant sub-steps (10 kHz by default) with
  exact stick-slip by the simulated rig's plant (:func:`motosim.sim.hands.plant_step`),
  driven by the rider's torque (a profile of the scenario), held by the rider's arms, and
  the motor torque ``N k_t i_m``;
- the drive's current loop, a first-order lag of ``current_time_constant`` [s] towards the
  commanded current, limited to ``max_current`` [A]; no command for ``command_timeout``
  [s], or ENABLE 0, and the drive stops the torque (its own STO);
- the status frame at ``status_rate`` [Hz]: the angle quantised by the encoder
  (``encoder_bits`` per handlebar revolution) and by the DBC scaling, the current with noise;
  with a torque sensor, its ``HB_TORQUE`` frame after each status frame: the torque of the
  rider's hands on the handlebar (active, and the arms' passive while they hold it), with
  the sensor's offset and noise, quantised by the DBC scaling;
- the bus: a latency with jitter (truncated normal; a frame never overtakes an earlier one
  of the same identifier, as on CAN, where one node sends them in order), random frame
  loss (Bernoulli) and bursts (a two-state Gilbert-Elliott channel), stale frames (the
  previous frame sent again, counter unchanged) and duplicated frames, a bus-off window
  (nothing sent);
- injected faults from a given time after the run's first enabled command: frozen encoder,
  sign flip of the angle, an offset on the current sensor, a frame with a wrong checksum, an
  E-stop frame, the drive's fault flag.

The rig is stepped with :meth:`VirtualRig.advance_to`: in one process on a
:class:`~motosim.rt.clock.SimulatedClock` (lock-step tests, each deadline advances the rig
first) or by ``motosim rig`` in its own process on the wall clock.
"""

import heapq
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.choices import SENSOR_ESTIMATOR
from motosim.errors import MotosimError
from motosim.io.can import HandlebarCodecs, Link
from motosim.model.handlebar import HandlebarPlant, plant_of
from motosim.params.checks import check_number
from motosim.params.handlebar import HandlebarParameters
from motosim.rt.clock import SimulatedClock
from motosim.rt.config import table_number
from motosim.rt.stack import STACK_SIGNALS
from motosim.rt.telemetry import StateReceiver
from motosim.sim.closed_loop import RigModel
from motosim.sim.hands import NO_ARMS, Arms, hands_torque, is_held, plant_step
from motosim.sim.rider import rider_torque
from motosim.sim.scenario import Scenario, TorqueSensor

__all__ = [
    "Bar",
    "BarPlant",
    "LockstepLink",
    "RigFaults",
    "RigRider",
    "RigSettings",
    "VirtualRider",
    "VirtualRig",
    "parse_rig",
    "torque_sensor",
]

Array = NDArray[np.float64]
_NEVER = math.inf
_RUN_GONE = 1.0
"""Silence on the bus [s] after which the rig takes the run as gone (its process stopped)."""


@dataclass(frozen=True, slots=True)
class RigFaults:
    """Times [s] from which each fault is injected (inf: never) and the current offset [A].

    The times, like ``bus_off_at``, count from the run's first enabled command (the rig
    may run long before ``motosim run`` starts; each run gets its faults again), or from
    the rig's start for a rider who is not started by the run (``RigRider(on_enable=False)``).
    """

    frozen_encoder: float = _NEVER
    sign_flip: float = _NEVER
    current_offset_at: float = _NEVER
    current_offset: float = 0.0
    bad_checksum: float = _NEVER
    estop: float = _NEVER
    drive_fault: float = _NEVER


@dataclass(frozen=True, slots=True)
class RigSettings:
    """The drive, the sensors and the bus of the virtual rig.

    Parameters
    ----------
    plant_rate, status_rate : float
        Plant sub-step rate and status frame rate [Hz]; the first a multiple of the second.
    encoder_bits : int
        Encoder resolution per handlebar revolution [bits]; 0 for an exact angle.
    current_noise : float
        Standard deviation of the current measurement noise [A].
    max_current, current_time_constant, command_timeout : float
        The drive's current limit [A], its current loop's time constant [s] (0: ideal) and
        how long it keeps the last command without a new one [s].
    latency, jitter : float
        Mean one-way delay of a status frame [s] and its standard deviation [s]; a frame
        delayed less than the one sent before it with the same identifier waits for it.
    loss : float
        Probability that a frame is lost, independently.
    burst_enter, burst_leave : float
        Per-frame probabilities of entering and leaving a burst in which every frame is lost.
    stale, duplicate : float
        Probabilities of sending the previous frame again instead of a new one, and of sending
        a new frame twice.
    bus_off_at, bus_off_duration : float
        A window [s] in which the rig sends nothing (from the run's first enabled command,
        as the faults' times).
    faults : RigFaults
        Injected faults.
    """

    plant_rate: float
    status_rate: float
    encoder_bits: int
    current_noise: float
    max_current: float
    current_time_constant: float = 0.0
    command_timeout: float = 0.05
    latency: float = 0.0
    jitter: float = 0.0
    loss: float = 0.0
    burst_enter: float = 0.0
    burst_leave: float = 1.0
    stale: float = 0.0
    duplicate: float = 0.0
    bus_off_at: float = _NEVER
    bus_off_duration: float = 0.0
    faults: RigFaults = field(default_factory=RigFaults)

    def __post_init__(self) -> None:
        for name, low, high, unit in (
            ("plant_rate", 1.0, 1e6, "Hz"),
            ("status_rate", 1.0, 1e5, "Hz"),
            ("max_current", 0.01, 200.0, "A"),
            ("command_timeout", 1e-4, 60.0, "s"),
        ):
            check_number(getattr(self, name), where=f"rig {name}", lower=low, upper=high, unit=unit)
        ratio = self.plant_rate / self.status_rate
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise MotosimError(
                f"rig plant_rate = {self.plant_rate!r} Hz: expected a multiple of "
                f"status_rate = {self.status_rate!r} Hz"
            )
        for name, high, unit in (
            ("current_noise", 100.0, "A"),
            ("current_time_constant", 1.0, "s"),
            ("latency", 1.0, "s"),
            ("jitter", 1.0, "s"),
            ("bus_off_duration", 86_400.0, "s"),  # 0 s is no bus-off; a negative one is refused
        ):
            check_number(getattr(self, name), where=f"rig {name}", lower=0.0, upper=high, unit=unit)
        for name in ("loss", "burst_enter", "burst_leave", "stale", "duplicate"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise MotosimError(f"rig {name} = {value!r}: expected a probability in [0, 1]")
        if not 0 <= self.encoder_bits <= 32:
            raise MotosimError(f"rig encoder_bits = {self.encoder_bits!r}: expected 0..32")


def parse_rig(
    table: Mapping[str, Any], *, base: Mapping[str, Any], where: str = "[realtime.rig]"
) -> RigSettings:
    """:class:`RigSettings` from a TOML table over the values ``base`` (from the scenario).

    Unknown keys and wrong types are one-line errors; ``faults`` is a sub-table whose keys
    are the fields of :class:`RigFaults`.
    """
    values: dict[str, Any] = dict(base)
    for key, value in _known(table, RigSettings, where).items():
        if key == "faults":
            values[key] = _parse_faults(value, f"{where[:-1]}.faults]")
        else:
            values[key] = table_number(key, value, where, key == "encoder_bits")
    return RigSettings(**values)


def torque_sensor(scenario: Scenario) -> TorqueSensor | None:
    """The torque sensor the virtual rig of ``scenario`` has: for the estimator
    ``torque_sensor``, its ``[sensor.torque]`` (an ideal one without the table); else none.

    Examples
    --------
    >>> from motosim.sim import parse_scenario
    >>> doc = {"scenario": {"name": "s"}, "rider": {"kind": "torque", "profile": 1.0}}
    >>> torque_sensor(parse_scenario(doc, origin="s")) is None
    True
    >>> doc |= {"estimator": {"name": "torque_sensor"}, "sensor": {"torque": {"noise": 0.1}}}
    >>> torque_sensor(parse_scenario(doc, origin="s"))
    TorqueSensor(noise=0.1, offset=0.0, low_pass=0.0)
    """
    if scenario.estimator.name != SENSOR_ESTIMATOR:
        return None
    return scenario.sensor.torque or TorqueSensor()


def _known(table: Any, kind: type, where: str) -> Mapping[str, Any]:
    """``table``, checked to be a table whose keys are fields of the dataclass ``kind``."""
    if not isinstance(table, Mapping):
        raise MotosimError(f"{where}: expected a table")
    allowed = {f.name for f in fields(kind)}
    for key in table:
        if key not in allowed:
            raise MotosimError(f"{where}: unknown key {key!r}; expected one of {sorted(allowed)}")
    return table


def _parse_faults(table: Any, where: str) -> RigFaults:
    known = _known(table, RigFaults, where)
    return RigFaults(**{key: table_number(key, value, where) for key, value in known.items()})


class Bar(IntEnum):
    """The true handlebar's state in :attr:`VirtualRig.x`: angle [rad], rate [rad/s] and
    the motor's current [A]."""

    theta = 0
    omega = 1
    i_m = 2


class BarPlant(NamedTuple):
    """What :func:`_plant_steps` steps: the true handlebar; the current's lag ``a_i``
    (``1 - exp(-h/T)``) and limit [A]; the sub-step ``h`` [s]; the rider's arms and
    hands-off phases (rows [t0, t1] [s])."""

    handlebar: HandlebarPlant
    a_i: float
    max_i: float
    h: float
    arms: Arms
    hands_off: Array


@njit(cache=True)
def _plant_steps(
    x: Array, i_cmd: float, p: BarPlant, tau_r: Array, k0: int, n: int, t_rider: float
) -> None:
    """Advance ``x`` (:class:`Bar`) by ``n`` sub-steps of ``p.h`` [s] in place.

    The current follows its command with ``i += (i_cmd - i) a_i``, limited to ``max_i``;
    the rider's torque is ``tau_r[k0 + k]`` (held at its last value) and acts, with the
    arms, while the rider holds the handlebar: ``t_rider`` >= 0, the rider's time at the
    first sub-step [s], outside the hands-off phases. Each sub-step is the simulated rig's
    (:func:`motosim.sim.hands.plant_step`).
    """
    theta, omega, i = x[Bar.theta], x[Bar.omega], x[Bar.i_m]
    last = tau_r.size - 1
    h, kt, off = p.h, p.handlebar.torque_per_amp, p.hands_off
    for k in range(n):
        i += (i_cmd - i) * p.a_i
        i = min(max(i, -p.max_i), p.max_i)
        held = t_rider >= 0.0 and (off.shape[0] == 0 or is_held(t_rider + k * h, off))
        torque = tau_r[min(k0 + k, last)] + kt * i if held else kt * i
        theta, omega = plant_step(theta, omega, torque, p.handlebar, p.arms, held, h)
    x[Bar.theta], x[Bar.omega], x[Bar.i_m] = theta, omega, i


@dataclass(frozen=True, eq=False)
class RigRider:
    """Who holds the virtual rig's handlebar: the rider's torque, arms and presence.

    Parameters
    ----------
    torque : ndarray or callable
        The rider's active torque [N*m] at each plant sub-step from the rider's start (held
        after the end), or a function of the time since the rider's start [s] giving it then
        (a :class:`VirtualRider`), asked once per status period.
    arms : Arms, optional
        The rider's arms while the rider holds the handlebar (``RigModel.arms`` of
        :func:`motosim.sim.build_rig`); by default none, a pure torque source.
    hands_off : ndarray, shape (m, 2), optional
        Phases [t0, t1] of the rider's time [s] in which nobody holds the handlebar.
    on_enable : bool
        Start the rider's profile when the first command with ENABLE arrives (a person takes
        the handlebar when the simulator starts) and let go when the run ends (ENABLE 0, or
        no command for 1 s: its process has gone), the profile starting again with the next
        enable; else the profile runs from the rig's t = 0 whatever the drive does.

    Raises
    ------
    MotosimError
        On a profile that is empty or not finite, or hands-off phases of the wrong shape
        (one line).
    """

    torque: Array | Callable[[float], float]
    arms: Arms = NO_ARMS
    hands_off: Array | None = None
    on_enable: bool = True

    def __post_init__(self) -> None:
        if not callable(self.torque):
            tau = np.asarray(self.torque, dtype=float)
            if tau.ndim != 1 or tau.size == 0 or not np.all(np.isfinite(tau)):
                raise MotosimError("rider torque: expected a non-empty 1-D array of finite N*m")
            object.__setattr__(self, "torque", tau)
        off = self.hands_off
        off = np.zeros((0, 2)) if off is None else np.asarray(off, dtype=np.float64)
        if off.ndim != 2 or off.shape[1] != 2:
            raise MotosimError("hands_off: expected rows [t0, t1] [s]")
        object.__setattr__(self, "hands_off", off)


class VirtualRig:
    """The true handlebar and its drive, answering the DBC's frames (see the module docstring).

    Parameters
    ----------
    handlebar : HandlebarParameters
        The true handlebar.
    settings : RigSettings
        The drive, sensors, bus and faults.
    codecs : HandlebarCodecs
        The frames.
    link : Link
        The rig's end of the bus.
    rider : RigRider
        The rider's torque, arms and presence.
    rng : numpy.random.Generator
        Noise, jitter and frame loss.
    theta0 : float
        Initial angle [rad].
    torque_sensor : TorqueSensor, optional
        A torque sensor between the grips and the steering column: the rig then sends its
        ``HB_TORQUE`` frame after each status frame (its ``low_pass`` is the stack's, not
        the sensor's). Without it, none.
    """

    def __init__(
        self,
        handlebar: HandlebarParameters,
        settings: RigSettings,
        codecs: HandlebarCodecs,
        link: Link,
        rider: RigRider,
        rng: np.random.Generator,
        *,
        theta0: float = 0.0,
        torque_sensor: TorqueSensor | None = None,
    ) -> None:
        if torque_sensor is not None and codecs.torque is None:
            raise MotosimError(
                "the virtual rig has a torque sensor and the DBC has no torque frame "
                f"({codecs.mapping.torque}); expected a DBC with it"
            )
        torque = rider.torque
        self._policy = torque if callable(torque) else None
        self.rider_torque = np.zeros(1) if callable(torque) else torque
        self.hb = handlebar
        self.settings = settings
        self.codecs = codecs
        self.link = link
        self.rng = rng
        self.arms = rider.arms
        self.hands_off: Array = rider.hands_off  # type: ignore[assignment]
        self.x = np.array([float(theta0), 0.0, 0.0])
        self.h = 1.0 / settings.plant_rate
        self._sub = round(settings.plant_rate / settings.status_rate)
        tc = settings.current_time_constant
        self._a_i = 1.0 if tc == 0.0 else -math.expm1(-self.h / tc)
        self.k = 0  # plant sub-steps done
        self.i_cmd = 0.0
        self.enabled = False
        self._last_command = -math.inf
        self._queue: list[tuple[float, int, int, bytes]] = []
        self._seq = 0
        self._last_due: dict[int, float] = {}
        self._counter = 0
        self._previous: bytes | None = None
        self._burst = False
        self._frozen = math.nan
        self._estop_sent = False
        self._bad_sent = False
        self._frame_positions(codecs)
        self._k_rider = -1 if rider.on_enable else 0
        self._let_go = rider.on_enable
        self._t_run = math.inf if rider.on_enable else 0.0  # where fault times count from
        self._idle = np.zeros(1)
        self._held = np.zeros(1)
        self._started = False
        self.torque_sensor = torque_sensor
        self._hands = 0.0  # the rider's active torque now [N*m]
        self._holding = False  # whether the rider holds the handlebar now
        self._sampled = (0.0, 0.0)  # the time [s] and rate [rad/s] of the last torque frame
        self._torque_counter = 0
        self._plant = self._compiled_plant()
        self.frames_sent = 0
        self.torque_frames_sent = 0
        """The torque sensor's frames sent (not in :attr:`frames_sent`)."""
        self.frames_dropped = 0
        self.frames_late = 0
        """Status frames not sent because the rig's process was late (see
        :meth:`advance_to`)."""
        self.commands = 0
        self.bad_commands = 0
        self.on_frame: Callable[[int, bytes], object] | None = None
        """Called with every other frame the rig reads (the platform twin's CAN frames)."""

    def _frame_positions(self, codecs: HandlebarCodecs) -> None:
        """Where the status, command and torque frames' signals sit in their values."""
        st = codecs.status
        self._values = np.zeros(len(st.names))
        parts = ("angle", "current", "enabled", "counter", "drive_fault")
        self._p = {part: codecs.position(st, part) for part in parts}
        self._command = np.zeros(len(codecs.command.names))
        self._c_current = codecs.position(codecs.command, "current_command")
        self._c_enable = codecs.position(codecs.command, "enable")
        tq = codecs.torque
        self._torque_id = -1 if tq is None else tq.frame_id
        if tq is not None:
            self._torque_values = np.zeros(len(tq.names))
            self._t_torque = codecs.position(tq, "rider_torque")
            self._t_counter = codecs.position(tq, "counter")

    def _compiled_plant(self) -> BarPlant:
        """The handlebar's plant, its sub-steps compiled (or loaded from numba's cache) now
        for each type of profile a run's start passes (the idle one and the rider's; a
        read-only profile is another type): not on the run's first enabled command, where
        the compile would stall the status frames and trip the run's watchdog."""
        plant = BarPlant(
            plant_of(self.hb),
            self._a_i,
            self.settings.max_current,
            self.h,
            self.arms,
            self.hands_off,
        )
        for tau_r in (self._idle, self.rider_torque):
            _plant_steps(self.x.copy(), 0.0, plant, tau_r, 0, 1, 0.0)
        return plant

    @property
    def t(self) -> float:
        """The rig's time [s]."""
        return self.k * self.h

    def _receive(self) -> None:
        cmd = self.codecs.command
        for _ in range(256):
            frame = self.link.receive()
            if frame is None:
                return
            frame_id, data = frame
            if frame_id != cmd.frame_id:
                if self.on_frame is not None:
                    self.on_frame(frame_id, data)
                continue
            if not cmd.decode(data, self._command):
                self.bad_commands += 1
                continue
            self.commands += 1
            self.i_cmd = float(self._command[self._c_current])
            self.enabled = self._command[self._c_enable] > 0.5
            self._last_command = self.t
            if self.enabled and self._k_rider < 0:
                self._k_rider = self.k
                self._start_run()

    def _start_run(self) -> None:
        """A run starts (the first enabled command after the rider let go): the injected
        faults and the bus-off window count from now, each once per run."""
        self._t_run = self.t
        self._frozen = math.nan
        self._estop_sent = False
        self._bad_sent = False

    def advance_to(self, t: float, *, catch_up: bool = True) -> None:
        """Take the commands received, run the plant to time ``t`` [s], send what is due.

        ``catch_up`` False: the caller (a rig process ticking on the wall clock) is late by
        more than a status period. Of the status frames due meanwhile only the newest is
        sent: a drive sends on its own timer, never a backlog at once, which a loop paced by
        the frames could not answer one by one (the others counted in :attr:`frames_late`).
        """
        self._receive()
        s = self.settings
        if not self._started:  # the drive reports its state from power-on
            self._started = True
            if self.torque_sensor is not None and self._k_rider == 0 and self._policy is None:
                self._hands_at(self.rider_torque, 0, 0.0, 0.0)
            self._sample()
        while self.k * self.h < t - 1e-12:
            silent = self.t - self._last_command
            live = self.enabled and silent <= s.command_timeout
            if self._let_go and (not self.enabled or silent > _RUN_GONE):
                self._k_rider = -1  # the run has ended: the rider lets go
            # up to the next status sample, not beyond t: a command received by then is
            # carried from then, as a drive does
            n = min(self._sub - self.k % self._sub, max(1, math.ceil(t / self.h - self.k - 1e-9)))
            rider, k0 = self.rider_torque, self.k - self._k_rider
            t_rider = k0 * self.h
            if self._k_rider < 0:
                rider, k0, t_rider = self._idle, 0, -1.0
            elif self._policy is not None:
                if self.k % self._sub == 0:
                    self._held[0] = self._policy(k0 * self.h)  # once per status period
                rider, k0 = self._held, 0
            i_cmd = self.i_cmd if live else 0.0
            _plant_steps(self.x, i_cmd, self._plant, rider, k0, n, t_rider)
            if self.torque_sensor is not None:
                self._hands_at(rider, k0 + n, t_rider + n * self.h, t_rider)
            self.k += n
            if self.k % self._sub == 0:
                self._sample()
            if catch_up:
                self._deliver(min(self.t, t))
        self._deliver(t, newest_status=not catch_up)

    def _sample(self) -> None:
        s, f = self.settings, self.settings.faults
        t = self.t - self._t_run  # the faults' time: since the run's first enable
        theta, i = float(self.x[Bar.theta]), float(self.x[Bar.i_m])
        if s.encoder_bits > 0:
            q = 2.0 * math.pi / (1 << s.encoder_bits)
            theta = math.floor(theta / q + 0.5) * q
        if t >= f.frozen_encoder:
            if self._frozen != self._frozen:
                self._frozen = theta
            theta = self._frozen
        if t >= f.sign_flip:
            theta = -theta
        if s.current_noise > 0.0:
            i += s.current_noise * float(self.rng.standard_normal())
        if t >= f.current_offset_at:
            i += f.current_offset
        if t >= f.estop and not self._estop_sent:
            self._estop_sent = True
            es = self.codecs.estop
            values = np.zeros(len(es.names))
            values[self.codecs.position(es, "estop_signal")] = 1.0
            self._push(self.t, es.encode(values), es.frame_id)
        v = self._values
        v[self._p["angle"]] = theta
        v[self._p["current"]] = i
        v[self._p["enabled"]] = 1.0 if self.enabled else 0.0
        v[self._p["drive_fault"]] = 1.0 if t >= f.drive_fault else 0.0
        v[self._p["counter"]] = self._counter
        frame = self.codecs.status.encode(v)
        if t >= f.bad_checksum and not self._bad_sent:
            self._bad_sent = True
            frame = bytes([frame[0] ^ 0x5A]) + frame[1:]
        rng = self.rng
        if self._previous is not None and s.stale > 0.0 and rng.random() < s.stale:
            frame = self._previous  # the previous frame again, counter unchanged
        else:
            self._counter = (self._counter + 1) % 15  # E2E Profile 1's counter: 0 to 14
        self._previous = frame
        if s.burst_enter > 0.0:
            if self._burst:
                self._burst = rng.random() >= s.burst_leave
            else:
                self._burst = rng.random() < s.burst_enter
        if self._burst or (s.loss > 0.0 and rng.random() < s.loss):
            self.frames_dropped += 1
            return
        if s.bus_off_at <= t < s.bus_off_at + s.bus_off_duration:
            self.frames_dropped += 1
            return
        self._push(self.t, frame)
        if s.duplicate > 0.0 and rng.random() < s.duplicate:
            self._push(self.t, frame)
        if self.torque_sensor is not None:
            self._push(self.t, self._torque_frame(), self._torque_id)

    def _hands_at(self, rider: Array, k: int, t: float, t_rider: float) -> None:
        """Keep the rider's active torque now, for the torque sensor: ``rider[k]`` (the last
        value held), at the rider's time ``t`` [s] (``t_rider`` < 0: the rider does not hold
        the handlebar)."""
        self._holding = t_rider >= 0.0 and is_held(t, self.hands_off)
        self._hands = float(rider[min(k, rider.size - 1)]) if self._holding else 0.0

    def _torque_frame(self) -> bytes:
        """The torque sensor's frame now: the hands' torque on the handlebar (the arms'
        passive torque with the rate's change since the last torque frame for theta_h''),
        plus the sensor's offset and noise."""
        sensor, codec = self.torque_sensor, self.codecs.torque
        assert sensor is not None and codec is not None
        theta, omega = float(self.x[Bar.theta]), float(self.x[Bar.omega])
        torque = self._hands + sensor.offset
        t_last, omega_last = self._sampled
        if self._holding:
            a = self.arms
            accel = (omega - omega_last) / (self.t - t_last) if self.t > t_last else 0.0
            torque += hands_torque(theta, omega, accel, a.J_a, a.c_a, a.k_a, a.theta_hold)
        self._sampled = (self.t, omega)
        if sensor.noise > 0.0:
            torque += sensor.noise * float(self.rng.standard_normal())
        values = self._torque_values
        values[self._t_torque] = torque
        values[self._t_counter] = self._torque_counter
        self._torque_counter = (self._torque_counter + 1) % 16
        return codec.encode(values)

    def _push(self, t: float, frame: bytes, frame_id: int | None = None) -> None:
        s = self.settings
        delay = s.latency
        if s.jitter > 0.0:
            delay += s.jitter * float(self.rng.standard_normal())
        if frame_id is None:
            frame_id = self.codecs.status.frame_id
        due = max(t + max(delay, 0.0), self._last_due.get(frame_id, -math.inf))
        self._last_due[frame_id] = due
        heapq.heappush(self._queue, (due, self._seq, frame_id, frame))
        self._seq += 1

    def _deliver(self, t: float, *, newest_status: bool = False) -> None:
        """Send the frames due by ``t`` [s]; with ``newest_status``, of the status frames
        only the newest due (the others counted in :attr:`frames_late`)."""
        queue = self._queue
        status_id = self.codecs.status.frame_id
        newest = -math.inf
        if newest_status:
            newest = max(
                (due for due, _, frame_id, _ in queue if frame_id == status_id and due <= t),
                default=-math.inf,
            )
        torque_id = self._torque_id
        while queue and queue[0][0] <= t + 1e-12:
            due, _, frame_id, frame = heapq.heappop(queue)
            if frame_id == status_id and due < newest:
                self.frames_late += 1
                continue
            if self.link.send(frame_id, frame):
                if frame_id == torque_id:
                    self.torque_frames_sent += 1
                else:
                    self.frames_sent += 1


class VirtualRider:
    """The scenario's virtual rider at the rig, steering by the state that ``run`` publishes.

    The rider of :func:`motosim.sim.rider.rider_torque` (the same path, gains and limits as
    offline) looks at the virtual motorcycle's states in the newest datagram of the run's
    state stream (:mod:`motosim.rt.telemetry`); before the first one it holds 0 N*m. The
    scenario's probe (``world.rider_probe``) is added at the time it is asked for, once per
    status frame (held over a frame period where offline it changes every control period).

    Parameters
    ----------
    world : RigModel
        The scenario's world (its path, the rider's gain schedule and the probe).
    receiver : StateReceiver
        The state stream.
    names : tuple of str
        The signals of the stream's rows.
    rate : float
        The scenario's control rate [Hz], at which ``world.rider_probe`` is sampled (0 after
        its end: a rig serving a run longer than the scenario adds no torque there).
    """

    _STATES = ("v_y", "psi_dot", "phi_dot", "delta_dot", "phi", "delta", "F_yr", "F_yf")

    def __init__(
        self,
        world: RigModel,
        receiver: StateReceiver,
        names: tuple[str, ...] = STACK_SIGNALS,
        *,
        rate: float,
    ) -> None:
        self.check(world)
        if not (math.isfinite(rate) and rate > 0.0):
            raise MotosimError(f"rate = {rate!r} Hz: expected a positive control rate")
        self.world = world
        self.rate = float(rate)
        self.receiver = receiver
        self._states_at = [names.index(n) for n in self._STATES]
        self._at = {n: names.index(n) for n in ("v_x", "psi", "x", "y")}
        self._x_v = np.zeros(8)
        self._k_path = 0
        self.torque = 0.0
        self.lateral_error = 0.0
        # the compiled rider loaded now, not on the run's first state row (a stall of the
        # rig's frames at the run's start); nothing kept
        x, y, psi, _ = world.path[:, 0]  # the path's start: its rows x, y, heading, curvature
        self._torque(np.zeros(8), float(world.rider_speeds[0]), psi, x, y, 0)

    @staticmethod
    def check(world: RigModel) -> None:
        """Refuse a world whose rider this class cannot be (before a socket is opened for it).

        Raises
        ------
        MotosimError
            If the scenario's rider is a torque profile, or its motorcycle the multibody one
            (this rider steers Sharp 1971's).
        """
        if not world.virtual_rider:
            raise MotosimError("the scenario's rider is a torque profile, not a virtual rider")
        if world.motorcycle_inputs.shape[0] > 0:
            raise MotosimError(
                "the virtual rig's rider steers Sharp 1971 only; expected [motorcycle] model = "
                '"sharp1971" or [rider] kind = "torque" with model = "multibody"'
            )

    def __call__(self, t: float) -> float:
        """The rider's torque [N*m] ``t`` [s] after the rider took the handlebar: the path's,
        from the newest state row, plus the probe's at ``t``."""
        if self.receiver.poll():
            row, at = self.receiver.row, self._at
            for i, state_at in enumerate(self._states_at):
                self._x_v[i] = row[state_at]
            tau, self._k_path, self.lateral_error = self._torque(
                self._x_v, row[at["v_x"]], row[at["psi"]], row[at["x"]], row[at["y"]], self._k_path
            )
            self.torque = float(tau)
        probe = self.world.rider_probe
        k = max(math.floor(t * self.rate + 1e-9), 0)
        return self.torque + (float(probe[k]) if k < probe.size else 0.0)

    def _torque(
        self, x_v: Array, v_x: float, psi: float, x: float, y: float, k_path: int
    ) -> tuple[float, int, float]:
        """:func:`~motosim.sim.rider.rider_torque` of the scenario's rider at the states
        ``x_v``, speed ``v_x`` [m/s], heading ``psi`` [rad] and place ``x``, ``y`` [m], from
        the path's point ``k_path`` on: the torque [N*m], the next point, the lateral error."""
        w = self.world
        return rider_torque(
            x_v,
            v_x,
            psi,
            x,
            y,
            k_path,
            w.path,
            w.path_ds,
            w.rider_speeds,
            w.rider_K,
            w.rider_x_ss,
            w.rider_tau_ss,
            w.rider_preview,
            w.rider_max_torque,
        )


class LockstepLink(Link):
    """A link whose blocking receive lets simulated time pass (bus pacing in lock-step).

    ``receive(timeout)`` with a positive ``timeout`` polls ``link`` (the host's end of the
    bus) and, while nothing has come, advances ``clock`` (the one the rig listens on: the rig
    runs and sends meanwhile) by ``tick`` [s] > 0 at a time (the rig's plant step: frames are
    due on it) until a frame comes or ``timeout`` has passed: what a blocking receive on a
    real bus does, deterministically. ``send`` and a zero-timeout ``receive`` go straight to
    ``link``.
    """

    def __init__(self, link: Link, clock: SimulatedClock, tick: float) -> None:
        if not (math.isfinite(tick) and tick > 0.0):
            raise MotosimError(f"tick = {tick!r} s: expected a positive time")
        self.link = link
        self.clock = clock
        self.tick = float(tick)

    def send(self, frame_id: int, data: bytes) -> bool:
        """Send one frame on ``link``."""
        return self.link.send(frame_id, data)

    def receive(self, timeout: float = 0.0) -> tuple[int, bytes] | None:
        """The next frame, letting simulated time pass for up to ``timeout`` [s]."""
        frame = self.link.receive()
        if frame is not None or timeout <= 0.0:
            return frame
        clock = self.clock
        end = clock.now() + timeout
        while frame is None and clock.now() < end:
            clock.sleep_until(min(clock.now() + self.tick, end))
            frame = self.link.receive()
        return frame
