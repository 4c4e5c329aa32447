"""Summary numbers and flags of a closed-loop run, computed from its recorded signals.

Free of plotting and of files: the simulator, the report, the real-time loop and campaigns
all summarise runs with :func:`run_metrics`, and :func:`failure` says whether a run that
completed numerically still failed (the motorcycle fell, its speed left the model's range,
the motor saturated most of the time). The fidelity numbers are those a rider feels: how far
the handlebar is from the virtual steer angle, how wrong the torque estimate driving the
motorcycle is, and whether the motor buzzes once the rider holds the handlebar steady.
"""

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import NDArray

from motosim.choices import RIDER_SPEEDS

if TYPE_CHECKING:
    from motosim.model.tyred import TyredModel

__all__ = [
    "BUZZ_CUTOFF",
    "BUZZ_LIMIT",
    "FALL_ROLL",
    "QUIET_TORQUE",
    "STICK_RATE",
    "failure",
    "highpass",
    "range_reason",
    "run_metrics",
    "validity_limits",
    "warnings",
]

Array = NDArray[np.float64]

FALL_ROLL = math.radians(45.0)
"""Roll beyond which the motorcycle is taken as fallen, and the linear model invalid [rad]."""
STICK_RATE = 0.05
"""Handlebar rate below which it is taken as sticking (dry friction undetermined) [rad/s]."""
BUZZ_CUTOFF = 3.0
"""Frequency above which current content counts as a buzz, not steering [Hz]."""
BUZZ_LIMIT = 0.3
"""Peak-to-peak of the current's content above :data:`BUZZ_CUTOFF` that flags a buzz [A]."""
QUIET_TORQUE = 1.0
"""Half-width [N*m] of the band about its middle within which the rider's torque stays while
the rider holds the handlebar steady, on a straight or in a steady turn (buzz judged then)."""
_SATURATED_SHARE = 0.5  # a run saturated this share of the time has failed
_TAIL = 2.0  # the last seconds examined for a sustained oscillation [s]
_LEAD = 1.0  # [s] filtered before them: three periods of the 3 Hz cutoff, its transient


def _rms(values: Array) -> float:
    return float(np.sqrt(np.mean(np.square(values)))) if values.size else 0.0


def _fraction(value: float, scale: float) -> float:
    """value / scale; NaN (undefined, null in JSON) when the scale is 0."""
    return value / scale if scale > 0 else math.nan


def validity_limits(start_speed: float) -> tuple[float, float, float]:
    """The model's range of validity for a run that starts at ``start_speed``.

    Parameters
    ----------
    start_speed : float
        The run's initial speed [m/s].

    Returns
    -------
    tuple of float
        (largest roll [rad], lowest speed [m/s], highest speed [m/s]): :data:`FALL_ROLL`, and
        :data:`motosim.choices.RIDER_SPEEDS` (3-60 m/s, where the virtual rider is scheduled
        and the linearisation about forward running holds), widened to include the start of
        a run that was accepted outside it with a warning.

    Examples
    --------
    >>> [round(v, 3) for v in validity_limits(20.0)]
    [0.785, 3.0, 60.0]
    >>> validity_limits(1.0)[1:]
    (1.0, 60.0)
    """
    low, high = RIDER_SPEEDS
    return FALL_ROLL, min(low, start_speed), max(high, start_speed)


def highpass(t: Array, values: Array, cutoff: float) -> Array:
    """``values`` without their content below ``cutoff`` [Hz], with no phase shift.

    A 4th-order Butterworth high-pass run forward and backward, the ends extended by odd
    reflection over up to three periods of the cutoff, each pass started in the steady state
    of its first sample (``scipy.signal.sosfiltfilt`` of ``butter(4, cutoff, "highpass",
    output="sos")``, computed here without SciPy's signal module, whose import takes longer
    than a run). Unlike a high-pass by FFT, which takes the window as one period of a
    periodic signal, a slow swing that is not a whole number of periods in the window (a
    slalom's steering current) does not leak above the cutoff.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform time [s].
    values : ndarray, shape (n,)
        The signal.
    cutoff : float
        Frequency [Hz] below which the content is removed (-6 dB there, -48 dB a decade below).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> t = np.arange(0.0, 2.0, 1e-3)
    >>> x = np.sin(2 * np.pi * 0.5 * t) + 0.1 * np.sin(2 * np.pi * 10 * t)
    >>> round(float(np.ptp(highpass(t, x, 3.0))), 2)
    0.2
    >>> x = 5.0 * np.sin(2 * np.pi * 0.3 * t)  # 0.6 of a period: no content above 3 Hz
    >>> bool(np.ptp(highpass(t, x, 3.0)) < 0.05)
    True
    """
    if values.size < 16:
        return values - np.mean(values) if values.size else values
    dt = float(t[1] - t[0])
    sections = _butterworth_highpass(cutoff, dt)
    x = np.asarray(values, dtype=np.float64) - np.mean(values)
    pad = min(x.size - 1, math.ceil(3.0 / (cutoff * dt)))
    extended = np.concatenate(
        [2.0 * x[0] - x[pad:0:-1], x, 2.0 * x[-1] - x[-2 : -pad - 2 : -1]]
    )  # odd reflection at both ends
    forward = _filter(sections, extended)
    backward = _filter(sections, forward[::-1])[::-1]
    return np.asarray(backward[pad : pad + x.size], dtype=np.float64)


