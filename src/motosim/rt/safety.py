"""The safety stage: the last stage before the bus, always on.

Software limits are a second line of defence. The real safety function of a motorised
handlebar is the drive's hardware safe torque off (STO, IEC 61800-5-2; stop category 0 of
IEC 60204-1) wired to an emergency-stop button; the drive must also stop the torque on its
own when command frames stop coming. What this stage adds, after the stack has computed its
current command and before the command is encoded (the protections of force-feedback wheel
firmware such as OpenFFBoard's ``Axis.cpp`` and of Simucube's drives):

- a current clamp (``max_current`` [A]) and a slew-rate limit (``max_slew`` [A/s]);
- soft end stops: beyond ``soft_stop`` [rad] the command pushing further out is dropped and
  a restoring spring ``end_stop_gain`` [A/rad] is added; beyond ``hard_stop`` a fault;
- a speed limiter that only ever reduces what pushes the handlebar faster beyond
  ``max_speed`` [rad/s] (to zero ``speed_band`` [rad/s] above it), the end stops' spring
  included, never adds torque;
- a fade-in over ``fade_in`` [s] (0.5 s) on every enable, and a fade-out on a stop request
  (IDLE once the command sent is zero: the slew-rate limit may take longer than the fade);
- a communication watchdog: no valid status frame for ``watchdog_periods`` periods (the
  loop's deadlines, those it skipped when late included) -> zero command and a latched
  fault; a status frame is valid when its checksum is right and the check of AUTOSAR E2E
  Profile 1 (:mod:`motosim.rt.e2e`, settings :data:`STATUS_E2E`) gives it ``INITIAL``,
  ``OK`` or ``OKSOMELOST`` (a repeated, older or out-of-sequence frame does not feed the
  watchdog and is not used);
- guards: a NaN or inf measurement, estimate or command, a bad checksum, a fault flag of the
  drive, an emergency stop (from a CAN frame or the keyboard) -> zero command at once and a
  latched fault with its reason and time;
- hands-off detection: while the estimated rider torque stays below ``hands_off_torque``
  [N*m] for ``hands_off_time`` [s], the stack's command is scaled by ``hands_off_gain``
  (before the limits: the end stops' spring is not scaled; a period without an estimate
  keeps the flag as it is); once the rider's torque is back, the command is whole again at
  once, as fast as the slew-rate limit lets it (a rider who starts a manoeuvre needs the
  stack's feedback at once: the realtime guide, "Safety");
- with a torque sensor (the runner's, :mod:`motosim.rt.fused`): no valid ``HB_TORQUE`` frame
  with a new alive counter for as long as the watchdog waits -> ``TORQUE_SENSOR``, and a
  wrong checksum -> ``CHECKSUM``;
- a frozen-sensor monitor (given the handlebar's parameters): the angle has not changed
  while the motor torque has moved so far from its value at the angle's last change that a
  free handlebar would have turned by more than ``frozen_angle`` [rad] -> a latched fault
  (see :class:`SafetyStage`, Notes).

Each period the stack's command goes, in this order, through the hands-off gain, the end
stops, the speed limiter, the clamp, the fade and the slew-rate limit: no later stage adds
what an earlier one took away (the slew-rate limit only delays it: it holds a decrease back
as it holds an increase, by at most ``max_current / max_slew`` seconds).
A fault gives a zero command in the same period it is detected, without slew limiting, and
stays latched until :meth:`SafetyStage.clear`; enabling again starts a new fade-in. The stage
keeps its state in a numba structref stepped by compiled functions (:func:`safety_step` and
the others), which the fused period of :mod:`motosim.rt.fused` calls as they are; it
allocates nothing per period.
"""

import math
from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass, fields
from enum import IntEnum
from typing import Any, NamedTuple, cast

import numpy as np
from numba import njit
from numba.experimental import structref

from motosim.errors import MotosimError
from motosim.params.checks import check_number, short_repr
from motosim.params.handlebar import HandlebarParameters
from motosim.rt.e2e import E2EConfig, E2EState, E2EStatus, FieldsStruct, e2e_check, e2e_restart

__all__ = [
    "SAFETY_RANGES",
    "STATUS_E2E",
    "Fault",
    "SafetyLimits",
    "SafetyStage",
    "State",
    "fault_reason",
]


