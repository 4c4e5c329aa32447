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
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_coeffs, savgol_filter

from motosim.errors import MotosimError
from motosim.identification.gradient import gradient_law
from motosim.identification.least_squares import batch_least_squares, recursive_least_squares
from motosim.identification.output_error import DRIVES, nrmse, refine, simulate_angle
from motosim.identification.regressors import Regression, check_log, regression
from motosim.params.handlebar import HandlebarParameters
from motosim.timeseries import TimeSeries

__all__ = [
    "DRIVE_COLUMNS",
    "METHODS",
    "MODEL_ALLOWANCE",
    "WEAK_INERTIA",
    "Identification",
    "Validation",
    "back_emf_damping",
    "current_noise",
    "drive_from_columns",
    "identified_parameters",
    "identify",
    "is_voltage_driven",
    "validate",
]

Array = NDArray[np.float64]
Method = Literal["output_error", "lsq", "rls", "gradient"]

METHODS: tuple[str, ...] = ("output_error", "lsq", "rls", "gradient")
"""The identification methods, the default first."""

MODEL_ALLOWANCE: tuple[float, float, float] = (0.01, 0.008, 0.008)
"""Relative systematic allowance on (J_eq, beta_eq, beta_s) added to the output-error intervals.

The fit models dry friction as exact Coulomb with Karnopp sticking. On rigs whose friction is
smooth near zero speed, beta_s tanh(theta_h' / w) with w = 1e-3 rad/s, the estimates moved
by up to 1.2 %, 0.85 % and 0.72 % (statistical error included; handlebars of J/beta 1.5 to
13 ms at 100 Hz and 1 kHz, the rig of the reference tests), partly outside the statistical
intervals; this allowance, added in quadrature, covers it. A wider smoothing
(w = 1e-2 rad/s) is another friction law: J_eq then errs by 4-10 % and beta_s by 3-8 %.
"""

WEAK_INERTIA = 0.10
"""Relative 95 % half-width of J_eq above which the inertia is reported weakly identified."""


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
        the model driven by the measured current (between samples as ``drive`` says), from
        the first measured angle, in one open-loop run.
    confidence : ndarray, shape (3, 2) or None
        95 % intervals [lower, upper] of (J_eq, beta_eq, beta_s): for ``"output_error"``
        from the fit's Jacobian (cluster-robust) and an encoder bootstrap (see
        :func:`motosim.identification.output_error.refine`) with :data:`MODEL_ALLOWANCE`
        added in quadrature, for ``"lsq"`` from the
        regression with independent residuals (optimistic); None otherwise.
    history : ndarray, shape (m, 3) or None
        Estimate after each used sample (``"rls"``, ``"gradient"``); None otherwise.
    history_t : ndarray, shape (m,) or None
        Adaptation time of each history row [s] (sample time, continued over passes).
    drive : str
        How the motor torque was taken to behave between samples, one of
        :data:`motosim.identification.output_error.DRIVES`: as given, or as the log's
        columns say (:func:`drive_from_columns`).
    back_emf_damping : float
        The back-EMF damping used for a voltage-held drive [N*m*s/rad], else 0.
    drive_reason : str
        Why that drive: the log's columns, or "given".
    warnings : tuple of str
        One line each: a weakly identified inertia, with the excitation that would fix it.
    segment_nrmse : float
        For ``"output_error"``, the NRMSE the fit minimised: the model restarted from the
        measured angle every ``segment`` seconds, each segment's mean offset removed. It is
        smaller than :attr:`nrmse`, whose single open-loop run over the whole log lets a
        small torque offset or a stick-slip position error accumulate; NaN otherwise.
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
    drive_reason: str = ""
    warnings: tuple[str, ...] = ()
    segment_nrmse: float = math.nan

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
    current : ndarray, shape (n,)
        The current that drove the model [A] (``i_m``, or ``i_cmd`` for a held set-point).
    """

    nrmse: float
    t: Array
    theta_h: Array
    theta_h_measured: Array
    current: Array


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


DRIVE_COLUMNS: dict[str, str] = {
    "i_m": "measured motor current [A]: continuous, sampled by the drive or a sensor",
    "i_cmd": "commanded current set-point [A], held between samples by a current drive",
    "u": "commanded voltage [V], held between samples by a voltage drive",
}
"""The log's current and voltage columns and what each means for the drive."""


