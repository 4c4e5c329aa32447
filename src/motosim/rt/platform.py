"""Platform output of the real-time loop: washout cueing, safety envelope, UDP datagrams.

Each control period :class:`PlatformOutput` takes the virtual motorcycle's states from the
stack's row (``v_x``, ``v_y``, ``psi_dot``, ``phi``) and runs one compiled step
(:func:`platform_step`) of

1. the longitudinal acceleration ``a_x = v_x' - v_y psi_dot`` (backward difference) and the
   suspension pitch of :func:`motosim.cueing.head.suspension_pitch`;
2. the classical washout of :mod:`motosim.cueing.washout` (platform roll, pitch, yaw and the
   visual-horizon roll);
3. the handlebar safety stage's envelope (:attr:`motosim.rt.safety.SafetyStage.envelope`):
   the commands are scaled by it, so the platform fades in and out with the handlebar's
   torque and goes back to neutral on a fault or a stop;
4. the limit manager of :mod:`motosim.cueing.limits` last, so that the angle, rate and
   acceleration limits hold whatever the envelope does (scaling a 20 deg roll down in 0.5 s
   alone would ask for 40 deg/s), and the return to neutral after a fault is a braked,
   rate-limited one rather than a jump.

The MPC cueing is not run here: its step does not fit a 1 kHz period.

Every ``send_every`` periods one command goes to the platform: a datagram of
:data:`PLATFORM_FRAME` (:class:`PlatformSender`, a non-blocking UDP socket) or a
``PF_COMMAND`` CAN frame of the shipped DBC on the run's bus (:class:`PlatformCanSender`:
roll, pitch, yaw at 1e-4 rad, the live flag, the alive counter and the CRC-8 of the
handlebar frames; see :func:`motosim.io.can.platform_codecs`). The datagram's layout,
little-endian, 48 bytes (``struct`` format ``<4sBBBBIdfffffff``):

====== ======= ========================================================================
offset type    field
====== ======= ========================================================================
0      4 bytes magic ``b"MSPF"``
4      uint8   version (1)
5      uint8   state of the safety stage (:class:`~motosim.rt.safety.State`)
6      uint8   fault (:class:`~motosim.rt.safety.Fault`)
7      uint8   flags: bit 0 set while the platform may move (fade-in, running, stopping)
8      uint32  sequence counter, +1 per datagram, wrapping at 2^32
12     float64 time since the first period [s]
20     float32 roll command [rad] (right side down positive)
24     float32 pitch command [rad] (nose up positive)
28     float32 yaw command [rad] (nose right positive)
32     float32 roll rate [rad/s]
36     float32 pitch rate [rad/s]
40     float32 yaw rate [rad/s]
44     float32 visual-horizon roll [rad] (for the image generator)
====== ======= ========================================================================

:class:`PlatformTwin` is the platform's side: it reads these datagrams (or the CAN frames,
:meth:`PlatformTwin.receive_frame`, answering with ``PF_STATUS``), checks them and
applies each axis' limits and first-order actuator bandwidth
(:func:`motosim.cueing.limits.actuator_response`), so that a test or ``motosim rig`` sees
what the platform would do.
"""

import math
import socket
import struct
from dataclasses import dataclass
from enum import IntEnum
from operator import itemgetter
from typing import NamedTuple, Protocol

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.cueing.filters import biquad_step, lowpass2
from motosim.cueing.limits import design_limits, limit_step
from motosim.cueing.platform import CueingConfig, Platform
from motosim.cueing.washout import (
    WASHOUT_OUTPUTS,
    WASHOUT_STATE_SIZE,
    design_washout,
    washout_step,
)
from motosim.errors import MotosimError
from motosim.io.can import Link, PlatformCodecs
from motosim.rt.safety import State

