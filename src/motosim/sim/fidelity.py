"""The rendered steering feel: what the rider feels through the handlebar, against the machine.

The torque feedback should make the handlebar in the rider's hands move as the virtual
motorcycle's front assembly would: then the response from the rider's torque to the
handlebar angle equals the motorcycle's own response from steer torque to steer angle. The
ratio of the two is the haptic *transparency* of the simulator. :func:`feel_scenario` builds a
run that measures it (the virtual rider holds a straight at a speed while a probe torque is
added to the rider's), and :func:`periodic_feel` (a periodic multisine probe, averaged over
whole periods) or :func:`rendered_feel` (any probe, Welch cross-spectra) estimates both
frequency responses from the run, the rider's torque as input, and compares them with the
linear model's delta / tau_r at that speed. In a steady turn (``radius``) or on the multibody
motorcycle, where no linearisation about upright running holds, the reference is the
motorcycle's own delta / tau_r measured in the same run (give ``sharp`` None).

The multisine is the default: a linear chirp over 0.1-5 Hz in 60 s spends about a second
below 0.2 Hz, too little for its Welch estimate there even on a linear stack (no friction,
exact angle), where the periodic estimate matches the linear analysis of
:mod:`motosim.sim.loop_analysis` (the simulate guide compares them).
"""

import dataclasses
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.signal import csd, welch

from motosim.control.statespace import frequency_response
from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.params.sharp import SharpParameters
from motosim.sim.scenario import (
    ChirpProfile,
    MultisineProfile,
    Rider,
    Scenario,
    StraightPath,
    TurnPath,
)

__all__ = ["EXCITATIONS", "FeelResponse", "feel_scenario", "periodic_feel", "rendered_feel"]

Array = NDArray[np.float64]

EXCITATIONS = ("multisine", "chirp")
"""Probe torques of :func:`feel_scenario`; the first is the default."""


def _within(f: Array, low: float, high: float) -> NDArray[np.bool_]:
    """``low <= f <= high`` up to rounding: Welch's bins k df may fall a hair short of k df."""
    tol = 1e-9 * max(abs(low), abs(high))
    return np.asarray((f >= low - tol) & (f <= high + tol), dtype=np.bool_)


@dataclass(frozen=True, slots=True)
class FeelResponse:
    """Rendered and ideal steering feel over frequency.

    Attributes
    ----------
    frequency : ndarray, shape (m,)
        [Hz].
    rendered : ndarray of complex, shape (m,)
        theta_h / tau_r measured in the run [rad/(N*m)].
    steer : ndarray of complex, shape (m,)
        delta / tau_r measured in the run: the virtual motorcycle [rad/(N*m)].
    model : ndarray of complex, shape (m,)
        The reference delta / tau_r [rad/(N*m)]: the linear model's at the run's speed, or
        ``steer`` (the run's own, on the multibody motorcycle).
    coherence : ndarray, shape (m,)
        Coherence of tau_r and theta_h (1: the response is linear and noise-free); for
        :func:`periodic_feel`, the share of theta_h's power at the line that repeats from
        period to period (1: every period the same).
    """

    frequency: Array
    rendered: NDArray[np.complex128]
    steer: NDArray[np.complex128]
    model: NDArray[np.complex128]
    coherence: Array

    @property
    def magnitude_error_db(self) -> Array:
        """20 log10 |rendered / model| [dB]."""
        return np.asarray(20.0 * np.log10(np.abs(self.rendered / self.model)), dtype=np.float64)

    @property
    def phase_error_deg(self) -> Array:
        """Phase of rendered / model, wrapped to (-180, 180] [deg]."""
        return np.asarray(np.degrees(np.angle(self.rendered / self.model)), dtype=np.float64)

    def _band(self, low: float, high: float) -> tuple[Array, Array]:
        """|magnitude error| [dB] and |phase error| [deg] at the frequencies in the band."""
        band = _within(self.frequency, low, high)
        if not band.any():
            raise MotosimError(f"no frequency of the response within {low:g}-{high:g} Hz")
        return np.abs(self.magnitude_error_db[band]), np.abs(self.phase_error_deg[band])

    def median(self, low: float, high: float) -> tuple[float, float]:
        """Median |magnitude error| [dB] and |phase error| [deg] over ``low``-``high`` [Hz]."""
        magnitude, phase = self._band(low, high)
        return float(np.median(magnitude)), float(np.median(phase))

    def worst(self, low: float, high: float) -> tuple[float, float]:
        """Largest |magnitude error| [dB] and |phase error| [deg] over ``low``-``high`` [Hz]."""
        magnitude, phase = self._band(low, high)
        return float(np.max(magnitude)), float(np.max(phase))


