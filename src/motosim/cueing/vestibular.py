"""Vestibular models and the scoring of a cueing run by what the rider would perceive.

Semicircular canals (angular velocity) and otoliths (specific force) after Telban &
Cardullo, *Motion Cueing Algorithm Development: Human-Centered Linear and Nonlinear
Approaches*, NASA CR-2005-213747 (2005)::

    canal:    w_hat / w = tau_a tau_L s^2 / ((tau_a s + 1)(tau_L s + 1)(tau_S s + 1))
    otolith:  f_hat / f = K (tau_a s + 1) / ((tau_L s + 1)(tau_S s + 1))

both of unit gain in their mid band, with the perception thresholds of the same report.
The numbers (:data:`TELBAN_CARDULLO_2005`): canal ``tau_L`` = 5.73 s (cupula long time
constant), ``tau_S`` = 0.005 s, ``tau_a`` = 80 s (adaptation); otolith ``K`` = 0.4, ``tau_a``
= 13.2 s, ``tau_L`` = 5.33 s, ``tau_S`` = 0.66 s, the otolith form being that of Young &
Meiry, *A revised dynamic otolith model*, Aerospace Medicine 39(6), 1968; thresholds roll
3.0, pitch 3.6, yaw 2.6 deg/s and 0.17 m/s^2 in x and y, the task-level values quoted from
Telban & Cardullo after Reid & Nahon (1985) (not checked against either report: see
:data:`THRESHOLD_ROLL`). The primary laboratory measurements are lower:
Benson, Hutt & Brown (1989) roll 2.04, pitch 2.07, yaw 1.5 deg/s; Benson, Spencer & Stott
(1986) 0.063 and 0.057 m/s^2 (:data:`BENSON_1986_1989`); each constant cites its source.
The same canal long and adaptation time constants (5.7 s, 80 s) are those of the observer
model in J. Neurophysiol. 102(4), 2232-2244, 2009 (doi:10.1152/jn.00116.2009, table 4).
tests/reference/cueing checks the poles, zeros, gains and step responses these constants
give.
:func:`score` passes the motion at the rider's head on the motorcycle and on the platform
through the same models and compares them channel by channel: roll, pitch and yaw rates
(canals) and the longitudinal and lateral specific forces (otoliths).

A *false cue* is a sample where the platform's perceived value is above threshold and the
vehicle's is not above threshold in the same direction (perceived in the wrong direction,
or perceived where the motorcycle gives nothing); a *missing cue* is a sample where the
vehicle's is above threshold and the platform's is not. Shares are fractions of the run.
"""

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from motosim.cueing.head import check_rate
from motosim.cueing.platform import Platform
from motosim.errors import MotosimError
from motosim.timeseries import TimeSeries

__all__ = [
    "BENSON_1986_1989",
    "BENSON_PITCH",
    "BENSON_ROLL",
    "BENSON_SURGE",
    "BENSON_SWAY",
    "BENSON_YAW",
    "CHANNELS",
    "TELBAN_CARDULLO_2005",
    "THRESHOLD_PITCH",
    "THRESHOLD_ROLL",
    "THRESHOLD_SURGE",
    "THRESHOLD_SWAY",
    "THRESHOLD_YAW",
    "ChannelScore",
    "CueingScore",
    "VestibularModel",
    "canal_tf",
    "limit_margins",
    "otolith_tf",
    "perceive",
    "score",
]

Array = NDArray[np.float64]

CHANNELS = ("roll", "pitch", "yaw", "surge", "sway")
"""Scored channels: canal roll, pitch, yaw rates; otolith longitudinal, lateral force."""
_SOURCES = ("omega_x", "omega_y", "omega_z", "f_x", "f_y")


@dataclass(frozen=True, slots=True)
class VestibularModel:
    """Time constants [s], otolith gain and perception thresholds of the vestibular system.

    Attributes
    ----------
    canal_tau_L, canal_tau_S, canal_tau_a : float
        Canal long, short and adaptation time constants [s].
    otolith_K : float
        Otolith gain (its DC gain; mid-band gain ``K tau_a / tau_L``).
    otolith_tau_a, otolith_tau_L, otolith_tau_S : float
        Otolith lead, long and short time constants [s].
    thresholds : tuple of float
        Thresholds of :data:`CHANNELS`: roll, pitch, yaw rate [rad/s], longitudinal and
        lateral specific force [m/s^2].
    """

    canal_tau_L: float
    canal_tau_S: float
    canal_tau_a: float
    otolith_K: float
    otolith_tau_a: float
    otolith_tau_L: float
    otolith_tau_S: float
    thresholds: tuple[float, float, float, float, float]

    def __post_init__(self) -> None:
        values = [
            getattr(self, n)
            for n in (
                "canal_tau_L",
                "canal_tau_S",
                "canal_tau_a",
                "otolith_K",
                "otolith_tau_a",
                "otolith_tau_L",
                "otolith_tau_S",
            )
        ]
        if not all(math.isfinite(v) and v > 0 for v in [*values, *self.thresholds]) or len(
            self.thresholds
        ) != len(CHANNELS):
            raise MotosimError(
                f"vestibular model {values} thresholds {self.thresholds}; expected finite "
                f"numbers > 0 and {len(CHANNELS)} thresholds"
            )