class _Section(NamedTuple):
    """A second-order section b0 + b1 / z + b2 / z^2 over 1 + a1 / z + a2 / z^2."""

    b0: float
    b1: float
    b2: float
    a1: float
    a2: float


def _butterworth_highpass(cutoff: float, dt: float) -> list[_Section]:
    """The 4th-order Butterworth high-pass at ``cutoff`` [Hz] sampled at ``dt`` [s], as two
    second-order sections (b0, b1, b2, a1, a2), a0 = 1: each analog pair s^2 / (s^2 + 2 zeta
    w s + w^2), zeta = cos(pi/8) and cos(3 pi/8), by the bilinear transform prewarped at the
    cutoff (Oppenheim & Schafer, *Discrete-Time Signal Processing*, 3rd ed., sec. 7.2)."""
    k = 2.0 / dt
    w = k * math.tan(math.pi * cutoff * dt)
    out: list[_Section] = []
    for zeta in (math.cos(3.0 * math.pi / 8.0), math.cos(math.pi / 8.0)):
        a0 = k * k + 2.0 * zeta * w * k + w * w
        out.append(
            _Section(
                k * k / a0,
                -2.0 * k * k / a0,
                k * k / a0,
                2.0 * (w * w - k * k) / a0,
                (k * k - 2.0 * zeta * w * k + w * w) / a0,
            )
        )
    return out


def _filter(sections: list[_Section], x: Array) -> Array:
    """``x`` through the cascade of ``sections`` (transposed direct form II), each section
    started in its steady state for a constant input of ``x[0]`` (``scipy.signal.sosfilt``
    with ``sosfilt_zi(sos) * x[0]``)."""
    y = [float(v) for v in x]
    level = y[0]
    for b0, b1, b2, a1, a2 in sections:
        # the state a constant input `level` holds: the output gain * level, as it stays
        gain = (b0 + b1 + b2) / (1.0 + a1 + a2)
        z0 = (gain - b0) * level
        z1 = b2 * level - a2 * gain * level
        for i, v in enumerate(y):
            out = b0 * v + z0
            z0 = b1 * v - a1 * out + z1
            z1 = b2 * v - a2 * out
            y[i] = out
        level = gain * level
    return np.asarray(y, dtype=np.float64)