class State(IntEnum):
    """The stage's state (the ``STATE`` of the heartbeat frame)."""

    IDLE = 0
    FADE_IN = 1
    RUNNING = 2
    FAULT = 3
    STOPPING = 4


class Fault(IntEnum):
    """Why the torque was stopped (the ``FAULT`` of the heartbeat frame)."""

    NONE = 0
    WATCHDOG = 1
    NON_FINITE = 2
    CHECKSUM = 3
    ESTOP_CAN = 4
    ESTOP_KEY = 5
    DRIVE_FAULT = 6
    END_STOP = 7
    NO_DRIVE = 8
    FROZEN_SENSOR = 9
    TORQUE_SENSOR = 10


_REASONS = {
    Fault.NONE: "no fault",
    Fault.WATCHDOG: "communication watchdog: no valid status frame for {n} periods",
    Fault.NON_FINITE: "NaN or inf in a measurement, the estimate or the command",
    Fault.CHECKSUM: "a frame with a wrong checksum",
    Fault.ESTOP_CAN: "emergency stop (CAN frame)",
    Fault.ESTOP_KEY: "emergency stop (keyboard)",
    Fault.DRIVE_FAULT: "the drive reports a fault",
    Fault.END_STOP: "handlebar angle beyond the hard end stop",
    Fault.NO_DRIVE: "no valid status frame from the drive since the start",
    Fault.FROZEN_SENSOR: "frozen angle sensor: the angle stood still while the motor torque "
    "would have turned a free handlebar",
    Fault.TORQUE_SENSOR: "torque sensor: no valid HB_TORQUE frame for {n} status periods",
}


def fault_reason(fault: int, *, watchdog_periods: int) -> str:
    """A fault code's reason, in words.

    Examples
    --------
    >>> fault_reason(Fault.WATCHDOG, watchdog_periods=3)
    'communication watchdog: no valid status frame for 3 periods'
    """
    return _REASONS[Fault(fault)].format(n=watchdog_periods)


SAFETY_RANGES: dict[str, tuple[float, float, str]] = {
    "max_current": (0.01, 1000.0, "A"),
    "max_slew": (0.1, 1e9, "A/s"),
    "max_speed": (0.01, 1e4, "rad/s"),
    "speed_band": (0.01, 1e4, "rad/s"),
    "soft_stop": (0.01, 100.0, "rad"),
    "hard_stop": (0.01, 100.0, "rad"),
    "end_stop_gain": (0.0, 1e4, "A/rad"),
    "hands_off_torque": (0.0, 100.0, "N*m"),
    "hands_off_time": (0.001, 3600.0, "s"),
    "hands_off_gain": (0.0, 1.0, ""),
    "fade_in": (0.001, 60.0, "s"),
    "watchdog_periods": (1, 10_000, ""),
    "frozen_angle": (0.001, 10.0, "rad"),
}
"""Admitted interval (low, high, SI unit) of each safety limit. The lower bounds are far
below any usable limit (10 mA, 0.1 A/s, 10 mrad/s, 1 ms): a smaller positive value is a typo
or a unit slip and would make the stage trip or stall at once; the upper bounds are far beyond
any handlebar drive, so that a test may set a limit out of reach (1000 A, an end stop beyond a
full turn), and refuse only what is no number of a drive (1e300, an hour of fade)."""


