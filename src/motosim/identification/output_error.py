"""Output-error refinement: fit eq. (5) so that its simulated angle matches the measured one.

At 100 Hz the handlebar time constant J_eq / beta_eq (about 3 ms) is shorter than the sample
period: theta_h'' is barely visible in the sampled angle, and the differentiated regressors of
eq. (8) are smoothed over several samples while the motor torque is not, so least squares on
them is biased (mostly J_eq, a little beta_eq). Simulating eq. (5) between samples with the
exact stick-slip kernel of :mod:`motosim.model.handlebar`, driven by the logged current as the
drive applied it between samples, avoids any differentiation. The parameters minimise

    sum_k (theta_sim(t_k; p) - theta_h(t_k))^2

with :func:`scipy.optimize.least_squares` (trust-region reflective, finite-difference
Jacobian), started from the least-squares estimate. The run is cut into segments, each started
from the measured angle and the differentiated rate, so that a small torque offset or noise
cannot make the open-loop angle drift over a long log.

What the motor torque does between samples depends on the drive, and at 100 Hz it matters for
J_eq (tens of per cent). Three drives are modelled (:data:`DRIVES`): a current held between
samples (a digital current loop), a voltage held between samples (the current then moves with
the back-EMF, eq. (7)), and a continuous current that was only sampled (interpolated by a
Catmull-Rom cubic through the neighbouring samples, so a smooth current is followed to
third order between samples).
"""

import math
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.stats import t as student_t

from motosim.errors import MotosimError
from motosim.model.handlebar import step_exact

__all__ = ["DRIVES", "angle_quantum", "nrmse", "refine", "simulate_angle"]

Array = NDArray[np.float64]

DRIVES: tuple[str, ...] = ("current_held", "voltage_held", "current_sampled")
"""How the motor torque behaves between samples, for :func:`simulate_angle` and :func:`refine`."""


def _check_drive(drive: str) -> bool:
    """Validate ``drive``; True when the torque is interpolated between samples."""
    if drive not in DRIVES:
        raise MotosimError(f"drive = {drive!r}; expected one of {', '.join(DRIVES)}")
    return drive == "current_sampled"


_SUBSTEP = 1.25e-3  # [s] longest torque step within a sample period when interpolating
_MAX_SUBSTEPS = 8


@njit(cache=True)
def _simulate_segments(
    t: Array,
    torque: Array,
    theta0: Array,
    omega0: Array,
    starts: NDArray[np.int64],
    J: float,
    beta: float,
    beta_s: float,
    damping: float,
    linear: bool,
) -> Array:
    n = t.size
    out = np.empty(n)
    theta = 0.0
    omega = 0.0
    s = 0
    for k in range(n):
        if s < starts.size and k == starts[s]:
            # re-anchor the angle only: the simulated rate forgets its start within J/beta
            theta = theta0[k]
            if k == 0:
                omega = omega0[0]
            s += 1
        out[k] = theta
        if k == n - 1:
            break
        h = t[k + 1] - t[k]
        if linear:
            # a continuous current, sampled: the torque moves smoothly between samples
            # (Catmull-Rom cubic through the neighbouring samples, exact on quadratics)
            # steps of at most 1.25 ms (8 at 100 Hz, 1 at 1 kHz): the cubic's torque at the
            # step's midpoint, held over a step, errs by (step^2 / 24) torque''
            m = min(int(h / _SUBSTEP) + 1, _MAX_SUBSTEPS)
            sub = h / m
            p0 = torque[k - 1] if k > 0 else 2.0 * torque[k] - torque[k + 1]
            p3 = torque[k + 2] if k + 2 < n else 2.0 * torque[k + 1] - torque[k]
            p1 = torque[k]
            p2 = torque[k + 1]
            for j in range(m):
                w = (j + 0.5) / m
                applied = 0.5 * (
                    2.0 * p1
                    + (p2 - p0) * w
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * w * w
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * w * w * w
                )
                theta, omega = step_exact(theta, omega, applied, J, beta, beta_s, sub)
        else:
            # held; under voltage drive the back-EMF moves the current off its sample
            held = torque[k] + damping * omega
            theta, omega = step_exact(theta, omega, held, J, beta + damping, beta_s, h)
    return out


