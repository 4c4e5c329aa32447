"""Excitation signals and the measurement chain of a handlebar identification run.

Section II.D of the paper drives the motor in open loop (no feedback, tau_r = 0) with a chirp
voltage (0.1-2 Hz, 3 V) and validates with a chirp (0.1-4 Hz) and a bipolar rectangular
voltage (Figs. 4-5); the angle comes back over the CAN bus at 100 Hz. This module makes such
runs in simulation: it builds the voltages, simulates the handlebar finely with the exact
stick-slip kernel of :mod:`motosim.model.handlebar`, then samples, quantises and adds noise as
the sensors would. The resulting log (columns ``theta_h``, ``i_m``, ``u``) is what
:func:`motosim.identification.identify` takes, just like a log recorded on the hardware.

Data flow: ``params -> model -> identification`` (this module uses the model, nothing after).
"""

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.model.handlebar import simulate_handlebar
from motosim.params.handlebar import HandlebarParameters
from motosim.timeseries import TimeSeries

__all__ = [
    "INERTIA_SHARE",
    "ExcitationPlan",
    "MeasurementModel",
    "chirp_voltage",
    "excitation_run",
    "measure",
    "plan_excitation",
    "square_voltage",
]

Array = NDArray[np.float64]


def _check_positive(name: str, value: float, unit: str) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise MotosimError(f"{name} = {value!r}; expected a finite value > 0 [{unit}]")


def _time_grid(duration: float, rate: float) -> Array:
    _check_positive("duration", duration, "s")
    _check_positive("rate", rate, "Hz")
    n = round(duration * rate) + 1
    if n < 2:
        raise MotosimError(f"duration * rate = {duration * rate:g}; expected at least 1 sample")
    return np.arange(n, dtype=float) / rate


def chirp_voltage(
    *, amplitude: float, f0: float, f1: float, duration: float, rate: float
) -> TimeSeries:
    """Linear-sweep chirp voltage u(t) = A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))).

    Parameters
    ----------
    amplitude : float
        A [V], > 0.
    f0, f1 : float
        Start and end frequency [Hz], > 0 (section II.D: 0.1 and 2 Hz for identification,
        0.1 and 4 Hz for the validation of Fig. 4).
    duration : float
        T [s], > 0.
    rate : float
        Sample rate of the command [Hz]; the voltage is held between samples.

    Returns
    -------
    TimeSeries
        Column ``u`` [V] at t = k / rate, k = 0 ... round(T rate).

    Raises
    ------
    MotosimError
        If a value is not finite and positive.

    Examples
    --------
    >>> u = chirp_voltage(amplitude=3.0, f0=0.1, f1=2.0, duration=60.0, rate=100.0)
    >>> u.t.size, float(abs(u["u"]).max()) <= 3.0
    (6001, True)
    """
    _check_positive("amplitude", amplitude, "V")
    _check_positive("f0", f0, "Hz")
    _check_positive("f1", f1, "Hz")
    t = _time_grid(duration, rate)
    phase = 2.0 * np.pi * (f0 * t + 0.5 * (f1 - f0) * t**2 / duration)
    return TimeSeries(t, (amplitude * np.sin(phase))[:, None], ("u",))


def square_voltage(
    *, amplitude: float, frequency: float, duration: float, rate: float
) -> TimeSeries:
    """Bipolar rectangular voltage: +A for the first half of each period, -A for the second.

    Parameters
    ----------
    amplitude : float
        A [V], > 0.
    frequency : float
        Repetition frequency [Hz], > 0.
    duration : float
        Length [s], > 0.
    rate : float
        Sample rate of the command [Hz]; the voltage is held between samples.

    Returns
    -------
    TimeSeries
        Column ``u`` [V] at t = k / rate (Fig. 5 of the paper validates with such a signal).

    Raises
    ------
    MotosimError
        If a value is not finite and positive.

    Examples
    --------
    >>> u = square_voltage(amplitude=3.0, frequency=0.5, duration=2.0, rate=10.0)
    >>> u["u"][[0, 9, 10, 19]]
    array([ 3.,  3., -3., -3.])
    """
    _check_positive("amplitude", amplitude, "V")
    _check_positive("frequency", frequency, "Hz")
    t = _time_grid(duration, rate)
    # the phase in whole samples avoids rounding flips exactly at the edges
    cycles = np.floor(np.round(t * frequency * 2.0, 9))
    u = np.where(cycles % 2 == 0, amplitude, -amplitude)
    return TimeSeries(t, u[:, None], ("u",))