@dataclass(frozen=True, slots=True)
class SafetyLimits:
    """The limits of the safety stage (see the module docstring for each one's role).

    Parameters
    ----------
    max_current : float
        Current clamp [A], > 0.
    max_slew : float
        Largest change of the command [A/s], > 0.
    max_speed, speed_band : float
        Handlebar rate where the speed limiter starts [rad/s] and the excess over it where
        the command has gone to zero [rad/s], both > 0.
    soft_stop, hard_stop : float
        Angles [rad] of the soft end stop and of the fault, 0 < soft_stop < hard_stop.
    end_stop_gain : float
        Restoring current per radian beyond the soft stop [A/rad], >= 0.
    hands_off_torque, hands_off_time, hands_off_gain : float
        Rider torque below which nobody holds the handlebar [N*m] (>= 0; 0 disables), the
        time it must last [s] (> 0) and the command's scale meanwhile, in [0, 1].
    fade_in : float
        Ramp of the command on enable and on stop [s], > 0.
    watchdog_periods : int
        Periods without a valid status frame that trip the watchdog, >= 1.
    frozen_angle : float
        The turn of a free handlebar [rad], predicted from the change of the motor torque
        since the measured angle last changed, that trips ``FROZEN_SENSOR`` while the angle
        stands still (0.05 rad, about 130 counts of a 14-bit encoder), > 0.
    """

    max_current: float
    max_slew: float
    max_speed: float
    speed_band: float
    soft_stop: float
    hard_stop: float
    end_stop_gain: float
    hands_off_torque: float
    hands_off_time: float
    hands_off_gain: float
    fade_in: float = 0.5
    watchdog_periods: int = 3
    frozen_angle: float = 0.05

    def __post_init__(self) -> None:
        for name, (low, high, unit) in SAFETY_RANGES.items():
            value = getattr(self, name)
            if name == "watchdog_periods":
                if isinstance(value, bool) or not (isinstance(value, int) and low <= value <= high):
                    raise MotosimError(
                        f"safety watchdog_periods = {short_repr(value)}; expected an integer "
                        f"from {low:g} to {high:g}"
                    )
                continue
            check_number(value, where=f"safety {name}", lower=low, upper=high, unit=unit)
        if not self.hard_stop > self.soft_stop:
            raise MotosimError(
                f"safety hard_stop = {self.hard_stop!r} rad; expected more than soft_stop "
                f"= {self.soft_stop!r} rad"
            )


STATUS_E2E = E2EConfig(
    max_delta_counter_init=1, max_no_new_or_repeated_data=13, sync_counter_init=0
)
"""Profile 1's settings of the status frame's check, called once per frame period (those
without a frame at the next frame): a step of the counter up to one more than the frame
periods since the last frame taken is new (the periods without a frame are its lost frames);
after 14 frame periods or more without a new counter (where the 15 values may have come
round) the first frame is ``SYNC``, not used, and the next one step on is ``OK``; an older
frame is ``WRONGSEQUENCE`` and leaves the last counter as it is (no synchronisation to
it)."""

# --- the compiled stage ---------------------------------------------------------------
# Its state (a numba structref) and limits (a named tuple) are stepped by the same functions
# from :class:`SafetyStage` and from the fused period (numba takes an IntEnum's members as
# constants).


_LIMITS = tuple(f.name for f in fields(SafetyLimits) if f.name != "watchdog_periods")
"""The limits the compiled stage reads as they are."""
SafetyParams: Any = cast(
    Any,
    namedtuple(
        "SafetyParams",
        (*_LIMITS, "watchdog", "dt", "per_frame", "monitor", "torque_per_amp", "band", "beta"),
    ),
)
SafetyParams.__doc__ = """The limits as the compiled stage reads them (:func:`safety_params`):
the fields of :class:`SafetyLimits` but ``watchdog_periods``, then the control periods
without a valid status frame that trip the watchdog, the control period [s], the control
periods per status frame, whether the frozen-sensor monitor is on, and its handlebar's
N k_t [N*m/A], twice its dry friction (the monitor's dead band) [N*m] and beta_eq
[N*m*s/rad]."""


def safety_params(
    limits: SafetyLimits, dt: float, periods_per_frame: int, handlebar: HandlebarParameters | None
) -> Any:
    """The :data:`SafetyParams` of ``limits``, the period ``dt`` [s], ``periods_per_frame``
    and the frozen-sensor monitor's ``handlebar`` (None: the monitor off)."""
    monitor = (
        (0.0, 0.0, 0.0)
        if handlebar is None
        else (float(handlebar.torque_per_amp), 2.0 * handlebar.beta_s, float(handlebar.beta_eq))
    )
    derived = (
        float(limits.watchdog_periods * periods_per_frame),
        float(dt),
        float(periods_per_frame),
        handlebar is not None,
        *monitor,
    )
    return SafetyParams(*(float(getattr(limits, name)) for name in _LIMITS), *derived)


@structref.register
class SafetyStateType(FieldsStruct):
    """numba's type of :class:`SafetyState`."""


class SafetySnapshot(NamedTuple):
    """The fields of a :class:`SafetyState` at one instant."""

    state: int
    fault: int
    fault_time: float
    t: float
    envelope: float
    last: float
    heard: float
    fresh: bool
    missing: float
    quiet: float
    hands_off: bool
    ref_theta: float
    ref_torque: float
    free: float
    lost: int
    stale: int


