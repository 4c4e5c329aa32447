"""The safety stage: the last stage before the bus, always on.

Software limits are a second line of defence. The real safety function of a motorised
handlebar is the drive's hardware safe torque off (STO, IEC 61800-5-2; stop category 0 of
IEC 60204-1) wired to an emergency-stop button; the drive must also stop the torque on its
own when command frames stop coming. What this stage adds, after the stack has computed its
current command and before the command is encoded (the protections of force-feedback wheel
firmware such as OpenFFBoard's ``Axis.cpp`` and of Simucube's drives):

- a current clamp (``max_current`` [A]) and a slew-rate limit (``max_slew`` [A/s]);
- a speed limiter that only ever reduces the command pushing the handlebar faster beyond
  ``max_speed`` [rad/s] (to zero ``speed_band`` [rad/s] above it), never adds torque;
- soft end stops: beyond ``soft_stop`` [rad] the command pushing further out is dropped and
  a restoring spring ``end_stop_gain`` [A/rad] is added; beyond ``hard_stop`` a fault;
- a fade-in over ``fade_in`` [s] (0.5 s) on every enable, and a fade-out on a stop request;
- a communication watchdog: no valid status frame for ``watchdog_periods`` periods -> zero
  command and a latched fault; a status frame is valid when its checksum is right and its
  alive counter has moved (a stale or duplicated frame does not feed the watchdog);
- guards: a NaN or inf measurement, estimate or command, a bad checksum, a fault flag of the
  drive, an emergency stop (from a CAN frame or the keyboard) -> zero command at once and a
  latched fault with its reason and time;
- hands-off detection: while the estimated rider torque stays below ``hands_off_torque``
  [N*m] for ``hands_off_time`` [s], the command is scaled by ``hands_off_gain``;
- a frozen-sensor monitor (given the handlebar's parameters): the angle has not changed
  while the motor torque has moved so far from its value at the angle's last change that a
  free handlebar would have turned by more than ``frozen_angle`` [rad] -> a latched fault
  (see :class:`SafetyStage`, Notes).

A fault gives a zero command in the same period it is detected, without slew limiting, and
stays latched until :meth:`SafetyStage.clear`; enabling again starts a new fade-in. The stage
works on Python floats only and allocates nothing per period.
"""

import math
from dataclasses import dataclass
from enum import IntEnum

from motosim.errors import MotosimError
from motosim.params.checks import check_number, short_repr
from motosim.params.handlebar import HandlebarParameters