@dataclass(frozen=True, slots=True)
class MeasurementModel:
    """How the handlebar is measured: sample rate, angle encoder and current sensor.

    Attributes
    ----------
    sample_rate : float
        Rate at which angle, current and voltage are logged [Hz]; 100 Hz is the paper's CAN
        link (section II.D).
    counts_per_revolution : int
        Encoder counts per revolution of the encoder shaft (after quadrature decoding), >= 1.
        2048 counts is a 512-line encoder read in quadrature.
    pulley_ratio : float
        Encoder shaft turns per handlebar turn, > 0 (the paper's encoder is geared up by a
        pulley-belt to improve resolution, Fig. 3). The angle step is
        2 pi / (counts_per_revolution pulley_ratio) [rad].
    current_noise : float
        Standard deviation of the white noise added to each current sample [A], >= 0.
        0.05 A is typical of a Hall-effect sensor of a 20-30 A range.

    Raises
    ------
    MotosimError
        If a value is not finite or out of range.

    Examples
    --------
    >>> m = MeasurementModel()
    >>> round(m.angle_resolution, 6)    # [rad]
    0.000256
    """

    sample_rate: float = 100.0
    counts_per_revolution: int = 2048
    pulley_ratio: float = 12.0
    current_noise: float = 0.05

    def __post_init__(self) -> None:
        _check_positive("sample_rate", self.sample_rate, "Hz")
        if isinstance(self.counts_per_revolution, bool) or not isinstance(
            self.counts_per_revolution, int | np.integer
        ):
            raise MotosimError(
                f"counts_per_revolution = {self.counts_per_revolution!r}; expected an integer"
            )
        if self.counts_per_revolution < 1:
            raise MotosimError(
                f"counts_per_revolution = {self.counts_per_revolution}; expected >= 1"
            )
        _check_positive("pulley_ratio", self.pulley_ratio, "1")
        if not (math.isfinite(self.current_noise) and self.current_noise >= 0.0):
            raise MotosimError(
                f"current_noise = {self.current_noise!r}; expected a finite value >= 0 [A]"
            )

    @property
    def angle_resolution(self) -> float:
        """Angle step of the encoder at the handlebar axis [rad]."""
        return 2.0 * math.pi / (self.counts_per_revolution * self.pulley_ratio)


def measure(truth: TimeSeries, model: MeasurementModel, rng: np.random.Generator) -> TimeSeries:
    """Sample, quantise and add noise to a finely simulated run, as the sensors would.

    Parameters
    ----------
    truth : TimeSeries
        Simulated run with at least the columns ``theta_h`` [rad], ``i_m`` [A] and ``u`` [V],
        on a grid much finer than the sampling period (for example 10 kHz). Samples are taken
        at t[0] + k / sample_rate; the truth is linearly interpolated when such an instant
        falls between its samples, so a fine grid that contains these instants gives the
        exact values.
    model : MeasurementModel
        Sample rate, encoder and current sensor.
    rng : numpy.random.Generator
        Source of the current-sensor noise.

    Returns
    -------
    TimeSeries
        Columns ``theta_h`` (floored to whole encoder counts, as an incremental encoder
        counting from the start), ``i_m`` (with the noise) and ``u`` (exact, the command).

    Raises
    ------
    MotosimError
        If a column is missing or the run is shorter than two sampling periods.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 1001)
    >>> truth = TimeSeries(t, np.column_stack([t, 0 * t, 0 * t]), ("theta_h", "i_m", "u"))
    >>> log = measure(truth, MeasurementModel(current_noise=0.0), np.random.default_rng(0))
    >>> log.t.size, float(abs(log["theta_h"] - log.t).max()) < 3e-4
    (101, True)
    """
    for name in ("theta_h", "i_m", "u"):
        if name not in truth.names:
            raise MotosimError(f"truth has no column {name!r}; expected theta_h, i_m and u")
    span = float(truth.t[-1] - truth.t[0])
    n = math.floor(span * model.sample_rate + 1e-9) + 1
    if n < 2:
        raise MotosimError(
            f"truth lasts {span:g} s; expected at least one period 1/{model.sample_rate:g} s"
        )
    t = truth.t[0] + np.arange(n, dtype=float) / model.sample_rate
    step = model.angle_resolution
    theta = np.interp(t, truth.t, truth["theta_h"])
    theta = np.floor(theta / step + 1e-9) * step
    current = np.interp(t, truth.t, truth["i_m"])
    if model.current_noise > 0.0:
        current = current + model.current_noise * rng.standard_normal(n)
    volts = np.interp(t, truth.t, truth["u"])
    return TimeSeries(t, np.column_stack([theta, current, volts]), ("theta_h", "i_m", "u"))