def simulate_angle(
    t: Array,
    torque: Array,
    parameters: Array,
    *,
    initial_angle: Array,
    initial_rate: Array,
    starts: NDArray[np.int64] | None = None,
    back_emf_damping: float = 0.0,
    drive: str = "current_held",
) -> Array:
    """Angle of eq. (5) with tau_r = 0 and the motor torque held between samples.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times [s].
    torque : ndarray, shape (n,)
        N k_t i_m at the samples [N*m], held from t_k to t_{k+1}.
    parameters : ndarray, shape (3,)
        [J_eq kg*m^2, beta_eq N*m*s/rad, beta_s N*m].
    initial_angle, initial_rate : ndarray, shape (n,)
        Angle [rad] and rate [rad/s] to restart from at each segment start (only those
        entries are read).
    starts : ndarray of int, optional
        Sample indices where a segment starts; ``[0]`` by default (one open-loop run).
    back_emf_damping : float
        c = N k_t k_e N / R [N*m*s/rad] when the drive holds the voltage, not the current,
        between samples: the current then moves from its sample i_k as the rate changes,
        N k_t i(t) = N k_t i_k - c (theta_h'(t) - theta_h'(t_k)) by eq. (7). 0 for a
        current-controlled drive. Used with ``drive="voltage_held"`` only.
    drive : str
        One of :data:`DRIVES`.

    Returns
    -------
    ndarray, shape (n,)
        Simulated theta_h [rad].
    """
    linear = _check_drive(drive)
    damping = back_emf_damping if drive == "voltage_held" else 0.0
    J, beta, beta_s = (float(v) for v in parameters)
    if starts is None:
        starts = np.zeros(1, dtype=np.int64)
    return np.asarray(
        _simulate_segments(
            t, torque, initial_angle, initial_rate, starts, J, beta, beta_s, damping, linear
        )
    )


def nrmse(simulated: Array, measured: Array) -> float:
    """Normalised RMS error ||simulated - measured|| / ||measured - mean(measured)||.

    0 is a perfect fit; 1 is no better than the mean (MATLAB's fit is 100 (1 - NRMSE) %).

    Examples
    --------
    >>> nrmse(np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 2.0]))
    0.0
    """
    spread = float(np.linalg.norm(measured - np.mean(measured)))
    if spread == 0.0:
        return math.inf
    return float(np.linalg.norm(simulated - measured)) / spread


def _half_widths(jac: Array, residual: Array, starts: NDArray[np.int64]) -> Array:
    """95 % half-widths of a least-squares fit whose residuals are correlated within segments.

    The Gauss-Newton covariance (J^T J)^-1 sigma^2 assumes independent residuals; an
    output-error residual is not (quantisation, noise integrated by the model, an anchor
    error shared by a whole segment). The cluster-robust "sandwich" estimate
    (J^T J)^-1 (sum_g s_g s_g^T) (J^T J)^-1, with s_g = J_g^T r_g summed over segment g,
    allows any correlation within a segment and takes the segments as independent (each
    restarts from the measured angle); the quantile is Student's t with G - 1 degrees of
    freedom for G segments (Cameron & Miller, "A practitioner's guide to cluster-robust
    inference", J. Human Resources 50(2), 2015, sections II-III and VI).
    """
    groups = starts.size
    if groups < 4:
        dof = max(residual.size - jac.shape[1], 1)
        meat = float(residual @ residual) / dof * (jac.T @ jac)
        quantile = 1.96
    else:
        scores = np.add.reduceat(jac * residual[:, None], starts, axis=0)
        meat = groups / (groups - 1) * (scores.T @ scores)
        quantile = float(student_t.ppf(0.975, groups - 1))
    try:
        bread = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full(jac.shape[1], np.inf)
    cov = bread @ meat @ bread
    return np.asarray(quantile * np.sqrt(np.clip(np.diag(cov), 0.0, None)))


def angle_quantum(theta: Array) -> float:
    """The encoder step of a quantised angle log [rad], 0 when the angle is not on a grid.

    The step is the smallest difference between distinct angles; the log is taken as
    quantised when every angle is a whole number of steps from the smallest (within 1 %).

    Examples
    --------
    >>> angle_quantum(np.array([0.0, 0.5, 1.5, 1.0, 0.5]))
    0.5
    >>> angle_quantum(np.array([0.0, 0.31, 1.0]))
    0.0
    """
    values = np.unique(theta)
    if values.size < 2:
        return 0.0
    step = float(np.min(np.diff(values)))
    counts = (values - values[0]) / step
    if step > 0.0 and float(np.max(np.abs(counts - np.round(counts)))) < 0.01:
        return step
    return 0.0