class SafetyState(structref.StructRefProxy):
    """The stage's state, shared by :class:`SafetyStage` and compiled code.

    Fields: ``state`` and ``fault`` (codes of :class:`State` and :class:`Fault`),
    ``fault_time`` [s] (NaN without a fault), ``t`` the stage's time [s], ``envelope`` the
    fade's scale [-], ``last`` the last command sent [A], ``heard`` the time of the last
    status frame checked [s] (NaN before the first), ``fresh`` whether a valid frame came
    this period,
    ``missing`` periods without one, ``quiet`` the time the rider's torque has stayed low
    [s], ``hands_off`` its flag, ``ref_theta`` [rad] and ``ref_torque`` [N*m] the
    frozen-sensor monitor's references and ``free`` its free turn [rad], ``lost`` and
    ``stale`` the frames lost and refused, and ``e2e`` the status frame's Profile 1 check
    (:class:`motosim.rt.e2e.E2EState`). Python reads them but ``e2e`` through
    :func:`safety_snapshot`.
    """

    def __new__(cls) -> "SafetyState":
        made: SafetyState = structref.StructRefProxy.__new__(  # type: ignore[no-untyped-call]
            cls,
            int(State.IDLE),
            int(Fault.NONE),
            math.nan,
            0.0,
            0.0,
            0.0,
            math.nan,
            False,
            0.0,
            0.0,
            False,
            math.nan,
            0.0,
            0.0,
            0,
            0,
            E2EState(STATUS_E2E),
        )
        return made


structref.define_proxy(SafetyState, SafetyStateType, [*SafetySnapshot._fields, "e2e"])  # type: ignore[no-untyped-call]


@njit(cache=True)
def safety_snapshot(s: Any) -> SafetySnapshot:
    """The stage's state fields now, for Python."""
    return SafetySnapshot(
        s.state,
        s.fault,
        s.fault_time,
        s.t,
        s.envelope,
        s.last,
        s.heard,
        s.fresh,
        s.missing,
        s.quiet,
        s.hands_off,
        s.ref_theta,
        s.ref_torque,
        s.free,
        s.lost,
        s.stale,
    )


@njit(cache=True)
def safety_brief(s: Any) -> tuple[int, int, float]:
    """The stage's state and fault codes and its fade envelope [-]."""
    return s.state, s.fault, s.envelope


@njit(cache=True)
def safety_clear(s: Any) -> None:
    """:meth:`SafetyStage.clear` on the state."""
    s.fault = Fault.NONE
    s.fault_time = math.nan
    s.state = State.IDLE
    s.missing = 0.0
    s.heard = math.nan
    e2e_restart(s.e2e)
    s.ref_theta = math.nan
    s.free = 0.0
    s.quiet = 0.0
    s.hands_off = False


@njit(cache=True)
def safety_trip(s: Any, fault: int) -> None:
    """Latch ``fault`` (a :class:`Fault` code) now: the next step returns 0."""
    if fault == Fault.NONE:
        return
    if s.fault == Fault.NONE:
        s.fault = fault
        s.fault_time = s.t
    s.state = State.FAULT
    s.envelope = 0.0
    s.last = 0.0


@njit(cache=True)
def _periods_since(s: Any, p: Any, now: float) -> float:
    """Periods since the last step at time ``now`` [s], at least 1 (1 if ``now`` is NaN): the
    deadlines a late loop skipped passed without a status frame too."""
    if now != now:
        return 1.0
    return max(1.0, float(math.floor((now - s.t) / p.dt + 0.5)))


@njit(cache=True)
def safety_status_frame(
    s: Any, p: Any, checksum_ok: bool, counter: float, drive_fault: bool, now: float
) -> bool:
    """:meth:`SafetyStage.status_frame` on the state and limits (``now`` NaN: the
    frame is taken as one period after the last step)."""
    t = s.t + p.dt if now != now else now
    if s.heard == s.heard:  # the frame periods since the last frame, each a receive cycle
        cycles = math.floor((t - s.heard) / (p.dt * p.per_frame) + 0.5)
        for _ in range(min(cycles - 1, 15)):  # those without a frame (15 saturate the check)
            e2e_check(s.e2e, False, True, 0)
    s.heard = t
    status = e2e_check(s.e2e, True, checksum_ok, int(counter))
    if not checksum_ok:
        safety_trip(s, Fault.CHECKSUM)
        return False
    if drive_fault:  # whatever its counter: a drive that reports a fault is believed
        safety_trip(s, Fault.DRIVE_FAULT)
    if status == E2EStatus.OK or status == E2EStatus.OKSOMELOST or status == E2EStatus.SYNC:
        s.lost += s.e2e.lost_data
    elif status != E2EStatus.INITIAL:  # repeated, older, or a counter of 15
        s.stale += 1
        return False
    if status == E2EStatus.SYNC:  # the counter taken up again: its data not yet
        return False
    s.fresh = True
    return True