def drive_from_columns(names: Sequence[str]) -> tuple[str, str]:
    """The inter-sample drive model that a log's columns say, and why.

    ======================  ===================  ==========================================
    columns                 drive                torque between samples
    ======================  ===================  ==========================================
    ``i_cmd`` (+ ``i_m``)   ``current_held``     N k_t i_cmd, held
    ``u`` + ``i_m``         ``voltage_held``     N k_t i_m, moved by the back-EMF, eq. (7)
    ``i_m`` only            ``current_sampled``  N k_t i_m, interpolated (cubic)
    ======================  ===================  ==========================================

    Parameters
    ----------
    names : sequence of str
        The log's columns.

    Returns
    -------
    drive : str
        One of :data:`motosim.identification.output_error.DRIVES`.
    reason : str
        The columns that decided it, for the user.

    Raises
    ------
    MotosimError
        When the columns do not decide (``i_cmd`` and ``u`` both, ``u`` without ``i_m``) or
        there is no current column; the message names the ``--drive`` option.

    Examples
    --------
    >>> drive_from_columns(["theta_h", "i_m"])[0]
    'current_sampled'
    """
    have = set(names)
    if "i_cmd" in have and "u" in have:
        raise MotosimError(
            "log has both i_cmd (a held current set-point) and u (a held voltage); cannot tell "
            "which the drive held: give --drive current_held or --drive voltage_held"
        )
    if "i_cmd" in have:
        return "current_held", "i_cmd: a current set-point held by a current drive"
    if "u" in have:
        if "i_m" not in have:
            raise MotosimError(
                "log has a voltage u but no measured current i_m; expected i_m [A] with u "
                "(or a log with i_cmd and --drive current_held)"
            )
        return "voltage_held", "u: a voltage held by a voltage drive, i_m its measured current"
    if "i_m" in have:
        return "current_sampled", "i_m only: a measured continuous current, sampled"
    raise MotosimError(
        f"log has no current column (have {', '.join(names) or 'none'}); expected i_m "
        "(measured current [A]) or i_cmd (held current set-point [A])"
    )


def current_noise(current: Array) -> float:
    """Standard deviation of the white noise on a sampled current [A].

    The residual of a cubic Savitzky-Golay fit over 7 samples, scaled to the noise it leaves
    (the fit follows a signal sampled at 25 or more samples per period to 1e-3).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> t = np.arange(20000) * 1e-3
    >>> round(current_noise(np.sin(2 * np.pi * t) + 0.005 * rng.standard_normal(t.size)), 4)
    0.005
    """
    if current.size < 7:
        return 0.0
    residual = current - savgol_filter(current, 7, 3)
    centre = float(savgol_coeffs(7, 3)[3])
    return float(np.std(residual[3:-3]) / math.sqrt(1.0 - centre))


