"""Identify J_eq, beta_eq and beta_s of eq. (5) from a logged excitation run, and validate.

:func:`identify` is the design-side entry point of the layer (pure, offline, returns a frozen
:class:`Identification`); :func:`validate` replays the measured voltage through the identified
model as in Figs. 4-5 of the paper.

Methods (section II.D, eqs. (8)-(9)):

``"output_error"`` (default)
    Batch least squares on eq. (8), then the output-error refinement of
    :mod:`motosim.identification.output_error`. The only method that is unbiased at 100 Hz,
    where the handlebar time constant (about 3 ms) is shorter than the sample period.
``"lsq"``
    Batch least squares on eq. (8) with 95 % confidence intervals.
``"rls"``
    Recursive least squares; the history of the estimate.
``"gradient"``
    The adaptive gradient law of eq. (9), sign corrected and normalised per parameter
    (:mod:`motosim.identification.gradient`); the history of the estimate.
"""

import math
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.identification.gradient import gradient_law
from motosim.identification.least_squares import batch_least_squares, recursive_least_squares
from motosim.identification.output_error import DRIVES, nrmse, refine, simulate_angle
from motosim.identification.regressors import regression
from motosim.params.handlebar import HandlebarParameters
from motosim.timeseries import TimeSeries

__all__ = [
    "METHODS",
    "Identification",
    "Validation",
    "back_emf_damping",
    "identified_parameters",
    "identify",
    "is_voltage_driven",
    "validate",
]

Array = NDArray[np.float64]
Method = Literal["output_error", "lsq", "rls", "gradient"]

METHODS: tuple[str, ...] = ("output_error", "lsq", "rls", "gradient")
"""The identification methods, the default first."""


@dataclass(frozen=True, slots=True)
class Identification:
    """Identified handlebar parameters of eq. (5) and how well they fit.

    Attributes
    ----------
    method : str
        One of :data:`METHODS`.
    J_eq : float
        Equivalent inertia [kg*m^2].
    beta_eq : float
        Equivalent viscous friction [N*m*s/rad].
    beta_s : float
        Dry friction torque [N*m].
    nrmse : float
        Normalised RMS error of the simulated angle against the measured one (0 is perfect),
        the model driven by the measured current held between samples, from the first
        measured angle, in one open-loop run.
    confidence : ndarray, shape (3, 2) or None
        95 % intervals [lower, upper] of (J_eq, beta_eq, beta_s) for ``"lsq"`` and
        ``"output_error"`` (residuals taken as independent, so optimistic); None otherwise.
    history : ndarray, shape (m, 3) or None
        Estimate after each used sample (``"rls"``, ``"gradient"``); None otherwise.
    history_t : ndarray, shape (m,) or None
        Adaptation time of each history row [s] (sample time, continued over passes).
    drive : str
        How the motor torque was taken to behave between samples, one of
        :data:`motosim.identification.output_error.DRIVES`: as given, or the one whose
        output-error fit was best.
    back_emf_damping : float
        The back-EMF damping used for a voltage-held drive [N*m*s/rad], else 0.
    """

    method: str
    J_eq: float
    beta_eq: float
    beta_s: float
    nrmse: float
    confidence: Array | None = None
    history: Array | None = None
    history_t: Array | None = None
    drive: str = "current_held"
    back_emf_damping: float = 0.0

    @property
    def parameters(self) -> Array:
        """[J_eq, beta_eq, beta_s], shape (3,)."""
        return np.array([self.J_eq, self.beta_eq, self.beta_s])


@dataclass(frozen=True, slots=True)
class Validation:
    """Identified model replayed with the measured voltage (Figs. 4-5 of the paper).

    Attributes
    ----------
    nrmse : float
        Normalised RMS error of the simulated angle against the measured one.
    t : ndarray, shape (n,)
        Sample times [s].
    theta_h : ndarray, shape (n,)
        Simulated angle [rad].
    theta_h_measured : ndarray, shape (n,)
        Measured angle [rad].
    """

    nrmse: float
    t: Array
    theta_h: Array
    theta_h_measured: Array