__all__ = [
    "PLATFORM_FRAME",
    "PLATFORM_MAGIC",
    "PLATFORM_VERSION",
    "Motion",
    "PlatformCanSender",
    "PlatformCueing",
    "PlatformFrame",
    "PlatformLink",
    "PlatformOutput",
    "PlatformSender",
    "PlatformTee",
    "PlatformTwin",
    "PlatformValue",
    "decode_platform",
    "encode_platform",
    "platform_step",
]

Array = NDArray[np.float64]

PLATFORM_FRAME = struct.Struct("<4sBBBBIdfffffff")
"""The datagram's layout (module docstring), 48 bytes."""
PLATFORM_MAGIC = b"MSPF"
PLATFORM_VERSION = 1
_LIVE = (State.FADE_IN, State.RUNNING, State.STOPPING)
_MAX_COUNTER_STEP = 7
"""The largest forward step of a ``PF_COMMAND`` frame's 4-bit counter the twin takes as new."""


@dataclass(frozen=True, slots=True)
class PlatformFrame:
    """One decoded platform datagram (the fields of the module docstring's table; ``live``
    the flag, ``angles`` roll, pitch, yaw [rad], ``rates`` theirs [rad/s])."""

    sequence: int
    t: float
    state: int
    fault: int
    live: bool
    angles: tuple[float, float, float]
    rates: tuple[float, float, float]
    horizon: float


def encode_platform(
    sequence: int, t: float, state: int, fault: int, live: bool, values: Array
) -> bytes:
    """Pack one datagram (the fields of the module docstring's table; ``sequence`` taken
    modulo 2^32; ``values`` roll, pitch, yaw [rad], their rates [rad/s], the horizon roll).

    Examples
    --------
    >>> frame = encode_platform(7, 1.5, 2, 0, True, np.array([0.1, 0, 0, 0.2, 0, 0, 0.3]))
    >>> len(frame), decode_platform(frame).sequence
    (48, 7)
    """
    return PLATFORM_FRAME.pack(
        PLATFORM_MAGIC,
        PLATFORM_VERSION,
        state,
        fault,
        1 if live else 0,
        sequence & 0xFFFFFFFF,
        t,
        *(float(v) for v in values[:7]),
    )


def decode_platform(data: bytes) -> PlatformFrame:
    """Unpack one datagram.

    Raises
    ------
    MotosimError
        If its size, magic or version is not the layout's.
    """
    if len(data) != PLATFORM_FRAME.size:
        raise MotosimError(
            f"platform datagram of {len(data)} bytes; expected {PLATFORM_FRAME.size}"
        )
    magic, version, state, fault, flags, seq, t, *v = PLATFORM_FRAME.unpack(data)
    if magic != PLATFORM_MAGIC or version != PLATFORM_VERSION:
        raise MotosimError(
            f"platform datagram magic {magic!r} version {version}; expected "
            f"{PLATFORM_MAGIC!r} version {PLATFORM_VERSION}"
        )
    return PlatformFrame(
        seq, t, state, fault, bool(flags & 1), (v[0], v[1], v[2]), (v[3], v[4], v[5]), v[6]
    )


class Motion(IntEnum):
    """What :attr:`PlatformCueing.motion` remembers between periods."""

    v_x = 0
    """The previous period's forward speed [m/s]."""
    started = 1
    """1 once a period has run (the forward acceleration needs two speeds)."""


class PlatformValue(IntEnum):
    """The platform's command, in the order of :func:`platform_step`'s ``out`` (and of the
    datagram's values)."""

    roll = 0
    pitch = 1
    yaw = 2
    roll_rate = 3
    pitch_rate = 4
    yaw_rate = 5
    horizon = 6