__all__ = ["SAFETY_RANGES", "Fault", "SafetyLimits", "SafetyStage", "State", "fault_reason"]


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
                if not (isinstance(value, int) and low <= value <= high):
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
    handlebar still against the motor, which is legitimate (a steady turn: the rider's torque
    balances the motor's and the angle stands still for seconds). Only the angle and the
    motor current are measured, so a still angle under a large *steady* current proves
    nothing. What a rider cannot do is hold the handlebar to one encoder count while the
    motor torque *changes* a lot: an arm is a spring of at most a few hundred N*m/rad, so a
    change of a few N*m moves the handlebar by milliradians, tens of counts. The monitor
    keeps the motor torque ``tau_0 = N k_t i`` of the period the measured angle last changed
    and, while it stands still, integrates the turn of a *free* handlebar of eq. (5) driven
    by the change of torque since then, quasi-statically (the inertia's lag,
    ``J_eq / beta_eq`` = 3 ms for Table I, is neglected), with twice the dry friction as a
    dead band (the still handlebar may sit anywhere in the friction band)::

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
    ...     _ = stage.status_frame(checksum_ok=True, counter=k % 16, drive_fault=False)
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

    __slots__ = (
        "_counter",
        "_envelope",
        "_fault",
        "_fault_time",
        "_free",
        "_fresh",
        "_hands_off",
        "_hb",
        "_last",
        "_missing",
        "_quiet",
        "_ref_theta",
        "_ref_torque",
        "_state",
        "_t",
        "_watchdog",
        "dt",
        "frames_lost",
        "frames_stale",
        "limits",
    )

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
        if periods_per_frame < 1:
            raise MotosimError(
                f"periods_per_frame = {periods_per_frame!r}: expected an integer >= 1"
            )
        self._watchdog = limits.watchdog_periods * periods_per_frame
        self.limits = limits
        self.dt = float(dt)
        self._state = State.IDLE
        self._fault = Fault.NONE
        self._fault_time = math.nan
        self._t = 0.0
        self._envelope = 0.0
        self._last = 0.0
        self._counter = -1
        self._fresh = False
        self._missing = 0
        self._quiet = 0.0
        self._hands_off = False
        self._hb: tuple[float, float, float] | None = None if handlebar is None else (
            handlebar.torque_per_amp, 2.0 * handlebar.beta_s, handlebar.beta_eq
        )  # fmt: skip
        self._ref_theta = math.nan
        self._ref_torque = 0.0
        self._free = 0.0
        self.frames_lost = 0
        self.frames_stale = 0

    @property
    def watchdog_periods(self) -> int:
        """Control periods without a valid status frame that trip the watchdog."""
        return self._watchdog

    # --- state -------------------------------------------------------------------------
    @property
    def state(self) -> State:
        """IDLE, FADE_IN, RUNNING, FAULT or STOPPING."""
        return self._state

    @property
    def fault(self) -> Fault:
        """The latched fault (NONE when there is none)."""
        return self._fault

    @property
    def fault_time(self) -> float:
        """When the fault was detected [s since the stage started] (NaN without a fault)."""
        return self._fault_time

    @property
    def hands_off(self) -> bool:
        """Whether nobody seems to hold the handlebar."""
        return self._hands_off

    @property
    def free_turn(self) -> float:
        """The frozen-sensor monitor's turn of a free handlebar since the angle last changed
        [rad] (see Notes)."""
        return self._free

    @property
    def envelope(self) -> float:
        """The fade-in/fade-out scale of the command, in [0, 1]."""
        return self._envelope

    def describe(self) -> str:
        """The latched fault's reason and time, in words."""
        if self._fault == Fault.NONE:
            return "no fault"
        reason = fault_reason(self._fault, watchdog_periods=self.limits.watchdog_periods)
        return f"{reason} (t = {self._fault_time:.3f} s)"

    # --- operator ----------------------------------------------------------------------
    def enable(self) -> None:
        """Start the torque with a fade-in (ignored while a fault is latched)."""
        if self._state in (State.IDLE, State.STOPPING):
            self._state = State.FADE_IN

    def request_stop(self) -> None:
        """Fade the torque out over ``fade_in`` seconds, then go IDLE."""
        if self._state in (State.FADE_IN, State.RUNNING):
            self._state = State.STOPPING

    def trip(self, fault: Fault) -> None:
        """Latch ``fault`` now: the next :meth:`step` returns 0."""
        if fault == Fault.NONE:
            return
        if self._fault == Fault.NONE:
            self._fault = fault
            self._fault_time = self._t
        self._state = State.FAULT
        self._envelope = 0.0
        self._last = 0.0

    def clear(self) -> None:
        """Forget a latched fault and go IDLE (the watchdog starts afresh)."""
        self._fault = Fault.NONE
        self._fault_time = math.nan
        self._state = State.IDLE
        self._missing = 0
        self._counter = -1

    # --- frames ------------------------------------------------------------------------
    def status_frame(self, *, checksum_ok: bool, counter: float, drive_fault: bool) -> bool:
        """Check a received status frame; True if it is valid and fresh (use its values).

        A wrong checksum trips CHECKSUM; a drive fault flag trips DRIVE_FAULT; a counter
        that has not moved (a stale or duplicated frame) makes the frame invalid; a counter
        that jumped counts the lost frames.
        """
        if not checksum_ok:
            self.trip(Fault.CHECKSUM)
            return False
        c = int(counter) & 0xF
        if c == self._counter:
            self.frames_stale += 1
            return False
        if self._counter >= 0:
            self.frames_lost += (c - self._counter - 1) & 0xF
        self._counter = c
        if drive_fault:
            self.trip(Fault.DRIVE_FAULT)
        self._fresh = True
        return True

    def silent(self) -> None:
        """The watchdog's whole time passed without a valid status frame (a bus-paced loop's
        wait timed out): trip the watchdog now, unless IDLE (as :meth:`step` would after
        ``watchdog_periods`` periods)."""
        if self._state != State.IDLE:
            self.trip(Fault.WATCHDOG)

    def estop_frame(self, *, checksum_ok: bool, pressed: bool) -> None:
        """An E-stop frame: pressed (or unreadable) trips the emergency stop."""
        if not checksum_ok:
            self.trip(Fault.CHECKSUM)
        elif pressed:
            self.trip(Fault.ESTOP_CAN)

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
        """The current to send [A] for the stack's ``command`` [A] this period.

        Parameters
        ----------
        command : float
            The stack's current command [A].
        theta, omega : float
            Last valid handlebar angle [rad] and its estimated rate [rad/s].
        tau_hat : float
            The estimated rider torque [N*m] (NaN if the stack has none: hands-off off).
        now : float, optional
            The loop's time [s], for the fault's time stamp; by default the stage counts
            its own periods.
        """
        lim = self.limits
        dt = self.dt
        self._t = self._t + dt if now is None else now
        if self._fresh:
            self._missing = 0
            self._fresh = False
        else:
            self._missing += 1
            if self._missing >= self._watchdog and self._state != State.IDLE:
                self.trip(Fault.WATCHDOG)
        if not (
            math.isfinite(command) and math.isfinite(theta) and math.isfinite(omega)
        ) or math.isinf(tau_hat):
            self.trip(Fault.NON_FINITE)
        elif abs(theta) > lim.hard_stop:
            self.trip(Fault.END_STOP)
        elif self._hb is not None:
            self._frozen_monitor(theta, self._hb)
        state = self._state
        if state == State.FAULT or state == State.IDLE:
            self._last = 0.0
            self._envelope = 0.0
            return 0.0
        # speed limiter: only reduces a command that pushes the handlebar faster
        i = command
        excess = abs(omega) - lim.max_speed
        if excess > 0.0 and i * omega > 0.0:
            i *= max(0.0, 1.0 - excess / lim.speed_band)
        # soft end stops
        over = abs(theta) - lim.soft_stop
        if over > 0.0:
            out = 1.0 if theta > 0.0 else -1.0
            if i * out > 0.0:
                i = 0.0
            i -= out * lim.end_stop_gain * over
        # hands-off: reduce the gain while nobody holds the handlebar
        if lim.hands_off_torque > 0.0 and tau_hat == tau_hat:
            if abs(tau_hat) < lim.hands_off_torque:
                self._quiet += dt
                self._hands_off = self._quiet >= lim.hands_off_time
            else:
                self._quiet = 0.0
                self._hands_off = False
            if self._hands_off:
                i *= lim.hands_off_gain
        # clamp, fade, slew
        i = min(max(i, -lim.max_current), lim.max_current)
        ramp = dt / lim.fade_in
        if state == State.STOPPING:
            self._envelope = max(0.0, self._envelope - ramp)
            if self._envelope == 0.0:
                self._state = State.IDLE
        elif state == State.FADE_IN:
            self._envelope = min(1.0, self._envelope + ramp)
            if self._envelope >= 1.0:
                self._state = State.RUNNING
        i *= self._envelope
        step = lim.max_slew * dt
        i = min(max(i, self._last - step), self._last + step)
        self._last = i
        return i

    def _frozen_monitor(self, theta: float, hb: tuple[float, float, float]) -> None:
        """The frozen-sensor monitor of one period (see Notes); trips FROZEN_SENSOR."""
        torque_per_amp, band, beta = hb
        torque = torque_per_amp * self._last
        if theta != self._ref_theta or self._state in (State.IDLE, State.STOPPING):
            self._ref_theta = theta
            self._ref_torque = torque
            self._free = 0.0
            return
        drive = abs(torque - self._ref_torque) - band
        if drive > 0.0:
            self._free += drive / beta * self.dt
            if self._free > self.limits.frozen_angle:
                self.trip(Fault.FROZEN_SENSOR)