def feel_scenario(
    base: Scenario,
    *,
    speed: float,
    amplitude: float = 10.0,
    band: tuple[float, float] = (0.1, 5.0),
    duration: float = 60.0,
    excitation: Literal["multisine", "chirp"] = "multisine",
    period: float = 20.0,
    periods: int = 4,
    lateral_tolerance: float = 3.0,
    course_tolerance: float = 0.5,
    radius: float | None = None,
) -> Scenario:
    """``base`` turned into a feel measurement: a straight at ``speed`` [m/s], a probe torque.

    With ``radius`` [m] the rider holds a right-hand turn of that radius instead (entered
    over a 30 m clothoid from the start, and turned as long as the run lasts): the feel at
    the lean v^2 / (g R) asks for.

    The virtual rider holds the straight (the machine is unstable on its own above the
    capsize speed) while a probe of peak ``amplitude`` [N*m] over ``band`` [Hz] is added to
    the rider's torque; handlebar, estimator, controller, rates and the rider's hands stay
    the base's (with hands, tau_r is their whole torque, active and passive). The
    probe is a periodic multisine of ``period`` [s]
    (:class:`~motosim.sim.scenario.MultisineProfile`, lines at multiples of 1 / ``period``),
    one period to settle and ``periods`` to average (the run lasts
    ``(periods + 1) * period``), or a linear chirp over ``duration`` [s].

    The rider holds the straight loosely (``lateral_tolerance`` [m] and ``course_tolerance``
    [rad] of :class:`~motosim.sim.scenario.Rider`): a rider who holds it tightly cancels
    most of the probe at the lowest lines with their own balancing torque, and the little
    torque left there is then measured against the estimate's errors in stick phases.
    """
    if not (math.isfinite(amplitude) and 0 < amplitude <= 50.0):
        raise MotosimError(f"amplitude = {amplitude!r}; expected a torque in (0, 50] N*m")
    low, high = band
    if not (0 < low < high <= 20.0):
        raise MotosimError(f"band = {low:g}:{high:g}; expected 0 < low < high <= 20 Hz")
    probe: ChirpProfile | MultisineProfile
    if excitation == "chirp":
        probe = ChirpProfile(amplitude, low, high, start=0.0)
    elif excitation == "multisine":
        if not (isinstance(periods, int) and 1 <= periods <= 100):
            raise MotosimError(f"periods = {periods!r}; expected a whole number of 1 to 100")
        if not (math.isfinite(period) and period * low >= 1.0 - 1e-9):
            raise MotosimError(
                f"period = {period!r} s; expected at least 1 / low = {1.0 / low:g} s, so that "
                f"the band's {low:g} Hz is one of the multisine's lines"
            )
        probe = MultisineProfile(amplitude, low, high, period)
        duration = (periods + 1) * period
    else:
        raise MotosimError(f"excitation = {excitation!r}; expected one of {', '.join(EXCITATIONS)}")
    path: StraightPath | TurnPath = StraightPath()
    if radius is not None:
        if not (math.isfinite(radius) and 10.0 <= radius <= 10_000.0):
            raise MotosimError(f"radius = {radius!r}; expected a turn of 10 to 10000 m")
        path = TurnPath(
            radius, angle=(speed * duration + 100.0) / radius, start=0.0, transition=30.0
        )
    rider = Rider(
        "virtual",
        path=path,
        probe=probe,
        lateral_tolerance=lateral_tolerance,
        course_tolerance=course_tolerance,
        hands=base.rider.hands,
    )
    motorcycle = dataclasses.replace(base.motorcycle, speed=speed)
    return dataclasses.replace(
        base, name=f"{base.name}_feel", duration=duration, rider=rider, motorcycle=motorcycle
    )


def _model_response(sharp: SharpParameters, speed: float, f: Array) -> NDArray[np.complex128]:
    """delta / tau_r of the linear motorcycle at ``speed`` [m/s], at ``f`` [Hz]."""
    lin = sharp_model.linearize(sharp, speed)
    row = sharp_model.STATE_NAMES.index("delta")
    model = np.array([frequency_response(lin, 2 * math.pi * fk)[row, 0] for fk in f])
    return np.asarray(model, dtype=np.complex128)