def run_metrics(
    t: Array,
    signal: Callable[[str], Array | None],
    *,
    complete: bool,
    max_current: float | None = None,
    running: NDArray[np.bool_] | None = None,
    limits: tuple[float, float, float] | None = None,
) -> dict[str, float]:
    """Summary numbers and flags of a run, in SI units.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time [s].
    signal : callable
        ``signal(name)`` returns the recorded column ``name`` (shape (n,)), or None when
        the run did not record it.
    complete : bool
        Whether the run reached its end.
    max_current : float, optional
        The controller's current limit [A], for the saturation share.
    running : ndarray of bool, shape (n,), optional
        Rows where the command reached the handlebar unfaded (a real-time run's RUNNING
        state). The buzz is then judged on the last two seconds of the last such span, not
        on a fade-in or a fade-out, whose ramp to zero is no oscillation; and, when the
        true rider torque is not recorded, the rider is taken as holding the handlebar
        steady from the estimate ``tau_r_hat`` below :data:`BUZZ_CUTOFF` (the buzz itself
        swings the estimate above it).

    limits : tuple of float, optional
        (fall roll [rad], lowest and highest speed [m/s]) that flag a fall and a speed out
        of range; by default :func:`validity_limits` of the first speed (a multibody run's
        are :func:`motosim.sim.closed_loop.run_limits`).

    Returns
    -------
    dict of str to float
        Always ``duration`` [s], ``samples`` and ``complete`` (1.0 or 0.0); with the
        signals they need:

        - ``rms_tau_r_error`` [N*m], ``rms_tracking_error`` [rad], ``rms_rate_error``
          [rad/s], ``max_abs_phi`` [rad], ``max_abs_e_y`` [m];
        - fidelity: ``peak_steer`` [rad] and ``tracking_rms_fraction``,
          ``tracking_peak_fraction`` (of ``theta_h - delta`` against the peak steer angle);
          ``peak_rider_torque`` [N*m], ``estimate_rms_fraction`` (of ``tau_r_hat - tau_r``
          against it), ``stick_share`` (time with |theta_h'| < :data:`STICK_RATE`) and
          ``rms_tau_r_error_moving`` [N*m] outside those stick phases, where the dry
          friction is determined;
        - ``buzz_current_p2p`` [A]: peak-to-peak of the current's content above
          :data:`BUZZ_CUTOFF` over the last two seconds, and ``buzz_frequency`` [Hz], its
          strongest frequency;
        - ``saturated_share`` (time at the current limit, with ``max_current``);
        - flags 1.0 or 0.0: ``flag_oscillation`` (buzz above :data:`BUZZ_LIMIT` while the
          rider's torque, ``tau_r_active`` where recorded (the arms' passive torque follows the
          buzz), stays within :data:`QUIET_TORQUE` of its middle value over those two
          seconds: the handlebar held steady, upright or in a steady turn),
          ``flag_saturation`` (saturated more than half the time), ``flag_fall`` (roll beyond
          :data:`FALL_ROLL`), ``flag_out_of_range`` (the speed left 3-60 m/s, where the
          virtual rider is scheduled and the linear model is meant for, or went further out
          than a start outside them: :func:`validity_limits`);
        - ``min_speed``, ``max_speed`` [m/s].

    Examples
    --------
    >>> cols = {"phi": np.array([0.2, 0.0])}
    >>> m = run_metrics(np.array([0.0, 1.0]), cols.get, complete=False)
    >>> m["duration"], m["complete"], round(m["max_abs_phi"], 3), m["flag_fall"]
    (1.0, 0.0, 0.2, 0.0)
    """
    out = {
        "duration": float(t[-1] - t[0]) if t.size else 0.0,
        "samples": float(t.size),
        "complete": 1.0 if complete else 0.0,
    }
    if t.size == 0:
        return out
    differences = {
        "rms_tau_r_error": ("tau_r_hat", "tau_r"),
        "rms_tracking_error": ("theta_h", "delta"),
        "rms_rate_error": ("theta_h_dot_hat", "theta_h_dot"),
    }
    for key, (estimate_name, truth_name) in differences.items():
        estimate, truth = signal(estimate_name), signal(truth_name)
        if estimate is not None and truth is not None:
            out[key] = _rms(estimate - truth)
    for key, name in (("max_abs_phi", "phi"), ("max_abs_e_y", "e_y")):
        values = signal(name)
        if values is not None:
            out[key] = float(np.max(np.abs(values)))
    speed = signal("v_x")
    fall, low, high = limits or validity_limits(float(speed[0]) if speed is not None else 20.0)
    if "max_abs_phi" in out:
        out["flag_fall"] = float(out["max_abs_phi"] > fall)
    if speed is not None:
        out["min_speed"], out["max_speed"] = float(np.min(speed)), float(np.max(speed))
        out["flag_out_of_range"] = float(out["min_speed"] < low or out["max_speed"] > high)

    theta, delta = signal("theta_h"), signal("delta")
    if theta is not None and delta is not None:
        peak = float(np.max(np.abs(delta)))
        error = theta - delta
        out["peak_steer"] = peak
        out["tracking_rms_fraction"] = _fraction(_rms(error), peak)
        out["tracking_peak_fraction"] = _fraction(float(np.max(np.abs(error))), peak)
    tau, tau_hat, rate = signal("tau_r"), signal("tau_r_hat"), signal("theta_h_dot")
    if tau is not None and tau_hat is not None:
        peak_tau = float(np.max(np.abs(tau)))
        out["peak_rider_torque"] = peak_tau
        error = tau_hat - tau
        out["estimate_rms_fraction"] = _fraction(_rms(error), peak_tau)
        if rate is not None:
            moving = np.abs(rate) >= STICK_RATE
            out["stick_share"] = float(1.0 - np.mean(moving))
            out["rms_tau_r_error_moving"] = _rms(error[moving])
    current = signal("i_m")
    span = _last_span(running) if running is not None else slice(0, t.size)
    t_run = t[span]
    if current is not None and t_run.size > 8:
        current, end = current[span], t_run[-1]
        tail = t_run >= end - _TAIL
        # filtered with a second before the tail, so that only the run's end is an edge
        window = t_run >= end - _TAIL - _LEAD
        buzz = highpass(t_run[window], current[window], BUZZ_CUTOFF)[tail[window]]
        out["buzz_current_p2p"] = float(np.ptp(buzz))
        spectrum = np.abs(np.fft.rfft(buzz))
        freqs = np.fft.rfftfreq(buzz.size, float(t[1] - t[0]))
        out["buzz_frequency"] = float(freqs[int(np.argmax(spectrum))])
        # a buzz is current the rider does not ask for: judged while the rider holds the
        # handlebar steady, upright or in a steady turn (a constant torque asks for no change)
        held = None
        # the active torque where recorded: the arms' passive torque follows the buzz it damps
        active = signal("tau_r_active")
        asked = active if active is not None else tau
        if asked is not None:
            held = asked[span][tail]
        elif tau_hat is not None and running is not None:
            slow = tau_hat[span][window]
            held = (slow - highpass(t_run[window], slow, BUZZ_CUTOFF))[tail[window]]
        quiet = held is None or float(np.ptp(held)) <= 2.0 * QUIET_TORQUE
        out["flag_oscillation"] = float(quiet and out["buzz_current_p2p"] > BUZZ_LIMIT)
        if max_current is not None:
            share = float(np.mean(np.abs(current) >= 0.999 * max_current))
            out["saturated_share"] = share
            out["flag_saturation"] = float(share > _SATURATED_SHARE)
    return out