_D = math.pi / 180.0

# Perception thresholds, each beside its source. Rotation thresholds are on the angular
# velocity [rad/s], specific-force thresholds on the force [m/s^2].
THRESHOLD_ROLL = 3.0 * _D
"""Roll rate [rad/s]: the value quoted from Telban & Cardullo (2005) after Reid & Nahon
(1985), UTIAS Report 296. Not checked: neither report could be consulted for this package,
and no primary text giving these numbers was found; they are a task-level (pilot in the
loop) value, consistent in kind with Samji & Reid, *The detection of low-amplitude yawing
motion transients in a flight simulator*, IEEE Trans. Syst. Man Cybern. 22(2):300-306,
1992 (abstract: detection levels rise significantly when the pilot controls the simulator
instead of observing), and 1.5 to 3 times the laboratory values of :data:`BENSON_ROLL`."""
THRESHOLD_PITCH = 3.6 * _D
"""Pitch rate [rad/s]: same table as :data:`THRESHOLD_ROLL`."""
THRESHOLD_YAW = 2.6 * _D
"""Yaw rate [rad/s]: same table as :data:`THRESHOLD_ROLL`."""
THRESHOLD_SURGE = 0.17
"""Longitudinal specific force [m/s^2]: same table as :data:`THRESHOLD_ROLL`."""
THRESHOLD_SWAY = 0.17
"""Lateral specific force [m/s^2]: same table as :data:`THRESHOLD_ROLL`."""

BENSON_ROLL = 2.04 * _D
"""Roll (x-axis) direction-recognition threshold [rad/s], peak velocity of a 3.3 s
cosine-bell rotation in the dark, mean of 20 subjects: Benson, Hutt & Brown, *Thresholds for
the perception of whole body angular movement about a vertical axis*, Aviat. Space Environ.
Med. 60(3):205-213, 1989 (abstract)."""
BENSON_PITCH = 2.07 * _D
"""Pitch (y-axis) threshold [rad/s]: Benson, Hutt & Brown (1989), as :data:`BENSON_ROLL`."""
BENSON_YAW = 1.5 * _D
"""Yaw (z-axis) threshold [rad/s], mean of 30 subjects: Benson, Hutt & Brown (1989)."""
BENSON_SURGE = 0.063
"""Longitudinal (x-axis) direction-detection threshold [m/s^2], peak acceleration of a 3 s
cosine-bell velocity in the dark, mean of 24 subjects: Benson, Spencer & Stott, *Thresholds
for the detection of the direction of whole-body, linear movement in the horizontal plane*,
Aviat. Space Environ. Med. 57(11):1088-1096, 1986 (abstract)."""
BENSON_SWAY = 0.057
"""Lateral (y-axis) threshold [m/s^2]: Benson, Spencer & Stott (1986)."""

TELBAN_CARDULLO_2005 = VestibularModel(
    canal_tau_L=5.73,
    canal_tau_S=0.005,
    canal_tau_a=80.0,
    otolith_K=0.4,
    otolith_tau_a=13.2,
    otolith_tau_L=5.33,
    otolith_tau_S=0.66,
    thresholds=(THRESHOLD_ROLL, THRESHOLD_PITCH, THRESHOLD_YAW, THRESHOLD_SURGE, THRESHOLD_SWAY),
)
"""Telban & Cardullo (2005), NASA CR-2005-213747: canal and otolith models and their
thresholds (roll 3.0, pitch 3.6, yaw 2.6 deg/s; 0.17 m/s^2 in x and y). The default of the
score and of the MPC's scaling."""

BENSON_1986_1989 = replace(
    TELBAN_CARDULLO_2005,
    thresholds=(BENSON_ROLL, BENSON_PITCH, BENSON_YAW, BENSON_SURGE, BENSON_SWAY),
)
"""The same models with the laboratory thresholds of Benson et al. (1986, 1989): roll 2.04,
pitch 2.07, yaw 1.5 deg/s; 0.063 and 0.057 m/s^2. Direction recognition of passive motion
in the dark, 1.5 to 3 times below the task-level values of :data:`TELBAN_CARDULLO_2005`: a
stricter score of false cues (the washout's 3 deg/s tilt rate is above them)."""