@njit(cache=True)
def safety_estop_frame(s: Any, checksum_ok: bool, pressed: bool) -> None:
    """:meth:`SafetyStage.estop_frame` on the state."""
    if not checksum_ok:
        safety_trip(s, Fault.CHECKSUM)
    elif pressed:
        safety_trip(s, Fault.ESTOP_CAN)


@njit(cache=True)
def _frozen_monitor(s: Any, p: Any, theta: float) -> None:
    """The frozen-sensor monitor of one period (see :class:`SafetyStage`, Notes)."""
    torque = p.torque_per_amp * s.last
    state = s.state
    if theta != s.ref_theta or state == State.IDLE or state == State.STOPPING:
        s.ref_theta = theta
        s.ref_torque = torque
        s.free = 0.0
        return
    drive = abs(torque - s.ref_torque) - p.band
    if drive > 0.0:
        s.free += drive / p.beta * p.dt
        if s.free > p.frozen_angle:
            safety_trip(s, Fault.FROZEN_SENSOR)


@njit(cache=True)
def _watch(
    s: Any, p: Any, periods: float, command: float, theta: float, omega: float, tau_hat: float
) -> None:
    """The period's checks, tripping a fault: the watchdog (``periods`` since the last
    step), a value that is not finite, the hard end stop and the frozen-sensor monitor."""
    if s.fresh:
        s.missing = 0.0
        s.fresh = False
    else:
        s.missing += periods
        if s.missing >= p.watchdog and s.state != State.IDLE:
            safety_trip(s, Fault.WATCHDOG)
    finite = math.isfinite(command) and math.isfinite(theta) and math.isfinite(omega)
    if not finite or math.isinf(tau_hat):
        safety_trip(s, Fault.NON_FINITE)
    elif abs(theta) > p.hard_stop:
        safety_trip(s, Fault.END_STOP)
    elif p.monitor:
        _frozen_monitor(s, p, theta)


@njit(cache=True)
def _limited(s: Any, p: Any, command: float, theta: float, omega: float, tau_hat: float) -> float:
    """The stack's command [A] after the hands-off gain, the soft end stops and the speed
    limiter."""
    # hands-off: reduce the stack's command while nobody holds the handlebar (the flag
    # kept as it is without an estimate); not the end stops' spring, added after
    if p.hands_off_torque > 0.0 and tau_hat == tau_hat:
        if abs(tau_hat) < p.hands_off_torque:
            s.quiet += p.dt
            s.hands_off = s.quiet >= p.hands_off_time
        else:
            s.quiet = 0.0
            s.hands_off = False
    i = command * p.hands_off_gain if s.hands_off else command
    # soft end stops
    over = abs(theta) - p.soft_stop
    if over > 0.0:
        out = 1.0 if theta > 0.0 else -1.0
        if i * out > 0.0:
            i = 0.0
        i -= out * p.end_stop_gain * over
    # speed limiter: only reduces what pushes the handlebar faster (the end stops' spring
    # included: it must not speed up a handlebar already too fast on its way back)
    excess = abs(omega) - p.max_speed
    if excess > 0.0 and i * omega > 0.0:
        i *= max(0.0, 1.0 - excess / p.speed_band)
    return i


@njit(cache=True)
def safety_step(
    s: Any, p: Any, command: float, theta: float, omega: float, tau_hat: float, now: float
) -> float:
    """:meth:`SafetyStage.step` on the state (``now`` NaN: the stage counts its own
    periods; else the periods since the last step are counted from ``now``, so that the
    deadlines a late loop skipped count for the watchdog)."""
    periods = _periods_since(s, p, now)
    s.t = s.t + p.dt if now != now else now
    _watch(s, p, periods, command, theta, omega, tau_hat)
    state = s.state
    if state == State.FAULT or state == State.IDLE:
        s.last = 0.0
        s.envelope = 0.0
        return 0.0
    i = _limited(s, p, command, theta, omega, tau_hat)
    # clamp, fade, slew
    i = min(max(i, -p.max_current), p.max_current)
    s.envelope = _ramped_envelope(s, p)
    i *= s.envelope
    step = p.max_slew * p.dt
    last = s.last
    i = min(max(i, last - step), last + step)
    s.last = i
    if state == State.STOPPING and s.envelope == 0.0 and i == 0.0:  # faded out, sent 0
        s.state = State.IDLE
    elif state == State.FADE_IN and s.envelope >= 1.0:  # faded in
        s.state = State.RUNNING
    return float(i)