def _last_span(running: NDArray[np.bool_]) -> slice:
    """The rows of the last run of True in ``running`` (empty when there is none)."""
    on = np.flatnonzero(running)
    if on.size == 0:
        return slice(0, 0)
    end = int(on[-1]) + 1
    gaps = np.flatnonzero(~running[:end])
    return slice(int(gaps[-1]) + 1 if gaps.size else 0, end)


def failure(metrics: dict[str, float]) -> str | None:
    """Why a run that completed numerically failed, in one line, or None.

    A run fails when the motorcycle fell (roll beyond :data:`FALL_ROLL`, where the linear
    model no longer holds), its speed left the model's range (:func:`validity_limits`) or
    the motor was saturated more than half the time.
    """
    if metrics.get("flag_fall"):
        return (
            f"the motorcycle fell: roll reached {math.degrees(metrics['max_abs_phi']):.0f} deg "
            f"(beyond {math.degrees(FALL_ROLL):.0f} deg the linear model does not hold)"
        )
    if metrics.get("flag_out_of_range"):
        low, high = RIDER_SPEEDS
        return (
            f"the speed left the model's range: it went from {metrics['min_speed']:.3g} to "
            f"{metrics['max_speed']:.3g} m/s (the virtual rider is scheduled and the linear "
            f"model meant for {low:g} to {high:g} m/s)"
        )
    if metrics.get("flag_saturation"):
        return (
            f"the motor current was at its limit {100 * metrics['saturated_share']:.0f} % of "
            "the time"
        )
    return None


def range_reason(t: float, phi: float, speed: float, limits: tuple[float, float, float]) -> str:
    """Why a run stopped at time ``t`` [s] with roll ``phi`` [rad] and speed ``speed`` [m/s]
    beyond ``limits`` (:func:`validity_limits`), in one line.

    Examples
    --------
    >>> range_reason(2.5, 0.9, 20.0, (0.785, 3.0, 60.0)).split(",")[0]
    'the motorcycle fell at t = 2.500 s: roll 51.6 deg'
    """
    roll, low, high = limits
    if abs(phi) > roll:
        return (
            f"the motorcycle fell at t = {t:.3f} s: roll {math.degrees(phi):.1f} deg, beyond "
            f"{math.degrees(roll):.0f} deg where the linear model no longer holds; the run "
            "stopped there"
        )
    return (
        f"the speed left the model's range at t = {t:.3f} s: {speed:.5g} m/s, outside "
        f"{low:g} to {high:g} m/s (the virtual rider's schedule and the linearisation about "
        "forward running); the run stopped there"
    )