class PlatformCueing(NamedTuple):
    """What :func:`platform_step` steps.

    Coefficients: the suspension pitch section (``lowpass2`` of the rider's pitch model),
    the washout's, and the limit managers' rows (roll, pitch, yaw) with the period ``dt``
    [s]. States, zeros at rest and updated in place: ``motion`` (:class:`Motion`), the pitch
    section's two, the washout's and each axis's limit manager's (its output [rad] and
    rate [rad/s]). ``command`` is scratch: the washout's roll, pitch, yaw and horizon.
    """

    pitch: Array
    washout: Array
    limits: Array
    dt: float
    motion: Array
    pitch_state: Array
    washout_state: Array
    limit_state: Array
    command: Array


@njit(cache=True)
def platform_step(
    cueing: PlatformCueing,
    v_x: float,
    v_y: float,
    psi_dot: float,
    phi: float,
    envelope: float,
    out: Array,
) -> None:
    """One period of the platform cueing (module docstring, steps 1 to 4) from the
    motorcycle's forward and lateral speed [m/s], yaw rate [rad/s] and lean [rad] and the
    safety stage's envelope in [0, 1]: ``cueing``'s states updated in place, ``out``
    written with the command (:class:`PlatformValue`)."""
    motion, cmd = cueing.motion, cueing.command
    started = motion[Motion.started] > 0.0
    a_x = (v_x - motion[Motion.v_x]) / cueing.dt - v_y * psi_dot if started else 0.0
    motion[Motion.v_x] = v_x
    motion[Motion.started] = 1.0
    theta = biquad_step(cueing.pitch, 0, cueing.pitch_state, 0, a_x)
    washout_step(cueing.washout, cueing.washout_state, phi, theta, a_x, psi_dot, cmd)
    scale = min(1.0, max(0.0, envelope))
    for j, rate in _AXES:  # the angle and rate of roll, pitch and yaw
        axis = cueing.limit_state[j]
        out[j] = limit_step(cueing.limits[j], axis, scale * cmd[j], 0.0)
        out[rate] = axis[_LIMIT_RATE]
    # the horizon completes the roll the platform gives
    out[PlatformValue.horizon] = cmd[_HORIZON] + cmd[_ROLL] - out[PlatformValue.roll]


_AXES = (
    (int(PlatformValue.roll), int(PlatformValue.roll_rate)),
    (int(PlatformValue.pitch), int(PlatformValue.pitch_rate)),
    (int(PlatformValue.yaw), int(PlatformValue.yaw_rate)),
)
"""Each axis's angle and rate in :func:`platform_step`'s ``out`` (its row of the limits)."""
_LIMIT_RATE = 1
"""The rate [rad/s] in a limit manager's state (:func:`~motosim.cueing.limits.limit_step`)."""
_ROLL, _HORIZON = WASHOUT_OUTPUTS.index("phi_s"), WASHOUT_OUTPUTS.index("phi_vis")
"""The roll and the horizon in the washout's command
(:func:`~motosim.cueing.washout.washout_step`, :data:`~motosim.cueing.washout.WASHOUT_OUTPUTS`)."""


def _at_rest(cueing: PlatformCueing) -> PlatformCueing:
    """``cueing`` with fresh states, zeros (the platform at rest)."""
    return cueing._replace(
        motion=np.zeros(len(Motion)),
        pitch_state=np.zeros(2),
        washout_state=np.zeros(WASHOUT_STATE_SIZE),
        limit_state=np.zeros((3, 2)),
    )


class PlatformLink(Protocol):
    """Where :class:`PlatformOutput` sends its commands."""

    def send_command(
        self, sequence: int, t: float, state: int, fault: int, live: bool, values: Array
    ) -> None:
        """Send one command (arguments of :func:`encode_platform`)."""

    def close(self) -> None:
        """Release what the link holds."""