class SafetyStage:
    """The safety stage of one handlebar, stepped once per control period.

    Each period: :meth:`status_frame` for every status frame received (and
    :meth:`estop_frame` for every E-stop frame), then :meth:`step` with the stack's command;
    the value it returns is the only one to send.

    Parameters
    ----------
    limits : SafetyLimits
        The limits.
    dt : float
        The control period [s], > 0.
    periods_per_frame : int
        Control periods per status frame (the loop may run faster than the drive reports):
        the watchdog waits ``watchdog_periods`` frame periods.
    handlebar : HandlebarParameters, optional
        The (nominal) handlebar, for the frozen-sensor monitor; without it the monitor is off.

    Notes
    -----
    The frozen-sensor monitor tells a frozen angle sensor from a rider who holds the
    handlebar still against the motor (a steady turn, legitimate): a still angle under a
    large *steady* current proves nothing, but no rider holds the handlebar to one encoder
    count while the motor torque *changes* a lot (an arm is a spring of at most a few
    hundred N*m/rad). The monitor keeps the motor torque ``tau_0 = N k_t i`` of the period
    the measured angle last changed and, while it stands still, integrates the turn of a
    *free* handlebar of eq. (5) driven by the change of torque since then, quasi-statically
    (the inertia's lag ``J_eq / beta_eq`` neglected), with twice the dry friction as a dead
    band (the still handlebar may sit anywhere in the friction band)::

        d = |N k_t i - tau_0|,   theta_free += max(0, d - 2 beta_s) / beta_eq * dt

    and trips ``FROZEN_SENSOR`` when ``theta_free`` exceeds ``frozen_angle``. The current is
    the one sent the period before (what the drive held meanwhile). Any change of the
    measured angle starts it afresh, and so does a stop's fade-out (the torque is going to
    zero: a frozen sensor can do no harm then, and a rider easing off as it fades need not
    move the handlebar). The free handlebar is an upper bound of the turn of a
    held one: a rider holding still against a change ``d`` needs a stiffness of ``d`` per
    encoder count (9000 N*m/rad for 3.5 N*m and a 14-bit encoder). A measured angle
    moving the wrong way (a sign flip) is not detected: a rider overpowering the motor
    legitimately turns the handlebar against its torque.

    Examples
    --------
    >>> lim = SafetyLimits(max_current=10.0, max_slew=1000.0, max_speed=10.0, speed_band=5.0,
    ...                    soft_stop=0.5, hard_stop=0.7, end_stop_gain=0.0,
    ...                    hands_off_torque=0.0, hands_off_time=1.0, hands_off_gain=1.0)
    >>> stage = SafetyStage(lim, dt=0.01)
    >>> stage.enable()
    >>> out = []
    >>> for k in range(60):
    ...     _ = stage.status_frame(checksum_ok=True, counter=k % 15, drive_fault=False)
    ...     out.append(stage.step(5.0, theta=0.0, omega=0.0, tau_hat=1.0))
    >>> round(out[24], 3), out[-1], stage.state.name    # half-way through the 0.5 s fade-in
    (2.5, 5.0, 'RUNNING')
    >>> stage.step(5.0, theta=0.0, omega=0.0, tau_hat=1.0)    # one period without status
    5.0
    >>> stage.step(5.0, theta=0.0, omega=0.0, tau_hat=1.0)
    5.0
    >>> stage.step(5.0, theta=0.0, omega=0.0, tau_hat=1.0), stage.describe()
    (0.0, 'communication watchdog: no valid status frame for 3 periods (t = 0.630 s)')
    """

    __slots__ = ("_brief", "_p", "_s", "_snapshot", "dt", "limits")

    def __init__(
        self,
        limits: SafetyLimits,
        *,
        dt: float,
        periods_per_frame: int = 1,
        handlebar: HandlebarParameters | None = None,
    ) -> None:
        if not (math.isfinite(dt) and dt > 0.0):
            raise MotosimError(f"dt = {dt!r} s: expected a positive period")
        if (
            isinstance(periods_per_frame, bool)
            or not isinstance(periods_per_frame, int | np.integer)
            or periods_per_frame < 1
        ):  # a NaN would have made the watchdog's count never reached
            raise MotosimError(
                f"periods_per_frame = {periods_per_frame!r}: expected an integer >= 1"
            )
        self.limits = limits
        self.dt = float(dt)
        self._s = SafetyState()
        self._p = safety_params(limits, self.dt, int(periods_per_frame), handlebar)
        from motosim.rt.stack import compiled  # the stack's numba, loaded with the stage

        self._brief: Callable[..., tuple[int, int, float]] = compiled(safety_brief, self._s)
        self._snapshot: Callable[[SafetyState], SafetySnapshot] = compiled(safety_snapshot, self._s)

    @property
    def compiled_parts(self) -> tuple[SafetyState, Any]:
        """The state and limits the compiled functions work on (the state shared, not a
        copy: the fused period of :mod:`motosim.rt.fused` steps this very stage)."""
        return self._s, self._p

    @property
    def watchdog_periods(self) -> int:
        """Control periods without a valid status frame that trip the watchdog."""
        return int(self._p.watchdog)

    # --- state -------------------------------------------------------------------------
    @property
    def state(self) -> State:
        """IDLE, FADE_IN, RUNNING, FAULT or STOPPING."""
        state, _, _ = self._brief(self._s)
        return State(state)

    @property
    def fault(self) -> Fault:
        """The latched fault (NONE when there is none)."""
        _, fault, _ = self._brief(self._s)
        return Fault(fault)

    @property
    def fault_time(self) -> float:
        """When the fault was detected [s since the stage started] (NaN without a fault)."""
        return float(self._snapshot(self._s).fault_time)

    @property
    def hands_off(self) -> bool:
        """Whether nobody seems to hold the handlebar."""
        return bool(self._snapshot(self._s).hands_off)

    @property
    def free_turn(self) -> float:
        """The frozen-sensor monitor's turn of a free handlebar since the angle last changed
        [rad] (see Notes)."""
        return float(self._snapshot(self._s).free)

    @property
    def envelope(self) -> float:
        """The fade-in/fade-out scale of the command, in [0, 1]."""
        _, _, envelope = self._brief(self._s)
        return envelope

    @property
    def scale(self) -> float:
        """The share of its command the stage will pass in the next period, as far as it is
        known before the command (:func:`safety_scale`) [-]."""
        return float(safety_scale(self._s, self._p))

    @property
    def frames_lost(self) -> int:
        """Status frames lost (Profile 1's ``DeltaCounter - 1`` of the frames taken)."""
        return int(self._snapshot(self._s).lost)

    @property
    def frames_stale(self) -> int:
        """Status frames refused by the counter's check: ``REPEATED`` (stale or duplicated),
        ``WRONGSEQUENCE`` (older, or too far ahead) or a counter of 15."""
        return int(self._snapshot(self._s).stale)

    def brief(self) -> tuple[State, Fault, float]:
        """The state, the fault and the fade envelope [-] in one call (each period's
        telemetry)."""
        state, fault, envelope = self._brief(self._s)
        return State(state), Fault(fault), envelope

    def describe(self) -> str:
        """The latched fault's reason and time, in words."""
        if self.fault == Fault.NONE:
            return "no fault"
        reason = fault_reason(self.fault, watchdog_periods=self.limits.watchdog_periods)
        return f"{reason} (t = {self.fault_time:.3f} s)"

    # --- operator ----------------------------------------------------------------------
    def enable(self) -> None:
        """Start the torque with a fade-in (ignored while a fault is latched)."""
        safety_enable(self._s)

    def request_stop(self) -> None:
        """Fade the torque out over ``fade_in`` seconds, then go IDLE once the command
        sent is zero (later when the slew-rate limit holds it back)."""
        safety_request_stop(self._s)

    def trip(self, fault: Fault) -> None:
        """Latch ``fault`` now: the next :meth:`step` returns 0."""
        safety_trip(self._s, int(fault))

    def clear(self) -> None:
        """Forget a latched fault and go IDLE (the watchdog, the counter's check, the
        frozen-sensor monitor and hands-off detection start afresh)."""
        safety_clear(self._s)

    # --- frames ------------------------------------------------------------------------
    def status_frame(
        self, *, checksum_ok: bool, counter: float, drive_fault: bool, now: float | None = None
    ) -> bool:
        """Check a received status frame; True if it is valid and fresh (use its values).

        A wrong checksum trips CHECKSUM; a drive fault flag trips DRIVE_FAULT. The counter
        (0 to 14) goes through AUTOSAR E2E Profile 1's check (:data:`STATUS_E2E`), one
        receive cycle per frame period: the frame periods since the last frame that passed
        without one (the deadlines a late loop skipped included, counted from ``now``) are
        cycles without a frame first, so that they widen the step the counter may make.
        ``INITIAL``, ``OK`` and ``OKSOMELOST`` are valid (the lost frames counted);
        ``REPEATED``, ``WRONGSEQUENCE`` and a counter of 15 are refused (counted stale);
        ``SYNC`` counts its lost frames but is not used.

        ``now`` is the time of the period that reads the frame [s], on the clock of
        :meth:`step`'s ``now`` (by default, and for a stage stepped without one: one period
        after the last step).
        """
        t = math.nan if now is None else float(now)
        return bool(
            safety_status_frame(
                self._s, self._p, bool(checksum_ok), float(counter), bool(drive_fault), t
            )
        )

    def silent(self) -> None:
        """The watchdog's whole time passed without a valid status frame (a bus-paced loop's
        wait timed out): trip the watchdog now, unless IDLE (as :meth:`step` would after
        ``watchdog_periods`` periods)."""
        safety_silent(self._s)

    def estop_frame(self, *, checksum_ok: bool, pressed: bool) -> None:
        """An E-stop frame: pressed (or unreadable) trips the emergency stop."""
        safety_estop_frame(self._s, bool(checksum_ok), bool(pressed))

    # --- the period --------------------------------------------------------------------
    def step(
        self,
        command: float,
        *,
        theta: float,
        omega: float,
        tau_hat: float,
        now: float | None = None,
    ) -> float:
        """The current to send [A] for the stack's ``command`` [A] this period, given the
        last valid handlebar angle ``theta`` [rad], its estimated rate ``omega`` [rad/s] and
        the estimated rider torque ``tau_hat`` [N*m] (NaN if the stack has none: hands-off
        off).

        ``now`` is the loop's time [s] since the stage's first step, for the fault's time
        stamp and the watchdog: the control periods since the last step, rounded (at least
        one), count as periods without a status frame unless one came, so that the deadlines
        a late loop skipped count too. By default the stage counts its own periods.
        """
        t = math.nan if now is None else float(now)
        return float(
            safety_step(
                self._s, self._p, float(command), float(theta), float(omega), float(tau_hat), t
            )
        )