def excitation_run(
    hb: HandlebarParameters,
    signal: Literal["chirp", "square"],
    duration: float,
    measurement: MeasurementModel,
    rng: np.random.Generator,
    *,
    amplitude: float = 3.0,
    f0: float = 0.1,
    f1: float = 2.0,
    frequency: float = 0.5,
    simulation_rate: float = 10_000.0,
) -> TimeSeries:
    """Simulate an open-loop identification run of section II.D and measure it.

    The voltage is a digital command sent at the measurement's sample rate and held between
    samples by the motor drive (the paper's CAN link carries it). The handlebar, driven through
    eq. (7) i_m = (u - k_e N theta_h') / R with tau_r = 0, is simulated with the exact
    stick-slip kernel at ``simulation_rate``, then measured by :func:`measure`.

    Parameters
    ----------
    hb : HandlebarParameters
        The simulated handlebar (the truth).
    signal : {"chirp", "square"}
        Chirp from ``f0`` to ``f1`` or bipolar rectangular voltage at ``frequency``.
    duration : float
        Length of the run [s].
    measurement : MeasurementModel
        Sample rate and sensors.
    rng : numpy.random.Generator
        Source of the sensor noise.
    amplitude : float
        Voltage amplitude [V]; the paper uses 3 V.
    f0, f1 : float
        Chirp start and end frequencies [Hz]; the paper identifies with 0.1-2 Hz.
    frequency : float
        Frequency of the rectangular voltage [Hz].
    simulation_rate : float
        Rate of the fine simulation [Hz]; an integer multiple of the sample rate.

    Returns
    -------
    TimeSeries
        Columns ``theta_h`` [rad], ``i_m`` [A] and ``u`` [V] at the sample rate.

    Raises
    ------
    MotosimError
        On an unknown signal or invalid amplitudes, frequencies or rates.

    Examples
    --------
    >>> from motosim.params import load_parameters
    >>> hb = load_parameters("simacom_handlebar", "handlebar")
    >>> log = excitation_run(hb, "chirp", 2.0, MeasurementModel(), np.random.default_rng(1))
    >>> log.names, log.t.size
    (('theta_h', 'i_m', 'u'), 201)
    """
    rate = measurement.sample_rate
    _check_positive("simulation_rate", simulation_rate, "Hz")
    ratio = simulation_rate / rate
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise MotosimError(
            f"simulation_rate = {simulation_rate:g} Hz; expected an integer multiple of the "
            f"sample rate {rate:g} Hz"
        )
    if signal == "chirp":
        command = chirp_voltage(amplitude=amplitude, f0=f0, f1=f1, duration=duration, rate=rate)
    elif signal == "square":
        command = square_voltage(
            amplitude=amplitude, frequency=frequency, duration=duration, rate=rate
        )
    else:
        raise MotosimError(f"signal = {signal!r}; expected 'chirp' or 'square'")
    m = round(ratio)
    n_fine = (command.t.size - 1) * m + 1
    t_fine = np.arange(n_fine, dtype=float) / simulation_rate
    u_fine = np.repeat(command["u"], m)[:n_fine]
    truth = simulate_handlebar(hb, t_fine, voltage=u_fine)
    return measure(truth, measurement, rng)


@dataclass(frozen=True, slots=True)
class ExcitationPlan:
    """A current chirp that makes J_eq, beta_eq and beta_s identifiable on a given rig.

    Attributes
    ----------
    f0, f1 : float
        Start and end frequency of the linear chirp [Hz].
    amplitude : float
        Current amplitude [A].
    duration : float
        Length of the run [s].
    inertia_share : float
        J theta'' / (beta theta') at f1, 2 pi f1 J/beta: how visible the inertia is.
    counts_at_f1 : float
        Angle amplitude at f1 in encoder counts.
    notes : tuple of str
        One line per limit the plan ran into, with what would lift it.
    """

    f0: float
    f1: float
    amplitude: float
    duration: float
    inertia_share: float
    counts_at_f1: float
    notes: tuple[str, ...] = ()


INERTIA_SHARE = 0.15
"""J theta'' / (beta theta') aimed for at the chirp's top frequency."""