class PlatformSender:
    """Send platform datagrams to ``address`` over UDP; never blocks (a full buffer drops)."""

    def __init__(self, address: tuple[str, int]) -> None:
        self._address = address
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._socket.setblocking(False)
        self.dropped = 0

    def send(self, data: bytes) -> None:
        """Send one datagram."""
        try:
            self._socket.sendto(data, self._address)
        except OSError:  # buffer full, no route: the next one follows in a period
            self.dropped += 1

    def send_command(
        self, sequence: int, t: float, state: int, fault: int, live: bool, values: Array
    ) -> None:
        """Send one command as a datagram (:func:`encode_platform`)."""
        self.send(encode_platform(sequence, t, state, fault, live, values))

    def close(self) -> None:
        """Close the socket."""
        self._socket.close()


class PlatformCanSender:
    """Send platform commands as ``PF_COMMAND`` frames on a CAN link (the run's bus).

    Parameters
    ----------
    link : Link
        The link the run uses (:func:`motosim.io.can.open_link`); not closed by :meth:`close`.
    codecs : PlatformCodecs
        From :func:`motosim.io.can.platform_codecs`.
    """

    def __init__(self, link: Link, codecs: PlatformCodecs) -> None:
        self._link = link
        self.codecs = codecs
        self._values = np.zeros(len(codecs.command.names))
        self.dropped = 0

    def send_command(
        self, sequence: int, t: float, state: int, fault: int, live: bool, values: Array
    ) -> None:
        """Send one ``PF_COMMAND`` frame: the angles, the live flag and ``sequence`` mod 16."""
        c = self.codecs
        v = self._values
        v[c.command.counter_index] = sequence & 0xF
        v[c.live] = 1.0 if live else 0.0
        for j, i in enumerate(c.command_angles):
            v[i] = values[j]
        if not self._link.send(c.command.frame_id, c.command.encode(v)):
            self.dropped += 1

    def close(self) -> None:
        """Nothing to release (the run closes its link)."""


class PlatformTee:
    """Send each platform command through several links (UDP and CAN)."""

    def __init__(self, *links: PlatformLink) -> None:
        self.links = links

    def send_command(
        self, sequence: int, t: float, state: int, fault: int, live: bool, values: Array
    ) -> None:
        """Send one command through every link."""
        for link in self.links:
            link.send_command(sequence, t, state, fault, live, values)

    def close(self) -> None:
        """Close every link."""
        for link in self.links:
            link.close()


class PlatformOutput:
    """The platform stage of the real-time loop (module docstring).

    Parameters
    ----------
    config : CueingConfig
        Platform, rider's head model and washout tuning.
    dt : float
        Control period [s].
    names : tuple of str
        Names of the stack row's values; must hold ``v_x``, ``v_y``, ``psi_dot``, ``phi``.
    sender : PlatformSender or PlatformCanSender, optional
        Where the commands go; none: they are computed and kept only.
    send_every : int
        Periods per datagram (10 at 1 kHz: a 100 Hz platform stream).

    Raises
    ------
    MotosimError
        If a state is missing from ``names``, ``send_every`` < 1 or a washout corner is above
        0.2 of the Nyquist frequency.
    """

    def __init__(
        self,
        config: CueingConfig,
        dt: float,
        names: tuple[str, ...],
        *,
        sender: PlatformLink | None = None,
        send_every: int = 1,
    ) -> None:
        try:
            self._motion = itemgetter(*(names.index(n) for n in ("v_x", "v_y", "psi_dot", "phi")))
        except ValueError:
            raise MotosimError(
                f"platform output: stack row {names}; expected v_x, v_y, psi_dot and phi"
            ) from None
        if not (isinstance(send_every, int) and send_every >= 1):
            raise MotosimError(f"platform send_every = {send_every!r}; expected an integer >= 1")
        rider = config.rider
        limits = design_limits(config.platform, dt).coefficients()
        blank = np.zeros(0)
        self._cueing = _at_rest(
            PlatformCueing(
                lowpass2(rider.pitch_gain, rider.pitch_frequency, rider.pitch_damping, dt),
                design_washout(config.washout, dt).coefficients(),
                limits,
                float(dt),
                blank,
                blank,
                blank,
                blank,
                np.zeros(4),
            )
        )
        self.values = np.zeros(len(PlatformValue))
        """The last command (:class:`PlatformValue`)."""
        self.sender: PlatformLink | None = sender
        self.send_every = send_every
        self.sequence = 0
        at_rest = _at_rest(self._cueing)
        platform_step(at_rest, 0.0, 0.0, 0.0, 0.0, 0.0, np.zeros(len(PlatformValue)))  # compiled

    def step(
        self, k: int, t: float, row: Array | None, state: State, fault: int, envelope: float
    ) -> None:
        """Period ``k`` at ``t`` [s] since the first: the cueing from the stack's ``row``
        (neutral without one: before the drive's first status frame) and the safety stage's
        ``state``, ``fault`` and ``envelope``; every ``send_every`` periods, a command."""
        if row is None:
            v_x = v_y = psi_dot = phi = 0.0
            envelope = 0.0
        else:
            v_x, v_y, psi_dot, phi = self._motion(row)
        values = self.values
        platform_step(self._cueing, v_x, v_y, psi_dot, phi, envelope, values)
        if self.sender is not None and k % self.send_every == 0:
            live = state in _LIVE
            self.sender.send_command(self.sequence, t, state, fault, live, values)
            self.sequence += 1