def canal_tf(model: VestibularModel) -> tuple[Array, Array]:
    """Canal transfer function ``(num, den)``, highest power of s first."""
    ta, tl, ts = model.canal_tau_a, model.canal_tau_L, model.canal_tau_S
    den = np.array([ta * tl * ts, ta * tl + ta * ts + tl * ts, ta + tl + ts, 1.0])
    return np.array([ta * tl, 0.0, 0.0]), den


def otolith_tf(model: VestibularModel) -> tuple[Array, Array]:
    """Otolith transfer function ``(num, den)``, highest power of s first."""
    k, ta, tl, ts = model.otolith_K, model.otolith_tau_a, model.otolith_tau_L, model.otolith_tau_S
    return np.array([k * ta, k]), np.array([tl * ts, tl + ts, 1.0])


def _filter(num: Array, den: Array, x: Array, dt: float) -> Array:
    from scipy.signal import bilinear, lfilter, lfilter_zi

    b, a = bilinear(num, den, fs=1.0 / dt)
    zi = lfilter_zi(b, a) * x[0]  # start in the steady state of the first sample
    y: Array = lfilter(b, a, x, zi=zi)[0]
    return y


def perceive(model: VestibularModel, motion: TimeSeries) -> TimeSeries:
    """Perceived motion of :data:`CHANNELS` for a motion at the head.

    Parameters
    ----------
    model : VestibularModel
        For example :data:`TELBAN_CARDULLO_2005`.
    motion : TimeSeries
        Head motion with ``omega_x``, ``omega_y``, ``omega_z`` [rad/s], ``f_x``, ``f_y``
        [m/s^2] at a constant rate (:func:`motosim.cueing.head.vehicle_motion`).

    Returns
    -------
    TimeSeries
        Columns :data:`CHANNELS` in the units of their inputs, the models discretised with
        Tustin and started in the steady state of the first sample.
    """
    dt = check_rate(motion.t)
    canal, otolith = canal_tf(model), otolith_tf(model)
    cols = []
    for name in _SOURCES:
        num, den = canal if name.startswith("omega") else otolith
        cols.append(_filter(num, den, motion[name], dt))
    return TimeSeries(motion.t, np.column_stack(cols), CHANNELS)


@dataclass(frozen=True, slots=True)
class ChannelScore:
    """Comparison of the perceived platform motion with the perceived vehicle motion.

    Attributes
    ----------
    rms_error : float
        RMS of the difference, in the channel's unit.
    correlation : float
        Pearson correlation (NaN when a signal is constant).
    lag : float
        Delay of the platform's perception that maximises the cross-correlation, within
        +/- 1 s [s] (positive: the platform is late).
    false_cue_share, missing_cue_share : float
        Fractions of the samples with a false or a missing cue (module docstring).
    """

    rms_error: float
    correlation: float
    lag: float
    false_cue_share: float
    missing_cue_share: float


@dataclass(frozen=True, slots=True)
class CueingScore:
    """Scores of one cueing run.

    Attributes
    ----------
    channels : dict of str to ChannelScore
        One entry per name of :data:`CHANNELS`.
    margins : dict of str to tuple of float
        For ``"angle"``, ``"rate"`` and ``"accel"``, the smallest remaining fraction of the
        limit over the run, per axis (roll, pitch, yaw); negative means a violation.
    violations : int
        Samples beyond an angle, rate or acceleration limit (with a 1e-9 relative tolerance).
    """

    channels: dict[str, ChannelScore]
    margins: dict[str, tuple[float, float, float]]
    violations: int


def _lag(vehicle: Array, platform: Array, dt: float) -> float:
    from scipy.signal import correlate

    a, b = vehicle - vehicle.mean(), platform - platform.mean()
    if not (np.any(a) and np.any(b)):
        return math.nan
    full = correlate(b, a, mode="full", method="fft")
    zero = a.size - 1
    span = min(round(1.0 / dt), a.size - 1)
    window = full[zero - span : zero + span + 1]
    return float((int(np.argmax(window)) - span) * dt)