def back_emf_damping(hb: HandlebarParameters) -> float:
    """Damping the back-EMF adds under voltage drive, N k_t k_e N / R [N*m*s/rad].

    From eqs. (5) and (7): N k_t i_m = N k_t (u - k_e N theta_h') / R. Pass it to
    :func:`identify` when the log comes from a voltage-driven run (the voltage held between
    samples), so that the output-error model lets the current move between samples.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> back_emf_damping(load_parameters("simacom_handlebar", "handlebar"))
    6.0
    """
    return hb.torque_per_amp * hb.k_e * hb.N / hb.R


def is_voltage_driven(log: TimeSeries, *, torque_per_amp: float) -> bool:
    """Whether a log comes from a voltage drive: its current obeys eq. (7).

    True when the log has the voltage ``u`` and u = R i_m + k_e N theta_h' fits it (least
    squares for R > 0 and k_e N >= 0) with a residual below 5 % of the voltage's RMS. The
    back-EMF damping itself is better taken from the motor's constants: the differentiated
    rate of a sampled log is too smooth to estimate k_e N / R well enough for J_eq.

    Parameters
    ----------
    log : TimeSeries
        Columns ``theta_h`` [rad], ``i_m`` [A] and, for a voltage drive, ``u`` [V].
    torque_per_amp : float
        N k_t [N*m/A], for the differentiation of the regression.

    Returns
    -------
    bool
    """
    if "u" not in log.names:
        return False
    reg = regression(log, torque_per_amp=torque_per_amp)
    u = log["u"]
    X = np.column_stack([log["i_m"], reg.theta_h_dot])
    (R, ken), *_ = np.linalg.lstsq(X, u, rcond=None)
    rms = float(np.sqrt(np.mean(u**2)))
    residual = float(np.sqrt(np.mean((X @ np.array([R, ken]) - u) ** 2)))
    return bool(R > 0.0 and ken >= 0.0 and rms > 0.0 and residual < 0.05 * rms)


def identified_parameters(
    identification: Identification, hb: HandlebarParameters
) -> HandlebarParameters:
    """``hb`` with J_eq, beta_eq and beta_s replaced by the identified values.

    Raises
    ------
    MotosimError
        If the identified values are not valid handlebar parameters (for example J_eq below
        the motor's N^2 J_m).
    """
    return replace(
        hb,
        J_eq=identification.J_eq,
        beta_eq=identification.beta_eq,
        beta_s=max(identification.beta_s, 0.0),
    )