def periodic_feel(
    t: Array,
    rider_torque: Array,
    handlebar_angle: Array,
    steer_angle: Array,
    sharp: SharpParameters | None,
    speed: float,
    *,
    probe: MultisineProfile,
    band: tuple[float, float] = (0.1, 5.0),
) -> FeelResponse:
    """Estimate the rendered feel and the motorcycle's response at a multisine's lines.

    The run is cut into whole periods of ``probe`` after its first (the transient); each
    signal's DFT is averaged over the periods at the excited lines, and the responses are the
    ratios of the averages: theta_h / tau_r and delta / tau_r (Pintelon & Schoukens, *System
    Identification: A Frequency Domain Approach*, 2nd ed., 2012, chapter 2: the averaged
    spectra of a periodic excitation, without leakage). Only what repeats with the probe is
    kept: the rider's own balancing torque enters as far as it answers the probe.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform time [s], from the probe's start.
    rider_torque, handlebar_angle, steer_angle : ndarray, shape (n,)
        tau_r [N*m], theta_h [rad], delta [rad] of a run with the probe in the rider's torque.
    sharp : SharpParameters or None
        The virtual motorcycle, for its linear response at ``speed`` [m/s]; None: the
        reference is the run's own delta / tau_r (the multibody motorcycle).
    probe : MultisineProfile
        The probe of the run: its period and lines.
    band : tuple of two floats
        Frequencies kept [Hz].

    Returns
    -------
    FeelResponse

    Raises
    ------
    MotosimError
        If the run holds fewer than two periods, its step does not divide the period, or no
        line falls in ``band``.
    """
    if t.size < 16:
        raise MotosimError(f"{t.size} samples; expected a run of at least 16 to analyse")
    dt = float(np.median(np.diff(t)))
    per = round(probe.period / dt)
    if abs(per * dt - probe.period) > 1e-6 * probe.period:
        raise MotosimError(
            f"period = {probe.period:g} s; expected a whole number of steps of {dt:g} s"
        )
    k0 = max(0, round((probe.start - float(t[0])) / dt)) + per  # the first period settles
    count = (t.size - k0) // per
    if count < 1:
        raise MotosimError(
            f"run of {t.size * dt:g} s; expected at least two periods of {probe.period:g} s"
        )
    f = probe.frequencies()
    f = f[_within(f, band[0], band[1])]
    if f.size == 0:
        raise MotosimError(f"no line of the multisine within {band[0]:g}-{band[1]:g} Hz")
    lines = np.round(f * probe.period).astype(int)

    def spectra(x: Array) -> NDArray[np.complex128]:
        block = np.asarray(x, dtype=float)[k0 : k0 + count * per].reshape(count, per)
        return np.asarray(np.fft.rfft(block, axis=1)[:, lines], dtype=np.complex128)

    u, y, d = spectra(rider_torque), spectra(handlebar_angle), spectra(steer_angle)
    u_mean, y_mean = u.mean(axis=0), y.mean(axis=0)
    power = np.mean(np.abs(y) ** 2, axis=0)
    repeat = np.where(power > 0, np.abs(y_mean) ** 2 / np.where(power > 0, power, 1.0), 0.0)
    steer = np.asarray(d.mean(axis=0) / u_mean, dtype=np.complex128)
    return FeelResponse(
        frequency=np.asarray(f, dtype=np.float64),
        rendered=np.asarray(y_mean / u_mean, dtype=np.complex128),
        steer=steer,
        model=steer if sharp is None else _model_response(sharp, speed, f),
        coherence=np.asarray(repeat, dtype=np.float64),
    )


def rendered_feel(
    t: Array,
    rider_torque: Array,
    handlebar_angle: Array,
    steer_angle: Array,
    sharp: SharpParameters | None,
    speed: float,
    *,
    band: tuple[float, float] = (0.1, 5.0),
    resolution: float = 0.05,
) -> FeelResponse:
    """Estimate the rendered feel theta_h / tau_r and the motorcycle's delta / tau_r (Welch).

    For any broadband probe (the chirp); a multisine is better measured by
    :func:`periodic_feel`.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform time [s].
    rider_torque, handlebar_angle, steer_angle : ndarray, shape (n,)
        tau_r [N*m], theta_h [rad], delta [rad] of a run with a broadband rider torque.
    sharp : SharpParameters or None
        The virtual motorcycle, for its linear response at ``speed`` [m/s]; None: the
        reference is the run's own delta / tau_r (the multibody motorcycle).
    band : tuple of two floats
        Frequencies kept [Hz].
    resolution : float
        Frequency resolution of the Welch estimate [Hz].

    Returns
    -------
    FeelResponse
    """
    if t.size < 16:
        raise MotosimError(f"{t.size} samples; expected a run of at least 16 to analyse")
    dt = float(np.median(np.diff(t)))
    per = min(t.size, round(1.0 / (resolution * dt)))
    f, s_tt = welch(rider_torque, fs=1.0 / dt, nperseg=per)
    _, s_th = csd(rider_torque, handlebar_angle, fs=1.0 / dt, nperseg=per)
    _, s_td = csd(rider_torque, steer_angle, fs=1.0 / dt, nperseg=per)
    _, s_hh = welch(handlebar_angle, fs=1.0 / dt, nperseg=per)
    keep = _within(f, band[0], band[1]) & (s_tt > 0)
    f = f[keep]
    steer = np.asarray(s_td[keep] / s_tt[keep], dtype=np.complex128)
    return FeelResponse(
        frequency=f,
        rendered=np.asarray(s_th[keep] / s_tt[keep], dtype=np.complex128),
        steer=steer,
        model=steer if sharp is None else _model_response(sharp, speed, f),
        coherence=np.asarray(np.abs(s_th[keep]) ** 2 / (s_tt[keep] * s_hh[keep]), dtype=float),
    )