def identify(
    log: TimeSeries,
    *,
    torque_per_amp: float,
    method: Method = "output_error",
    drive: str = "auto",
    back_emf_damping: float = 0.0,
    current_delay: float = 0.0,
    window: float = 0.1,
    segment: float = 1.0,
    gain: float = 10.0,
    passes: int = 30,
    replicates: int = 8,
    rng: np.random.Generator | None = None,
) -> Identification:
    """Identify J_eq, beta_eq and beta_s from an open-loop run with tau_r = 0.

    Parameters
    ----------
    log : TimeSeries
        Uniformly sampled columns ``theta_h`` [rad] and a current, ``i_m`` (measured) or
        ``i_cmd`` (held set-point) [A], and ``u`` [V] for a voltage drive (see
        :data:`DRIVE_COLUMNS`), the handlebar free (no rider torque) and well excited, for
        example by :func:`motosim.identification.excitation.excitation_run`. The log may
        start with the handlebar moving, and the encoder may have any fixed offset.
    torque_per_amp : float
        N k_t [N*m/A], known from the motor and belt.
    method : {"output_error", "lsq", "rls", "gradient"}
        See the module docstring.
    drive : str
        What the motor torque did between samples: ``"current_held"`` (a digital current
        loop), ``"voltage_held"`` (a voltage command; the current moves with the back-EMF),
        ``"current_sampled"`` (a continuous current, only sampled), or ``"auto"``: as the
        log's columns say (:func:`drive_from_columns`). At 100 Hz the wrong choice biases
        J_eq by tens of per cent; the angle residuals of the drives are no guide (a wrong
        model with a smaller inertia fits the half-sample lag as well).
    back_emf_damping : float
        N k_t k_e N / R [N*m*s/rad] of the motor (see :func:`back_emf_damping`), required
        by the ``voltage_held`` drive.
    current_delay : float
        How late the logged current is [s] (>= 0): the value logged at t_k was measured at
        t_k - delay (one sample of CAN latency is common). The current is shifted back by
        linear interpolation, the samples without a current dropped.
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
    replicates : int
        Bootstrap refits for the output-error intervals
        (:func:`motosim.identification.output_error.refine`).
    rng : numpy.random.Generator, optional
        Random numbers of the bootstrap; ``default_rng(0)`` when not given.

    Returns
    -------
    Identification
        The estimate, its fit, 95 % intervals or history per method, and warnings.

    Raises
    ------
    MotosimError
        One line: a missing column, columns that do not decide the drive, a non-monotonic
        or duplicated time, a NaN, too few samples, too poor an excitation (regressor rank
        or conditioning), invalid options, or a gradient law that diverged.

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
    >>> est.drive
    'voltage_held'
    >>> bool(abs(est.beta_eq / 13.956 - 1) < 0.01 and abs(est.beta_s / 1.734 - 1) < 0.01)
    True
    """
    if method not in METHODS:
        raise MotosimError(f"method = {method!r}; expected one of {', '.join(METHODS)}")
    if drive != "auto" and drive not in DRIVES:
        raise MotosimError(f"drive = {drive!r}; expected auto or one of {', '.join(DRIVES)}")
    if not (math.isfinite(back_emf_damping) and back_emf_damping >= 0.0):
        raise MotosimError(
            f"back_emf_damping = {back_emf_damping!r}; expected a finite value >= 0 [N*m*s/rad]"
        )
    if not (math.isfinite(current_delay) and current_delay >= 0.0):
        raise MotosimError(f"current_delay = {current_delay!r}; expected a finite value >= 0 [s]")
    if drive == "auto":
        drive, reason = drive_from_columns(log.names)
    else:
        reason = "given"
    if drive == "voltage_held" and back_emf_damping <= 0.0:
        raise MotosimError(
            "drive voltage_held needs the motor's back-EMF damping N k_t k_e N / R > 0; "
            "expected the motor constants (--handlebar) or another --drive"
        )
    source = "i_cmd" if drive == "current_held" and "i_cmd" in log.names else "i_m"
    if source not in log.names:
        raise MotosimError(
            f"log has no column {source!r} for drive {drive}; expected i_m (measured current "
            "[A]) or, for current_held, i_cmd"
        )
    work = _working_log(log, source, current_delay)
    reg = regression(work, torque_per_amp=torque_per_amp, window=window)
    Phi, y = reg.Phi[reg.used], reg.y[reg.used]
    p, interval = batch_least_squares(Phi, y)
    confidence: Array | None = None
    history: Array | None = None
    history_t: Array | None = None
    torque = torque_per_amp * work["i_m"]
    segment_nrmse = math.nan
    if method == "lsq":
        confidence = interval
    elif method == "output_error":
        p, rms, half_width = refine(
            reg.t,
            work["theta_h"],
            torque,
            reg.theta_h_dot,
            p,
            segment=segment,
            back_emf_damping=back_emf_damping,
            drive=drive,
            torque_noise=torque_per_amp * current_noise(work["i_m"]),
            replicates=replicates,
            rng=rng,
        )
        # a systematic allowance for the friction law near zero speed, in quadrature
        half_width = np.hypot(half_width, np.asarray(MODEL_ALLOWANCE) * np.abs(p))
        confidence = np.column_stack([p - half_width, p + half_width])
        spread = float(np.std(work["theta_h"]))
        segment_nrmse = rms / spread if spread > 0.0 else math.inf
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
    fit = math.inf
    if J > 0.0 and beta > 0.0:
        sim = simulate_angle(
            reg.t,
            torque,
            np.array([J, beta, max(beta_s, 0.0)]),
            initial_angle=work["theta_h"],
            initial_rate=reg.theta_h_dot,
            back_emf_damping=back_emf_damping,
            drive=drive,
        )
        fit = nrmse(sim, work["theta_h"])
    damping = back_emf_damping if drive == "voltage_held" else 0.0
    return Identification(
        method,
        J,
        beta,
        beta_s,
        fit,
        confidence,
        history,
        history_t,
        drive,
        damping,
        reason,
        _warnings(J, beta, confidence, reg),
        segment_nrmse,
    )


