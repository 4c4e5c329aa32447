"""Classical washout for a rotational-only platform (roll, pitch, yaw).

The structure is the rotational part of the classical algorithm of Reid & Nahon (1985),
*Flight simulation motion-base drive algorithms: part 1*, UTIAS Report 296, with the
motorcycle-specific choices of the riding-simulator literature (sustained roll, a separate
visual-horizon roll; Lobjois et al., Ergonomics 2016; Barbagli et al., IEEE VR 2001):

- roll: the scaled lean with a soft saturation, ``L tanh(k phi / L)``, plus an onset cue
  ``k_o s^2 / (s^2 + 2 zeta w s + w^2) phi`` (the high-passed roll rate, integrated);
- pitch: tilt coordination, ``asin(k a_x / g)`` through ``w^2 / (s^2 + 2 zeta w s + w^2)``
  and a rate limit below the pitch perception threshold, plus the high-passed
  motorcycle pitch ``k s^2 / (s^2 + 2 zeta w s + w^2) theta``;
- yaw: the 2nd-order high-passed yaw rate integrated, ``k s / (s^2 + 2 zeta w s + w^2)
  psi_dot``;
- visual horizon: the roll of the horizon on the screen (which rolls with the platform)
  that makes the total visual roll ``k_v phi``: ``k_v phi - phi_s``.

:func:`design_washout` gives the discrete (Tustin) coefficients at the loop rate,
:func:`washout_step` is the compiled one-sample step and :func:`apply_washout` runs a whole
series. The commands still go through :mod:`motosim.cueing.limits`.
"""

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from motosim.cueing.filters import highpass2, lowpass2, tustin
from motosim.cueing.platform import WashoutTuning
from motosim.errors import MotosimError

__all__ = [
    "WASHOUT_OUTPUTS",
    "WASHOUT_STATE_SIZE",
    "WashoutDesign",
    "apply_washout",
    "design_washout",
    "washout_step",
]

Array = NDArray[np.float64]

WASHOUT_OUTPUTS = ("phi_s", "theta_s", "psi_s", "phi_vis")
"""Outputs of :func:`washout_step`, in order (see :mod:`motosim.signals`)."""
WASHOUT_STATE_SIZE = 9
"""Length of the state array of :func:`washout_step`."""

# Layout of the packed coefficient array.
_ROLL, _TILT, _PITCH, _YAW = 0, 5, 10, 15
_ROLL_SCALE, _ROLL_MAX, _TILT_SCALE, _TILT_STEP, _HORIZON, _G = 20, 21, 22, 23, 24, 25


@dataclass(frozen=True, slots=True)
class WashoutDesign:
    """Discrete washout at one loop rate.

    Attributes
    ----------
    dt : float
        Loop period [s].
    roll_onset, tilt, pitch_onset, yaw : tuple of float
        Tustin sections ``[c0, c1, c2, d1, d2]`` (see :mod:`motosim.cueing.filters`).
    roll_scale : float
        Gain from lean to sustained platform roll.
    roll_sustained : float
        Soft saturation level of the sustained roll [rad].
    tilt_scale : float
        Gain on ``a_x / g`` before the arcsine.
    tilt_step : float
        Largest tilt-coordination change per step [rad] (rate limit times ``dt``).
    horizon_gain : float
        Total visual roll per unit lean.
    g : float
        Gravitational acceleration [m/s^2].
    """

    dt: float
    roll_onset: tuple[float, ...]
    tilt: tuple[float, ...]
    pitch_onset: tuple[float, ...]
    yaw: tuple[float, ...]
    roll_scale: float
    roll_sustained: float
    tilt_scale: float
    tilt_step: float
    horizon_gain: float
    g: float

    def coefficients(self) -> Array:
        """The packed coefficient array that :func:`washout_step` reads, shape (26,)."""
        return np.array(
            [
                *self.roll_onset,
                *self.tilt,
                *self.pitch_onset,
                *self.yaw,
                self.roll_scale,
                self.roll_sustained,
                self.tilt_scale,
                self.tilt_step,
                self.horizon_gain,
                self.g,
            ],
            dtype=np.float64,
        )


