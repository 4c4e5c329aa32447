"""The rendered steering feel: what the rider feels through the handlebar, against the machine.

The torque feedback should make the handlebar in the rider's hands move as the virtual
motorcycle's front assembly would: then the response from the rider's torque to the
handlebar angle equals the motorcycle's own response from steer torque to steer angle. The
ratio of the two is the haptic *transparency* of the simulator. :func:`feel_scenario` builds a
run that measures it (the virtual rider holds a straight at a speed while a chirp torque is
added to the rider's), and :func:`rendered_feel` estimates both frequency responses from the
run (Welch cross-spectra, the rider's torque as input) and compares them with the linear
model's delta / tau_r at that speed.
"""

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import csd, welch

from motosim.control.statespace import frequency_response
from motosim.errors import MotosimError
from motosim.model import sharp as sharp_model
from motosim.params.sharp import SharpParameters
from motosim.sim.scenario import ChirpProfile, Rider, Scenario, StraightPath

__all__ = ["FeelResponse", "feel_scenario", "rendered_feel"]

Array = NDArray[np.float64]


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
        delta / tau_r of the linear model at the run's speed [rad/(N*m)].
    coherence : ndarray, shape (m,)
        Coherence of tau_r and theta_h (1: the response is linear and noise-free).
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

    def worst(self, low: float, high: float) -> tuple[float, float]:
        """Largest |magnitude error| [dB] and |phase error| [deg] over ``low``-``high`` [Hz]."""
        band = _within(self.frequency, low, high)
        if not band.any():
            raise MotosimError(f"no frequency of the response within {low:g}-{high:g} Hz")
        return (
            float(np.max(np.abs(self.magnitude_error_db[band]))),
            float(np.max(np.abs(self.phase_error_deg[band]))),
        )


def feel_scenario(
    base: Scenario,
    *,
    speed: float,
    amplitude: float = 3.0,
    band: tuple[float, float] = (0.1, 5.0),
    duration: float = 60.0,
) -> Scenario:
    """``base`` turned into a feel measurement: a straight at ``speed`` [m/s], a chirp probe.

    The virtual rider holds the straight (the machine is unstable on its own above the
    capsize speed) while a chirp of ``amplitude`` [N*m] sweeping ``band`` [Hz] over
    ``duration`` [s] is added to the rider's torque; handlebar, estimator, controller and
    rates stay the base's.
    """
    if not (math.isfinite(amplitude) and 0 < amplitude <= 50.0):
        raise MotosimError(f"amplitude = {amplitude!r}; expected a torque in (0, 50] N*m")
    low, high = band
    if not (0 < low < high <= 20.0):
        raise MotosimError(f"band = {low:g}:{high:g}; expected 0 < low < high <= 20 Hz")
    rider = Rider(
        "virtual", path=StraightPath(), probe=ChirpProfile(amplitude, low, high, start=0.0)
    )
    motorcycle = dataclasses.replace(base.motorcycle, speed=speed)
    return dataclasses.replace(
        base, name=f"{base.name}_feel", duration=duration, rider=rider, motorcycle=motorcycle
    )


def rendered_feel(
    t: Array,
    rider_torque: Array,
    handlebar_angle: Array,
    steer_angle: Array,
    sharp: SharpParameters,
    speed: float,
    *,
    band: tuple[float, float] = (0.1, 5.0),
    resolution: float = 0.05,
) -> FeelResponse:
    """Estimate the rendered feel theta_h / tau_r and the motorcycle's delta / tau_r.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Uniform time [s].
    rider_torque, handlebar_angle, steer_angle : ndarray, shape (n,)
        tau_r [N*m], theta_h [rad], delta [rad] of a run with a broadband rider torque.
    sharp : SharpParameters
        The virtual motorcycle, for its linear response at ``speed`` [m/s].
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
    lin = sharp_model.linearize(sharp, speed)
    row = sharp_model.STATE_NAMES.index("delta")
    model = np.array([frequency_response(lin, 2 * math.pi * fk)[row, 0] for fk in f])
    return FeelResponse(
        frequency=f,
        rendered=np.asarray(s_th[keep] / s_tt[keep], dtype=np.complex128),
        steer=np.asarray(s_td[keep] / s_tt[keep], dtype=np.complex128),
        model=model.astype(np.complex128),
        coherence=np.asarray(np.abs(s_th[keep]) ** 2 / (s_tt[keep] * s_hh[keep]), dtype=float),
    )