def _working_log(log: TimeSeries, source: str, delay: float) -> TimeSeries:
    """theta_h and the current that drove the handlebar, as ``i_m``, delay removed."""
    check_log(log, ("theta_h", source))
    current = log[source]
    theta = log["theta_h"]
    t = log.t
    if delay > 0.0:
        # the current of time t_k was logged at t_k + delay
        keep = t + delay <= t[-1]
        current = np.interp(t[keep] + delay, t, current)
        t, theta = t[keep], theta[keep]
    return TimeSeries(t.copy(), np.column_stack([theta, current]), ("theta_h", "i_m"))


def _warnings(J: float, beta: float, confidence: Array | None, reg: Regression) -> tuple[str, ...]:
    """The weak-identifiability warning on J_eq, with the excitation that would fix it."""
    if confidence is None or not (J > 0.0 and beta > 0.0):
        return ()
    half = 0.5 * float(confidence[0, 1] - confidence[0, 0]) / J
    if half <= WEAK_INERTIA:
        return ()
    moving = reg.used
    share = float(
        np.sqrt(np.mean((J * reg.Phi[moving, 0]) ** 2))
        / max(float(np.sqrt(np.mean((beta * reg.Phi[moving, 1]) ** 2))), 1e-300)
    )
    tau = J / beta
    # J theta'' is 2 pi f tau of beta theta' at the frequency f: aim for 15 %
    wanted = 0.15 / (2.0 * math.pi * tau)
    advice = (
        f"excite up to {wanted:.3g} Hz (where J theta'' is 15 % of beta theta' for "
        f"J/beta = {1e3 * tau:.3g} ms) at the largest current the rig allows"
    )
    if wanted > 0.1 / reg.h:
        advice = f"sample at {10 * wanted:.3g} Hz or faster and {advice}"
    return (
        f"J_eq is weakly identified (95 % interval +/-{100 * half:.3g} %): the inertia torque "
        f"J theta'' is only {100 * share:.2g} % of the viscous torque in this log; {advice}",
    )


def validate(
    identification: Identification,
    log: TimeSeries,
    *,
    torque_per_amp: float,
    current_delay: float = 0.0,
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
        Uniformly sampled columns ``theta_h`` [rad] and ``i_m`` (or ``i_cmd``) [A].
    torque_per_amp : float
        N k_t [N*m/A].
    current_delay : float
        How late the logged current is [s], as for :func:`identify`.

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
    source = "i_cmd" if identification.drive == "current_held" and "i_cmd" in log.names else "i_m"
    work = _working_log(log, source, current_delay)
    reg = regression(work, torque_per_amp=torque_per_amp)
    measured = work["theta_h"].copy()
    simulated = simulate_angle(
        reg.t,
        torque_per_amp * work["i_m"],
        np.array([identification.J_eq, identification.beta_eq, max(identification.beta_s, 0.0)]),
        initial_angle=measured,
        initial_rate=reg.theta_h_dot,
        back_emf_damping=identification.back_emf_damping,
        drive=identification.drive,
    )
    return Validation(
        nrmse(simulated, measured), work.t.copy(), simulated, measured, work["i_m"].copy()
    )