@njit(cache=True)
def safety_scale(s: Any, p: Any) -> float:
    """The share of its command the stage will pass in the coming period [-], as far as it
    is known before the command: the fade envelope (its ramp taken) times the hands-off
    gain while nobody holds the handlebar; 0 while the stage is idle or faulted. The clamp,
    the slew and the speed and end-stop limits, which depend on the command, are not in it.
    """
    if s.state == State.IDLE or s.state == State.FAULT:  # the drive is disabled
        return 0.0
    return float(_ramped_envelope(s, p) * (p.hands_off_gain if s.hands_off else 1.0))


@njit(cache=True)
def _ramped_envelope(s: Any, p: Any) -> float:
    """The fade envelope after this period's ramp: up while fading in, down while stopping,
    as it is otherwise."""
    ramp = p.dt / p.fade_in
    if s.state == State.FADE_IN:
        return float(min(1.0, s.envelope + ramp))
    if s.state == State.STOPPING:
        return float(max(0.0, s.envelope - ramp))
    return float(s.envelope)


@njit(cache=True)
def safety_enable(s: Any) -> None:
    """:meth:`SafetyStage.enable` on the state."""
    if s.state == State.IDLE or s.state == State.STOPPING:
        s.state = State.FADE_IN


@njit(cache=True)
def safety_request_stop(s: Any) -> None:
    """:meth:`SafetyStage.request_stop` on the state."""
    if s.state == State.FADE_IN or s.state == State.RUNNING:
        s.state = State.STOPPING


@njit(cache=True)
def safety_silent(s: Any) -> None:
    """:meth:`SafetyStage.silent` on the state."""
    if s.state != State.IDLE:
        safety_trip(s, Fault.WATCHDOG)