def design_washout(tuning: WashoutTuning, dt: float, *, g: float = 9.81) -> WashoutDesign:
    """Discretise the washout of the module docstring at the loop period ``dt``.

    Parameters
    ----------
    tuning : WashoutTuning
        Gains, frequencies [rad/s], dampings, the sustained-roll level [rad] and the
        tilt-rate limit [rad/s].
    dt : float
        Loop period [s].
    g : float, optional
        Gravitational acceleration [m/s^2].

    Returns
    -------
    WashoutDesign
        The discrete coefficients.

    Raises
    ------
    MotosimError
        If ``dt`` is not positive or a filter corner is above 0.2 of the Nyquist frequency
        (where Tustin's frequency warping exceeds the 1 % design tolerance).

    Examples
    --------
    >>> from motosim.cueing.platform import load_platform
    >>> d = design_washout(load_platform("simacom_platform").washout, 0.01)
    >>> round(math.degrees(d.tilt_step / d.dt), 6)
    3.0
    """
    if not (math.isfinite(dt) and dt > 0.0):
        raise MotosimError(f"loop period dt = {dt!r}; expected a finite number > 0 [s]")
    nyquist = math.pi / dt
    for name in (
        "roll_onset_frequency",
        "tilt_frequency",
        "pitch_onset_frequency",
        "yaw_frequency",
    ):
        w = getattr(tuning, name)
        if w > 0.2 * nyquist:
            raise MotosimError(
                f"washout {name} = {w:g} rad/s; expected <= {0.2 * nyquist:g} rad/s "
                f"(0.2 of the Nyquist frequency at dt = {dt:g} s)"
            )
    wy, zy = tuning.yaw_frequency, tuning.yaw_damping
    return WashoutDesign(
        dt=dt,
        roll_onset=tuple(
            highpass2(
                tuning.roll_onset_gain, tuning.roll_onset_frequency, tuning.roll_onset_damping, dt
            )
        ),
        tilt=tuple(lowpass2(1.0, tuning.tilt_frequency, tuning.tilt_damping, dt)),
        pitch_onset=tuple(
            highpass2(
                tuning.pitch_onset_gain,
                tuning.pitch_onset_frequency,
                tuning.pitch_onset_damping,
                dt,
            )
        ),
        yaw=tuple(tustin((tuning.yaw_gain, 0.0), (1.0, 2 * zy * wy, wy * wy), dt)),
        roll_scale=tuning.roll_scale,
        roll_sustained=tuning.roll_sustained,
        tilt_scale=tuning.tilt_scale,
        tilt_step=tuning.tilt_rate * dt,
        horizon_gain=tuning.horizon_gain,
        g=g,
    )


@njit(cache=True, inline="always")
def _section(coef: Array, c: int, state: Array, s: int, x: float) -> float:
    y = coef[c] * x + state[s]
    state[s] = coef[c + 1] * x - coef[c + 3] * y + state[s + 1]
    state[s + 1] = coef[c + 2] * x - coef[c + 4] * y
    return float(y)


@njit(cache=True)
def washout_step(
    coef: Array, state: Array, phi: float, theta: float, a_x: float, psi_dot: float, out: Array
) -> None:
    """One loop step of the washout.

    Parameters
    ----------
    coef : ndarray, shape (26,)
        :meth:`WashoutDesign.coefficients`.
    state : ndarray, shape (9,)
        Filter and rate-limiter states, updated in place (zeros at rest).
    phi : float
        Motorcycle lean [rad].
    theta : float
        Motorcycle suspension pitch [rad].
    a_x : float
        Longitudinal acceleration [m/s^2].
    psi_dot : float
        Yaw rate [rad/s].
    out : ndarray, shape (4,)
        Written: platform roll, pitch, yaw commands and the visual-horizon roll [rad]
        (:data:`WASHOUT_OUTPUTS`), before the limit manager.
    """
    level = coef[_ROLL_MAX]
    sustained = level * math.tanh(coef[_ROLL_SCALE] * phi / level) if level > 0.0 else 0.0
    roll = sustained + _section(coef, _ROLL, state, 0, phi)
    ratio = min(1.0, max(-1.0, coef[_TILT_SCALE] * a_x / coef[_G]))
    tilt = _section(coef, _TILT, state, 2, math.asin(ratio))
    step = coef[_TILT_STEP]
    state[8] += min(step, max(-step, tilt - state[8]))
    out[0] = roll
    out[1] = state[8] + _section(coef, _PITCH, state, 4, theta)
    out[2] = _section(coef, _YAW, state, 6, psi_dot)
    out[3] = coef[_HORIZON] * phi - roll


@njit(cache=True)
def _washout_run(coef: Array, inputs: Array, out: Array) -> None:
    state = np.zeros(WASHOUT_STATE_SIZE)
    for k in range(inputs.shape[0]):
        washout_step(coef, state, inputs[k, 0], inputs[k, 1], inputs[k, 2], inputs[k, 3], out[k])


def apply_washout(design: WashoutDesign, inputs: Array) -> Array:
    """Run the washout over a whole series from rest.

    Parameters
    ----------
    design : WashoutDesign
        From :func:`design_washout`, at the series' sample period.
    inputs : ndarray, shape (n, 4)
        Columns lean ``phi`` [rad], pitch ``theta`` [rad], ``a_x`` [m/s^2], ``psi_dot``
        [rad/s].

    Returns
    -------
    ndarray, shape (n, 4)
        Columns :data:`WASHOUT_OUTPUTS` [rad].

    Raises
    ------
    MotosimError
        If ``inputs`` is not (n, 4) and finite.
    """
    x = np.ascontiguousarray(inputs, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 4 or not np.all(np.isfinite(x)):
        raise MotosimError(f"washout inputs of shape {x.shape}; expected finite (n, 4)")
    out = np.empty((x.shape[0], 4))
    _washout_run(design.coefficients(), x, out)
    return out