class PlatformTwin:
    """The platform's side of the datagrams: limits and actuator bandwidth, as hardware.

    Each datagram's command passes through the limit manager of the platform (so a wrong
    command never exceeds the platform's limits, as a drive's own limits would ensure) and
    each axis then follows it through its first-order position loop at its bandwidth, both at
    ``dt``. Lost datagrams (sequence gaps), late ones (older than the last taken: delivered
    out of order, not used; after the watchdog's time without a command any sequence starts
    a new stream, the next run's) and bad ones are counted; the last good command is
    held for ``watchdog`` seconds, then the platform goes back to neutral (braked by its
    limits) until datagrams come again, as a platform controller must do when its host stops.

    Parameters
    ----------
    platform : Platform
        Limits and bandwidths.
    dt : float
        The twin's step [s].
    address : tuple of (str, int), optional
        Where to listen (UDP); none: feed it with :meth:`receive`.
    watchdog : float
        Time without a datagram after which the command is neutral [s].
    codecs : PlatformCodecs, optional
        The CAN frames (:func:`motosim.io.can.platform_codecs`), for :meth:`receive_frame`
        and :meth:`status_frame`.
    """

    def __init__(
        self,
        platform: Platform,
        dt: float,
        address: tuple[str, int] | None = None,
        *,
        watchdog: float = 0.1,
        codecs: PlatformCodecs | None = None,
    ) -> None:
        self.codecs = codecs
        self._frame = np.zeros(0 if codecs is None else len(codecs.command.names))
        self._status = np.zeros(0 if codecs is None else len(codecs.status.names))
        self._counter = -1
        self._status_counter = 0
        self._limits = design_limits(platform, dt).coefficients()
        self._alpha = np.array([math.exp(-axis.bandwidth * dt) for axis in platform.axes])
        self._states = np.zeros((3, 2))
        self.dt = dt
        self.command = np.zeros(3)
        """The last received roll, pitch, yaw command [rad]."""
        self.achieved = np.zeros(3)
        """The platform's angles [rad]."""
        self.t = 0.0
        self.watchdog = watchdog
        self.timeouts = 0
        """Times the watchdog sent the platform to neutral."""
        self._received = -math.inf
        self.frames = 0
        self.lost = 0
        self.late = 0
        self.bad = 0
        self.last: PlatformFrame | None = None
        self._socket: socket.socket | None = None
        if address is not None:
            self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._socket.bind(address)
            self._socket.setblocking(False)

    @property
    def address(self) -> tuple[str, int] | None:
        """The bound (host, port), or None."""
        if self._socket is None:
            return None
        host, port = self._socket.getsockname()[:2]
        return str(host), int(port)

    def _stream_ended(self) -> bool:
        """No command for longer than the watchdog: the next one may start a new stream."""
        return self._received > -math.inf and self.t - self._received > self.watchdog

    def receive(self, data: bytes) -> None:
        """Take one datagram."""
        try:
            frame = decode_platform(data)
        except MotosimError:
            self.bad += 1
            return
        values = (*frame.angles, *frame.rates, frame.horizon)
        if not all(math.isfinite(v) for v in values):
            self.bad += 1
            return
        if self._stream_ended():
            self.last = None  # a new sender (the next run) starts its own sequence
        if self.last is not None:
            step = (frame.sequence - self.last.sequence) & 0xFFFFFFFF
            if step == 0 or step >= 1 << 31:  # the same or an older datagram
                self.late += 1
                return
            self.lost += step - 1
        self.frames += 1
        self._received = self.t
        self.last = frame
        self.command[:] = frame.angles if frame.live else (0.0, 0.0, 0.0)

    def receive_frame(self, frame_id: int, data: bytes) -> bool:
        """Take one CAN frame; False if it is not a ``PF_COMMAND`` (or there are no codecs).

        A frame with a wrong length or checksum, or non-finite angles, counts as bad; a
        counter gap of up to 7 counts the frames lost (modulo 16); a counter that did not move
        or went back (more than 7 ahead) counts as late and is not used.
        """
        if self.codecs is None or frame_id != self.codecs.command.frame_id:
            return False
        c = self.codecs
        v = self._frame
        if not c.command.decode(data, v) or not np.all(np.isfinite(v)):
            self.bad += 1
            return True
        counter = int(v[c.command.counter_index])
        if self._stream_ended():
            self._counter = -1
        if self._counter >= 0:
            step = (counter - self._counter) & 0xF
            if step == 0 or step > _MAX_COUNTER_STEP:
                self.late += 1
                return True
            self.lost += step - 1
        self._counter = counter
        self.frames += 1
        self._received = self.t
        live = v[c.live] > 0.5
        for j, i in enumerate(c.command_angles):
            self.command[j] = v[i] if live else 0.0
        return True

    def status_frame(self) -> tuple[int, bytes]:
        """``(frame_id, data)`` of a ``PF_STATUS`` frame with the achieved angles.

        Raises
        ------
        MotosimError
            If the twin has no codecs.
        """
        if self.codecs is None:
            raise MotosimError("platform twin without CAN codecs; expected platform_codecs()")
        c = self.codecs
        v = self._status
        v[c.status.counter_index] = self._status_counter
        self._status_counter = (self._status_counter + 1) & 0xF
        v[c.watchdog] = 1.0 if self._stream_ended() else 0.0
        for j, i in enumerate(c.status_angles):
            v[i] = self.achieved[j]
        return c.status.frame_id, c.status.encode(v)

    def _poll(self) -> None:
        if self._socket is None:
            return
        for _ in range(256):
            try:
                data = self._socket.recv(256)
            except BlockingIOError:
                return
            self.receive(data)

    def step(self) -> Array:
        """Read waiting datagrams, advance one ``dt``; the achieved angles [rad]."""
        self._poll()
        if self._stream_ended():
            if np.any(self.command):
                self.timeouts += 1
            self.command[:] = 0.0
        for j in range(3):
            target = limit_step(self._limits[j], self._states[j], float(self.command[j]), 0.0)
            a = self._alpha[j]
            self.achieved[j] = a * self.achieved[j] + (1.0 - a) * target
        self.t += self.dt
        return self.achieved

    def advance_to(self, t: float) -> None:
        """Step until the twin's time reaches ``t`` [s]."""
        while self.t + 0.5 * self.dt <= t:
            self.step()

    def close(self) -> None:
        """Close the socket."""
        if self._socket is not None:
            self._socket.close()