def identify(
    log: TimeSeries,
    *,
    torque_per_amp: float,
    method: Method = "output_error",
    drive: str = "auto",
    back_emf_damping: float = 0.0,
    tie_preference: str = "current_sampled",
    window: float = 0.1,
    segment: float = 1.0,
    gain: float = 10.0,
    passes: int = 30,
) -> Identification:
    """Identify J_eq, beta_eq and beta_s from an open-loop run with tau_r = 0.

    Parameters
    ----------
    log : TimeSeries
        Uniformly sampled columns ``theta_h`` [rad] and ``i_m`` [A] (others are ignored),
        the handlebar free (no rider torque) and well excited, for example by
        :func:`motosim.identification.excitation.excitation_run`.
    torque_per_amp : float
        N k_t [N*m/A], known from the motor and belt.
    method : {"output_error", "lsq", "rls", "gradient"}
        See the module docstring.
    drive : str
        What the motor torque did between samples: ``"current_held"`` (a digital current
        loop), ``"voltage_held"`` (a voltage command; the current moves with the back-EMF),
        ``"current_sampled"`` (a continuous current, only sampled), or ``"auto"``: fit each
        (``voltage_held`` only with a positive ``back_emf_damping``) and keep the one whose
        angle residual is smallest. At 100 Hz the wrong choice biases J_eq by tens of per
        cent; at 1 kHz it hardly matters.
    back_emf_damping : float
        N k_t k_e N / R [N*m*s/rad] of the motor (see :func:`back_emf_damping`), for the
        ``voltage_held`` drive.
    tie_preference : str
        With ``"auto"``, the drive taken when the residuals tie (within 0.2 %, or 1 % for
        ``"voltage_held"``): by default the sampled continuous current (interpolating samples
        is the smallest assumption about a signal between them); ``"voltage_held"`` for a log
        that looks voltage driven (see :func:`is_voltage_driven`).
    window : float
        Savitzky-Golay window of the differentiation and of the current smoothing [s].
    segment : float
        Length of the output-error segments [s]: each re-anchors the simulated angle to the
        measured one, so that current noise cannot make the open-loop angle drift.
    gain : float
        g of the gradient law [1/s].
    passes : int
        Passes of the gradient law over the log; with more than one, the estimate is the
        average over the last pass.

    Returns
    -------
    Identification
        The estimate, its fit and, per method, confidence intervals or history.

    Raises
    ------
    MotosimError
        One line: a missing column, a non-monotonic or duplicated time, a NaN, too few
        samples, too poor an excitation (regressor rank or conditioning), invalid options,
        or a gradient law that diverged.

    Notes
    -----
    The regression is eq. (8), Phi p = N k_t i_m with Phi = [theta_h'', theta_h',
    sign(theta_h')], built by :func:`motosim.identification.regressors.regression`.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> from motosim.identification.excitation import MeasurementModel, excitation_run
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> log = excitation_run(hb, "chirp", 30.0, MeasurementModel(current_noise=0.0),
    ...                      np.random.default_rng(0))
    >>> est = identify(log, torque_per_amp=hb.torque_per_amp,
    ...                back_emf_damping=back_emf_damping(hb))
    >>> bool(abs(est.beta_eq / 13.956 - 1) < 0.01 and abs(est.beta_s / 1.734 - 1) < 0.01)
    True
    """
    if method not in METHODS:
        raise MotosimError(f"method = {method!r}; expected one of {', '.join(METHODS)}")
    if drive != "auto" and drive not in DRIVES:
        raise MotosimError(f"drive = {drive!r}; expected auto or one of {', '.join(DRIVES)}")
    if tie_preference not in DRIVES:
        raise MotosimError(
            f"tie_preference = {tie_preference!r}; expected one of {', '.join(DRIVES)}"
        )
    if not (math.isfinite(back_emf_damping) and back_emf_damping >= 0.0):
        raise MotosimError(
            f"back_emf_damping = {back_emf_damping!r}; expected a finite value >= 0 [N*m*s/rad]"
        )
    reg = regression(log, torque_per_amp=torque_per_amp, window=window)
    Phi, y = reg.Phi[reg.used], reg.y[reg.used]
    p, interval = batch_least_squares(Phi, y)
    confidence: Array | None = None
    history: Array | None = None
    history_t: Array | None = None
    if method == "lsq":
        confidence = interval
    elif method == "output_error":
        fits = {
            candidate: refine(
                reg.t,
                log["theta_h"],
                reg.torque_held,
                reg.theta_h_dot,
                p,
                segment=segment,
                back_emf_damping=back_emf_damping,
                drive=candidate,
            )
            for candidate in _candidates(drive, back_emf_damping)
        }
        drive = _best_drive({name: fit[1] for name, fit in fits.items()}, tie_preference)
        p, _, half_width = fits[drive]
        confidence = np.column_stack([p - half_width, p + half_width])
    else:
        if method == "rls":
            history = recursive_least_squares(Phi, y)
        else:
            history = gradient_law(Phi, y, reg.h, gain=gain, passes=passes)
            if history.shape[0] < passes * Phi.shape[0] or not np.all(np.isfinite(history[-1])):
                raise MotosimError(
                    f"gradient law diverged after {history.shape[0]} updates; expected a "
                    f"convergent gain (gain * h = {gain * reg.h:g} < 2)"
                )
        t_used = reg.t[reg.used] - reg.t[0]
        span = float(reg.t[-1] - reg.t[0])
        history_t = np.concatenate(
            [t_used + k * span for k in range(history.shape[0] // t_used.size)]
        )
        # one pass: the final estimate; several: the average over the last pass, which
        # removes the periodic wander a constant gain keeps when the log is replayed
        p = history[-1] if method == "rls" or passes == 1 else history[-Phi.shape[0] :].mean(axis=0)
    J, beta, beta_s = (float(v) for v in p)
    # the output-error fit chose its drive; the other methods take the one replaying best
    tried = (drive,) if method == "output_error" else _candidates(drive, back_emf_damping)
    fit = dict.fromkeys(tried, math.inf)
    if J > 0.0 and beta > 0.0:
        for candidate in fit:
            sim = simulate_angle(
                reg.t,
                reg.torque_held,
                np.array([J, beta, max(beta_s, 0.0)]),
                initial_angle=log["theta_h"],
                initial_rate=reg.theta_h_dot,
                back_emf_damping=back_emf_damping,
                drive=candidate,
            )
            fit[candidate] = nrmse(sim, log["theta_h"])
    drive = min(fit, key=lambda name: fit[name])
    damping = back_emf_damping if drive == "voltage_held" else 0.0
    return Identification(
        method, J, beta, beta_s, fit[drive], confidence, history, history_t, drive, damping
    )


# residuals this close cannot tell the drives apart: 0.2 % in general; 1 % in favour of a
# voltage drive, which a voltage column obeying eq. (7) already makes likely (0.05 A of current
# noise moves the residuals of the different drives by up to 0.6 %)
_TIE = {"voltage_held": 1.01}
_TIE_DEFAULT = 1.002


def _best_drive(rms: dict[str, float], preferred: str) -> str:
    """The drive with the smallest angle residual, ``preferred`` when the residuals tie.

    They tie at a fast sample rate, or with an excitation or current noise that hides the
    inertia; the preferred drive then carries what else is known about the log.
    """
    best = min(rms, key=lambda name: rms[name])
    if preferred in rms and rms[preferred] <= _TIE.get(preferred, _TIE_DEFAULT) * rms[best]:
        return preferred
    return best


def _candidates(drive: str, back_emf_damping: float) -> tuple[str, ...]:
    """The drives to try: the one given, or all that apply."""
    if drive != "auto":
        return (drive,)
    if back_emf_damping > 0.0:
        return DRIVES
    return tuple(d for d in DRIVES if d != "voltage_held")


def validate(
    identification: Identification, log: TimeSeries, *, torque_per_amp: float
) -> Validation:
    """Replay a log through the identified model, as in Figs. 4-5 of the paper.

    The identified eq. (5) is driven by the log's measured current (N k_t i_m), between
    samples as the identification's drive says, in one open-loop run from the first measured
    angle, and compared with the measured angle. Use a run other than the one identified from
    (the paper validates on a chirp and on a bipolar rectangular voltage).

    Parameters
    ----------
    identification : Identification
        The identified parameters, drive and back-EMF damping.
    log : TimeSeries
        Uniformly sampled columns ``theta_h`` [rad] and ``i_m`` [A].
    torque_per_amp : float
        N k_t [N*m/A].

    Returns
    -------
    Validation
        The NRMSE and the simulated and measured angles.

    Raises
    ------
    MotosimError
        On a bad log or identified values the model cannot simulate (J_eq or beta_eq <= 0).
    """
    if not (identification.J_eq > 0.0 and identification.beta_eq > 0.0):
        raise MotosimError(
            f"identified J_eq = {identification.J_eq:g}, beta_eq = {identification.beta_eq:g}; "
            "expected positive values to simulate"
        )
    reg = regression(log, torque_per_amp=torque_per_amp)
    measured = log["theta_h"].copy()
    simulated = simulate_angle(
        reg.t,
        reg.torque_held,
        np.array([identification.J_eq, identification.beta_eq, max(identification.beta_s, 0.0)]),
        initial_angle=measured,
        initial_rate=reg.theta_h_dot,
        back_emf_damping=identification.back_emf_damping,
        drive=identification.drive,
    )
    return Validation(nrmse(simulated, measured), log.t.copy(), simulated, measured)