def _channel(vehicle: Array, platform: Array, threshold: float, dt: float) -> ChannelScore:
    err = platform - vehicle
    if np.std(vehicle) > 0 and np.std(platform) > 0:
        corr = float(np.corrcoef(vehicle, platform)[0, 1])
    else:
        corr = math.nan
    felt_v = np.where(np.abs(vehicle) > threshold, np.sign(vehicle), 0.0)
    felt_p = np.where(np.abs(platform) > threshold, np.sign(platform), 0.0)
    false = np.mean((felt_p != 0) & (felt_p != felt_v))
    missing = np.mean((felt_v != 0) & (felt_p == 0))
    return ChannelScore(
        rms_error=float(np.sqrt(np.mean(err**2))),
        correlation=corr,
        lag=_lag(vehicle, platform, dt),
        false_cue_share=float(false),
        missing_cue_share=float(missing),
    )


def limit_margins(
    platform: Platform, commands: Array, dt: float
) -> tuple[dict[str, tuple[float, float, float]], int]:
    """Smallest remaining fraction of each limit and the number of violations.

    Parameters
    ----------
    platform : Platform
        The limits.
    commands : ndarray, shape (n, 3)
        Platform roll, pitch, yaw [rad], from neutral rest before the first sample.
    dt : float
        Sample period [s].

    Returns
    -------
    margins : dict
        ``{"angle": (roll, pitch, yaw), "rate": ..., "accel": ...}``, ``1 - max|x| / limit``;
        0 for a peak at its limit within the violations' tolerance (the rounding of the rate
        and acceleration differenced from the angles, about 1e-15 of the limit, is not
        reported as a negative margin).
    violations : int
        Samples beyond a limit by more than 1e-9 of it (and 1e-6 rad/s^2 for accelerations).

    Examples
    --------
    A roll ramp at exactly the SIMACOM-like platform's roll rate limit, 0.2 s at 100 Hz
    from rest (differenced, its rate is up to 1.6e-15 of the limit beyond it; its start is
    an acceleration far beyond that limit, the one violation):

    >>> from motosim.cueing import load_platform
    >>> platform = load_platform("simacom_platform").platform
    >>> ramp = np.zeros((20, 3))
    >>> ramp[:, 0] = platform.axes[0].rate * 0.01 * np.arange(1, 21)
    >>> margins, violations = limit_margins(platform, ramp, 0.01)
    >>> margins["rate"][0], round(margins["angle"][0], 6), violations
    (0.0, 0.7, 1)
    """
    x = np.asarray(commands, dtype=np.float64)
    padded = np.vstack([np.zeros((2, 3)), x])
    v = np.diff(padded, axis=0)[1:] / dt
    a = np.diff(padded, n=2, axis=0) / dt**2
    margins: dict[str, tuple[float, float, float]] = {}
    violations = 0
    for key, values in (("angle", x), ("rate", v), ("accel", a)):
        limits = np.array([getattr(ax, key) for ax in platform.axes])
        peak = np.max(np.abs(values), axis=0) if values.size else np.zeros(3)
        slack = 1e-9 * limits + (1e-6 if key == "accel" else 0.0)
        margin = np.where(
            peak <= limits + slack, np.maximum(1 - peak / limits, 0.0), 1 - peak / limits
        )
        margins[key] = (float(margin[0]), float(margin[1]), float(margin[2]))
        violations += int(np.sum(np.abs(values) > limits + slack))
    return margins, violations


def score(
    model: VestibularModel,
    vehicle: TimeSeries,
    platform_motion: TimeSeries,
    platform: Platform,
    commands: Array,
) -> CueingScore:
    """Score a cueing run by the rider's perception and the platform's limits.

    Parameters
    ----------
    model : VestibularModel
        The vestibular model and thresholds.
    vehicle, platform_motion : TimeSeries
        Head motion on the motorcycle and on the platform, same instants
        (:func:`motosim.cueing.head.vehicle_motion`, :func:`~motosim.cueing.head.platform_motion`).
    platform : Platform
        The limits.
    commands : ndarray, shape (n, 3)
        The platform commands [rad] whose limit margins are reported.

    Returns
    -------
    CueingScore
        Per channel scores, limit margins and violations.

    Raises
    ------
    MotosimError
        If the two motions are not on the same instants.
    """
    if vehicle.t.shape != platform_motion.t.shape or not np.allclose(vehicle.t, platform_motion.t):
        raise MotosimError(
            f"vehicle ({vehicle.t.size} samples) and platform ({platform_motion.t.size}) "
            "motions; expected the same instants"
        )
    dt = check_rate(vehicle.t)
    pv, pp = perceive(model, vehicle), perceive(model, platform_motion)
    channels = {
        name: _channel(pv[name], pp[name], model.thresholds[i], dt)
        for i, name in enumerate(CHANNELS)
    }
    margins, violations = limit_margins(platform, commands, dt)
    return CueingScore(channels, margins, violations)