LOCKED_SLIP = -0.9
"""A wheel whose longitudinal slip is at or below this is locked (slip -1: not turning)."""


def wheel_locks(t: Array, get: Callable[[str], Array], *, to_end: bool = True) -> list[str]:
    """One phrase for each wheel that locked, naming when.

    A wheel locks when its slip (``kappa_f``, ``kappa_r``) falls to :data:`LOCKED_SLIP` or
    below; named is the start of its last locked stretch, one that lasts to the run's end
    (``to_end``) or any.

    Examples
    --------
    >>> t = np.arange(5) * 0.5
    >>> slips = {"kappa_f": np.array([0.0, -0.1, -0.95, -1.0, -1.0]), "kappa_r": np.zeros(5)}
    >>> wheel_locks(t, slips.__getitem__)
    ['the front wheel locked at t = 1.000 s']
    >>> slips["kappa_f"][-1] = 1.0
    >>> wheel_locks(t, slips.__getitem__), wheel_locks(t, slips.__getitem__, to_end=False)
    ([], ['the front wheel locked at t = 1.000 s'])
    """
    out = []
    for wheel, column in (("front", "kappa_f"), ("rear", "kappa_r")):
        locked = np.asarray(get(column)) <= LOCKED_SLIP
        if not locked.any() or (to_end and not locked[-1]):
            continue
        last = int(np.flatnonzero(locked)[-1])
        free = np.flatnonzero(~locked[: last + 1])
        first = 0 if free.size == 0 else int(free[-1]) + 1
        out.append(f"the {wheel} wheel locked at t = {t[first]:.3f} s")
    return out


def multibody_reason(
    t: Array, get: Callable[[str], Array], model: "TyredModel", limits: tuple[float, float, float]
) -> str:
    """Why a run on the multibody motorcycle stopped at its last instant, in one line.

    It fell (roll beyond the ``model``'s roll limit, or the front wheel tucked under: steer
    beyond its steer limit), lifted a wheel off the ground (its normal load 0) or left the
    speeds ``limits`` (:func:`motosim.sim.closed_loop.run_limits`); a wheel locked before is
    named first (:func:`wheel_locks`).
    """
    roll_limit, steer_limit = model.roll_limit, model.steer_limit
    end = float(t[-1])
    phi, speed = float(get("phi")[-1]), float(get("v_x")[-1])
    delta = float(get("delta")[-1])
    if abs(phi) > roll_limit:
        what = (
            f"the motorcycle fell at t = {end:.3f} s: roll {math.degrees(phi):.1f} deg, beyond "
            f"{math.degrees(roll_limit):.0f} deg"
        )
    elif abs(delta) > steer_limit:
        what = (
            f"the motorcycle fell at t = {end:.3f} s: the front wheel tucked under (steer "
            f"{math.degrees(delta):.0f} deg, past the {math.degrees(steer_limit):.0f} deg "
            "steering stop)"
        )
    elif get("F_zr")[-1] <= 0.0 or get("F_zf")[-1] <= 0.0:
        wheel = "rear" if get("F_zr")[-1] <= 0.0 else "front"
        what = (
            f"the {wheel} wheel left the ground at t = {end:.3f} s (the model keeps both "
            "wheels on the road)"
        )
    else:
        low, high = limits[1:]
        what = (
            f"the speed left the model's range at t = {end:.3f} s: {speed:.5g} m/s, outside "
            f"{low:g} to {high:g} m/s"
        )
    locks = wheel_locks(t, get, to_end=False)
    return ", and ".join([*locks, what]) + "; the run stopped there"


def warnings(metrics: dict[str, float]) -> list[str]:
    """One line for each flag that does not fail a run but that a user must know of."""
    out = []
    if metrics.get("flag_oscillation"):
        out.append(
            f"the motor current buzzes: {metrics['buzz_current_p2p']:.2g} A peak to peak at "
            f"{metrics['buzz_frequency']:.3g} Hz while the rider holds the handlebar steady"
        )
    return out