def plan_excitation(
    *,
    J_eq: float,
    beta_eq: float,
    beta_s: float,
    torque_per_amp: float,
    sample_rate: float,
    max_current: float,
    angle_limit: float = 0.5,
    encoder_counts: int = 2**14,
) -> ExcitationPlan:
    """Recommend a current chirp for identifying a handlebar known roughly.

    Parameters
    ----------
    J_eq, beta_eq, beta_s : float
        Rough inertia [kg*m^2], viscous friction [N*m*s/rad] and dry friction [N*m].
    torque_per_amp : float
        N k_t [N*m/A].
    sample_rate : float
        The log's sample rate [Hz].
    max_current : float
        The largest current the drive may be commanded [A].
    angle_limit : float
        Largest handlebar angle from the start allowed [rad] (the steering lock).
    encoder_counts : int
        Encoder counts per handlebar turn.

    Returns
    -------
    ExcitationPlan
        Band, amplitude, duration, and the notes on the limits met.

    Raises
    ------
    MotosimError
        On non-positive values, or a current limit whose torque does not exceed twice the
        dry friction (the handlebar would hardly slide).

    Notes
    -----
    With a current amplitude I, eq. (5) moves the sliding handlebar at a rate amplitude of
    about (N k_t I - beta_s) / (beta_eq sqrt(1 + (2 pi f tau)^2)), tau = J_eq / beta_eq, and
    J theta'' is 2 pi f tau of beta theta'. So:

    * the amplitude is 80 % of the current limit (headroom for the drive's loop), and its
      torque must exceed twice the dry friction so that sliding dominates;
    * the top frequency f1 makes J theta'' :data:`INERTIA_SHARE` of beta theta', but stays
      below a tenth of the sample rate (the cubic inter-sample model and the encoder need
      ten samples per period);
    * the start frequency f0 (at least 0.1 Hz) keeps the angle within ``angle_limit``;
    * the duration gives at least 6000 samples, 20 s, and 6 periods of f0.

    Examples
    --------
    >>> plan = plan_excitation(J_eq=0.06, beta_eq=9.0, beta_s=1.0, torque_per_amp=1.0,
    ...                        sample_rate=100.0, max_current=5.0)
    >>> round(plan.f1, 2), plan.amplitude
    (3.58, 4.0)
    """
    for name, value, unit in (
        ("J_eq", J_eq, "kg*m^2"),
        ("beta_eq", beta_eq, "N*m*s/rad"),
        ("torque_per_amp", torque_per_amp, "N*m/A"),
        ("sample_rate", sample_rate, "Hz"),
        ("max_current", max_current, "A"),
        ("angle_limit", angle_limit, "rad"),
    ):
        _check_positive(name, value, unit)
    if not (math.isfinite(beta_s) and beta_s >= 0.0):
        raise MotosimError(f"beta_s = {beta_s!r}; expected a finite value >= 0 [N*m]")
    amplitude = 0.8 * max_current
    torque = torque_per_amp * amplitude
    if torque <= 2.0 * beta_s:
        raise MotosimError(
            f"max_current = {max_current:g} A gives {torque:.3g} N*m at 80 %; expected more than "
            f"2 beta_s = {2 * beta_s:.3g} N*m so that the handlebar slides (raise the limit)"
        )
    tau = J_eq / beta_eq
    notes: list[str] = []
    f1 = INERTIA_SHARE / (2.0 * math.pi * tau)
    if f1 > 0.1 * sample_rate:
        f1 = 0.1 * sample_rate
        notes.append(
            f"the top frequency is held at a tenth of the sample rate ({f1:.3g} Hz): J theta'' "
            f"reaches only {100 * 2 * math.pi * f1 * tau:.2g} % of beta theta' (15 % aimed "
            f"for), so J_eq is less sharply identified; sample at "
            f"{10 * INERTIA_SHARE / (2 * math.pi * tau):.3g} Hz or faster to reach 15 %"
        )
    rate_amplitude = (torque - beta_s) / beta_eq
    f0 = max(0.1, rate_amplitude / (2.0 * math.pi * angle_limit))
    if f0 >= 0.5 * f1:
        raise MotosimError(
            f"angle_limit = {angle_limit:g} rad needs a chirp from {f0:.3g} Hz, too close to its "
            f"top {f1:.3g} Hz; expected a larger angle range or a smaller current limit"
        )
    counts = (
        rate_amplitude
        / (2.0 * math.pi * f1 * math.sqrt(1.0 + (2.0 * math.pi * f1 * tau) ** 2))
        / (2.0 * math.pi / encoder_counts)
    )
    if counts < 20.0:
        notes.append(
            f"the angle moves only {counts:.3g} encoder counts at {f1:.3g} Hz; a finer encoder "
            "or a larger current limit would sharpen J_eq"
        )
    duration = max(20.0, 6000.0 / sample_rate, 6.0 / f0)
    return ExcitationPlan(
        f0, f1, amplitude, duration, 2.0 * math.pi * f1 * tau, counts, tuple(notes)
    )