def refine(
    t: Array,
    theta: Array,
    torque: Array,
    rate: Array,
    start: Array,
    *,
    segment: float = 2.0,
    back_emf_damping: float = 0.0,
    drive: str = "current_held",
    torque_noise: float = 0.0,
    replicates: int = 8,
    rng: np.random.Generator | None = None,
) -> tuple[Array, float, Array]:
    """Output-error estimate of [J_eq, beta_eq, beta_s] from a starting guess.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times [s].
    theta : ndarray, shape (n,)
        Measured theta_h [rad].
    torque : ndarray, shape (n,)
        Measured N k_t i_m [N*m], between samples as ``drive`` says.
    rate : ndarray, shape (n,)
        Differentiated theta_h' [rad/s], used only as the initial rate of each segment.
    start : ndarray, shape (3,)
        Starting estimate (the least-squares one); non-positive entries are replaced by
        small positive values.
    segment : float
        Length of the simulated segments [s]; ``inf`` for one open-loop run.
    back_emf_damping : float
        See :func:`simulate_angle`.
    drive : str
        One of :data:`DRIVES`.
    torque_noise : float
        Standard deviation of the noise on the measured torque [N*m], for the bootstrap.
    replicates : int
        Parametric-bootstrap refits for the intervals (0: the sandwich estimate alone).
    rng : numpy.random.Generator, optional
        Random numbers of the bootstrap; ``default_rng(0)`` when not given, so that the
        same log gives the same intervals.

    Returns
    -------
    parameters : ndarray, shape (3,)
        [J_eq kg*m^2, beta_eq N*m*s/rad, beta_s N*m].
    rms : float
        RMS of the remaining angle residual [rad].
    half_width : ndarray, shape (3,)
        Half-widths of the 95 % confidence intervals. A wide interval on J_eq says the
        excitation or the sampling does not reveal the inertia.

    Raises
    ------
    MotosimError
        If ``segment`` is not positive or the optimisation fails.

    Notes
    -----
    The intervals add two variances. One is the cluster-robust sandwich of the fit's
    Jacobian (:func:`_half_widths`), for the noise seen in the residual. The other is a
    parametric bootstrap for what the residual cannot show, the encoder: the fitted model's
    angle is re-quantised with the log's encoder step (:func:`angle_quantum`) at a random
    offset, the torque given fresh noise of ``torque_noise``, and the fit repeated;
    quantisation of a slowly moving angle shifts the estimates by a fraction of a per cent
    that depends on where the counts fall, an error the residual's spread does not reveal.
    """
    linear = _check_drive(drive)
    damping = back_emf_damping if drive == "voltage_held" else 0.0
    if not (segment > 0.0):
        raise MotosimError(f"segment = {segment!r}; expected > 0 [s]")
    span = float(t[-1] - t[0])
    if math.isfinite(segment) and segment < span:
        starts = np.searchsorted(t, np.arange(t[0], t[-1], segment)).astype(np.int64)
    else:
        starts = np.zeros(1, dtype=np.int64)
    counts = np.diff(np.append(starts, t.size)).astype(float)
    segment_of = np.repeat(np.arange(starts.size), np.diff(np.append(starts, t.size)))
    # scale: parameters in units of the starting guess; floors keep them positive
    typical = np.abs(np.asarray(start, dtype=float))
    scale = np.where(typical > 0.0, typical, 1.0)
    x0 = np.where(np.asarray(start) > 0.0, 1.0, 0.1)
    # J_eq and beta_eq must stay positive for the kernel; beta_s may reach 0
    lower = np.array([1e-6, 1e-6, 0.0])

    def simulate(x: Array, measured: Array, applied: Array) -> Array:
        return np.asarray(
            _simulate_segments(
                t,
                applied,
                measured,
                rate,
                starts,
                x[0] * scale[0],
                x[1] * scale[1],
                x[2] * scale[2],
                damping,
                linear,
            )
        )

    def fit_to(measured: Array, applied: Array, x_start: Array, tol: float) -> Any:
        def residual(x: Array) -> Array:
            r = simulate(x, measured, applied) - measured
            # the anchor sample is quantised too: remove each segment's mean offset
            return np.asarray(r - (np.add.reduceat(r, starts) / counts)[segment_of])

        try:
            return least_squares(
                residual,
                x_start,
                bounds=(lower, np.full(lower.size, np.inf)),
                method="trf",
                diff_step=1e-3,
                x_scale=1.0,
                xtol=tol,
                ftol=tol,
                gtol=tol,
                max_nfev=200,
            )
        except (ValueError, np.linalg.LinAlgError) as exc:  # pragma: no cover - defensive
            raise MotosimError(f"output-error refinement failed: {exc}") from None

    fit = fit_to(theta, torque, x0, 1e-10)
    variance = (_half_widths(fit.jac, fit.fun, starts) / 1.96) ** 2
    if replicates > 1:
        generator = rng if rng is not None else np.random.default_rng(0)
        quantum = angle_quantum(theta)
        model = simulate(fit.x, theta, torque)
        noise = float(np.sqrt(np.mean(fit.fun**2)))
        refits = np.empty((replicates, fit.x.size))
        for b in range(replicates):
            if quantum > 0.0:
                offset = generator.uniform(0.0, quantum)
                angle = np.floor((model + offset) / quantum) * quantum
            else:
                angle = model + noise * generator.standard_normal(model.size)
            applied = torque + torque_noise * generator.standard_normal(torque.size)
            refits[b] = fit_to(angle, applied, fit.x, 1e-8).x
        # the bootstrap's spread from few refits is itself uncertain: Student's t, R - 1 dof
        inflation = float(student_t.ppf(0.975, replicates - 1)) / 1.96
        variance = variance + inflation**2 * np.var(refits, axis=0, ddof=1)
    half_width = 1.96 * np.sqrt(variance) * scale
    return np.asarray(fit.x * scale), float(np.sqrt(np.mean(fit.fun**2))), half_width
