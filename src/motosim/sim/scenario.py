"""Scenario files: what one closed-loop run simulates, as typed, self-validating dataclasses.

A scenario is TOML. Each table is a frozen dataclass below whose fields are the table's keys,
with their defaults written once, here; each dataclass validates itself in
``__post_init__``. :func:`parse_scenario` only maps the TOML document onto the constructors:
it checks each value's type against the field's annotation (numbers, integers, booleans,
strings, ``Literal`` choices, lists of numbers, tagged profiles and paths), refuses unknown
keys (suggesting the closest known one) and prefixes every error with the table it is in,
so that an error is one line naming the key, the value and what was expected. The tables
(all optional but ``[scenario]``)::

    [scenario]     name, description, duration [s] = 10, seed = 0,
                   architecture = "closed_loop" (Fig. 7) | "open_loop" (Fig. 9)
    [rates]        plant = 10000, control = 1000, measurement = 1000 [Hz]
                   (control a multiple of measurement, plant a multiple of control)
    [measurement]  encoder_bits = 14 (0: exact angle), current_noise = 0 [A]
    [motorcycle]   params = "sharp1971", speed = 20 [m/s], input = "estimate" | "true",
                   drive_torque, brake_torque [N*m], wind_force [N] (longitudinal),
                   side_wind [N] (lateral, to the right): a number or a profile;
                   side_wind_height = 1 [m] (where the side wind acts)
    [rider]        kind = "torque" with profile = {...}, or kind = "virtual" with path = {...}
                   and lateral_tolerance, course_tolerance, torque_scale, preview, max_torque,
                   probe = {...} (a torque profile added to the virtual rider's, e.g. a chirp);
                   for either, hands = "relaxed" | "firm" | "off" or a table {inertia
                   [kg*m^2], damping [N*m*s/rad], stiffness [N*m/rad], hold [rad]} (the arms'
                   passive impedance, :mod:`motosim.sim.hands`; default "relaxed",
                   :data:`~motosim.sim.grips.DEFAULT_GRIP`, where the stack models hands, and
                   "off", a pure torque source, with a design file or the torque sensor:
                   :attr:`Scenario.rider_hands`) and hands_off =
                   [[t0, t1], ...] [s] (phases with no torque at all)
    [handlebar]    true = "simacom_handlebar", nominal = (true), inertia_factor = 1,
                   damping_factor = 1, friction = true
    [estimator]    name = "walcott_zak" | "inverse_dynamics" | "kalman" | "torque_sensor",
                   friction_compensation = true, lipschitz = 300
    [controller]   kind = "ours" | "paper" | "none", design = "DESIGN.toml" (optional),
                   bandwidth [Hz] (default: 10 Hz, a fifth of the measurement rate below
                   50 Hz), order = 1, integral_corner = 0.1 (W1's corner over the
                   bandwidth), discretization = "zoh" | "tustin",
                   max_current = 30 [A], feedforward = ["rider", "reference"] for ours,
                   [] for the paper's (the terms of :func:`motosim.sim.stack.step`),
                   prediction = true | false (cancel the rider torque predicted over the
                   estimate's lag; default: on with "rider" and the Walcott-Zak observer
                   from a 1 kHz measurement rate and at 100 Hz), grip = "relaxed" |
                   "firm" | "off" (the rider's hands the stack is designed for; default:
                   the rider's hands, none with a design file or the torque sensor)
    [sensor]       torque = {noise [N*m], offset [N*m], low_pass [Hz]} (a rider-torque
                   sensor, read by the estimator "torque_sensor"; without the table, ideal)

Profiles (rider torque, drive, brake, wind) are tables with ``kind``: ``constant`` (value),
``steps`` (times, values: the value after each time), ``square`` (low, high, period, start),
``chirp`` (amplitude, f0, f1, start, offset), ``multisine`` (amplitude, f0, f1, period,
per_decade, start: a periodic sum of log-spaced sines) or ``csv`` (file, column; sampled and
held).
Paths have ``kind``: ``straight``, ``lane_change`` (offset, length, start), ``slalom``
(amplitude, wavelength, cycles, start), ``turn`` (radius, angle, start, transition),
``avoidance`` (offset, length, hold, start), ``opendrive`` (file, road: the reference line
of a road of an OpenDRIVE file, which :func:`motosim.io.runs.load_scenario` reads into
``geometry``); the path is long enough for the run.
"""

import dataclasses
import difflib
import functools
import math
import types
from collections.abc import Mapping
from dataclasses import dataclass
from typing import (
    Any,
    ClassVar,
    Literal,
    NamedTuple,
    Union,
    get_args,
    get_origin,
    get_type_hints,
)

import numpy as np
from numpy.typing import NDArray

from motosim.choices import ESTIMATOR_NAMES as ESTIMATORS
from motosim.choices import (
    INTEGRAL_CORNER,
    LOWEST_BANDWIDTH,
    MAX_ORDER,
    MOTORCYCLE_PROFILES,
    RIDER_SPEEDS,
    SENSOR_ESTIMATOR,
)
from motosim.errors import MotosimError
from motosim.params.checks import check_number, short_repr
from motosim.sim import paths
from motosim.sim.grips import DEFAULT_GRIP, GRIPS, Hands, design_hands, resolve_hands
from motosim.timeseries import TimeSeries

__all__ = [
    "FEEDFORWARD",
    "PATHS",
    "PROFILES",
    "PROFILE_LIMITS",
    "VALIDATED_SPEEDS",
    "AvoidancePath",
    "ChirpProfile",
    "ConstantProfile",
    "Controller",
    "CsvProfile",
    "Estimator",
    "Handlebar",
    "LaneChangePath",
    "Measurement",
    "Motorcycle",
    "MultisineProfile",
    "OpenDrivePath",
    "PathSpec",
    "Profile",
    "Rates",
    "Rider",
    "Scenario",
    "Sensor",
    "SlalomPath",
    "SquareProfile",
    "StepsProfile",
    "StraightPath",
    "TorqueSensor",
    "TurnPath",
    "check_profile_values",
    "implausible",
    "parse_scenario",
    "scenario_dict",
    "scenario_from_dict",
]

Array = NDArray[np.float64]


SMALLEST = 1e-6
"""Smallest positive length [m], time [s], rate [Hz], gain or factor a scenario accepts: a
micrometre, a microsecond or a millionth is no lane change, period or handlebar, only a typo
or a unit slip (and 1e-300 would reach the integrator as a division by zero)."""


MAX_TIME = 3600.0
"""Largest magnitude of a time in a profile [s]: the longest run a scenario admits."""
MAX_DISTANCE = 1e6
"""Largest length, radius or position along a path [m]: farther than any run travels (100 m/s
for the longest run, 3600 s, is 360 km); a straight is a ``straight`` path."""
MAX_OFFSET = 100.0
"""Largest lateral offset or amplitude of a path [m]: a road is tens of metres wide."""


def _check(
    name: str,
    value: float,
    *,
    low: float = -math.inf,
    high: float = math.inf,
    low_open: bool = False,
    unit: str = "",
) -> None:
    """Refuse a number outside [low, high] (or (low, high]) naming it (one-line error).

    A positive quantity (``low = 0`` open) must be at least :data:`SMALLEST`.
    """
    if low == 0.0 and low_open:
        low, low_open = SMALLEST, False
    check_number(value, where=name, lower=low, upper=high, lower_closed=not low_open, unit=unit)


# --- profiles: a signal of time ----------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ConstantProfile:
    """A constant value."""

    value: float
    kind: ClassVar[str] = "constant"

    def __post_init__(self) -> None:
        _check("value", self.value)

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s]."""
        return np.full(t.size, float(self.value))


@dataclass(frozen=True, slots=True)
class StepsProfile:
    """Piecewise constant: 0 before the first time, then ``values[i]`` from ``times[i]`` [s]."""

    times: tuple[float, ...]
    values: tuple[float, ...]
    kind: ClassVar[str] = "steps"

    def __post_init__(self) -> None:
        if len(self.times) != len(self.values) or not self.times:
            raise MotosimError(
                f"times and values have {len(self.times)} and {len(self.values)} entries; "
                "expected the same number, at least one"
            )
        if any(b <= a for a, b in zip(self.times, self.times[1:], strict=False)):
            raise MotosimError(f"times = {list(self.times)}; expected increasing times")
        for time in (self.times[0], self.times[-1]):
            _check("times", time, low=-MAX_TIME, high=MAX_TIME, unit="s")

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s]."""
        idx = np.searchsorted(np.asarray(self.times), t, side="right") - 1
        values = np.concatenate([[0.0], np.asarray(self.values)])
        return np.asarray(values[idx + 1], dtype=np.float64)


@dataclass(frozen=True, slots=True)
class SquareProfile:
    """A square wave between ``low`` and ``high`` of ``period`` [s], ``low`` before ``start``."""

    low: float
    high: float
    period: float
    start: float = 0.0
    kind: ClassVar[str] = "square"

    def __post_init__(self) -> None:
        _check("low", self.low)
        _check("high", self.high)
        _check("period", self.period, low=0.0, low_open=True, high=MAX_TIME, unit="s")
        _check("start", self.start, low=-MAX_TIME, high=MAX_TIME, unit="s")

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s]."""
        phase = np.floor((t - self.start) / (0.5 * self.period))
        levels = np.where(phase % 2 == 0, self.high, self.low)
        return np.asarray(np.where(t < self.start, self.low, levels), dtype=np.float64)


@dataclass(frozen=True, slots=True)
class ChirpProfile:
    """A linear chirp from ``f0`` to ``f1`` [Hz] over the run, from ``start`` [s]."""

    amplitude: float
    f0: float
    f1: float
    start: float = 0.0
    offset: float = 0.0
    kind: ClassVar[str] = "chirp"

    def __post_init__(self) -> None:
        _check("amplitude", self.amplitude)
        # at most 10 kHz, as a multisine's lines; beyond half the rate it is sampled at it
        # would alias: refused by Scenario, which knows the rates
        _check("f0", self.f0, low=0.0, high=1e4, unit="Hz")
        _check("f1", self.f1, low=0.0, high=1e4, unit="Hz")
        _check("start", self.start, low=-MAX_TIME, high=MAX_TIME, unit="s")
        _check("offset", self.offset)

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s]."""
        tt = np.clip(t - self.start, 0.0, None)
        span = max(float(t[-1] - self.start), 1e-9)
        phase = 2 * np.pi * (self.f0 * tt + (self.f1 - self.f0) * tt**2 / (2 * span))
        wave = np.where(t < self.start, 0.0, self.amplitude * np.sin(phase))
        return np.asarray(self.offset + wave, dtype=np.float64)


@dataclass(frozen=True, slots=True)
class MultisineProfile:
    """A periodic multisine of peak ``amplitude`` with log-spaced lines in ``f0``-``f1`` [Hz].

    The lines are harmonics of 1 / ``period``, about ``per_decade`` per decade, each of the
    same amplitude with Schroeder's phases (a low crest factor), the sum scaled to the peak
    ``amplitude``; zero before ``start`` [s]. Periodic, so that a response can be averaged over
    whole periods without leakage (Pintelon & Schoukens, *System Identification: A Frequency
    Domain Approach*, 2nd ed., 2012, sections 2.5 and 3.4).
    """

    amplitude: float
    f0: float
    f1: float
    period: float
    per_decade: int = 12
    start: float = 0.0
    kind: ClassVar[str] = "multisine"

    def __post_init__(self) -> None:
        _check("amplitude", self.amplitude)
        _check("period", self.period, low=0.0, low_open=True, high=3600.0, unit="s")
        _check("f0", self.f0, low=1.0 / self.period, unit="Hz")
        _check("f1", self.f1, low=self.f0, low_open=True, high=1e4, unit="Hz")
        _check("per_decade", self.per_decade, low=1, high=1000)
        _check("start", self.start, low=-MAX_TIME, high=MAX_TIME, unit="s")

    def frequencies(self) -> Array:
        """The excited lines [Hz]: distinct harmonics of 1 / ``period`` nearest a log grid."""
        n = max(2, math.ceil(self.per_decade * math.log10(self.f1 / self.f0)) + 1)
        k = np.unique(np.round(np.geomspace(self.f0, self.f1, n) * self.period))
        k = k[(k >= math.ceil(self.f0 * self.period - 1e-9)) & (k > 0)]
        return np.asarray(k / self.period, dtype=np.float64)

    def _wave(self, t: Array) -> Array:
        f = self.frequencies()
        k = np.arange(1, f.size + 1)
        phase = -np.pi * k * (k - 1) / f.size  # Schroeder's phases
        return np.asarray(np.cos(2 * np.pi * np.outer(t, f) + phase).sum(axis=1), dtype=float)

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s]."""
        grid = np.linspace(0.0, self.period, 4096, endpoint=False)
        peak = float(np.max(np.abs(self._wave(grid))))
        tt = np.asarray(t, dtype=float) - self.start
        wave = np.zeros_like(tt)
        on = tt >= 0.0
        for chunk in np.array_split(np.flatnonzero(on), max(1, on.sum() // 20000)):
            wave[chunk] = self._wave(tt[chunk])
        return np.asarray(self.amplitude * wave / peak, dtype=np.float64)


@dataclass(frozen=True, slots=True)
class CsvProfile:
    """The column ``column`` of the CSV log ``file`` (relative to the scenario), held."""

    file: str
    column: str = "tau_r"
    kind: ClassVar[str] = "csv"

    def sample(self, t: Array, tables: Mapping[str, TimeSeries]) -> Array:
        """Values at the times ``t`` [s], from the loaded log ``tables[file]``."""
        log = tables[self.file]
        if self.column not in log.names:
            raise MotosimError(
                f"{self.file}: no column {self.column!r}; have {', '.join(log.names)}"
            )
        idx = np.clip(np.searchsorted(log.t, t, side="right") - 1, 0, log.t.size - 1)
        return np.asarray(log[self.column][idx], dtype=np.float64)


Profile = (
    ConstantProfile | StepsProfile | SquareProfile | ChirpProfile | MultisineProfile | CsvProfile
)
"""A signal of time, tagged by its ``kind``."""
PROFILES: dict[str, type[Profile]] = {
    cls.kind: cls
    for cls in (
        ConstantProfile,
        StepsProfile,
        SquareProfile,
        ChirpProfile,
        MultisineProfile,
        CsvProfile,
    )
}
"""Profile types by ``kind``."""


class ProfileLimit(NamedTuple):
    """The legal and the typical range of a profile's values, and why.

    A value outside ``[low, high]`` is refused; beyond ``typical`` in magnitude it is legal
    but warned about (:func:`implausible`).
    """

    low: float
    high: float
    typical: float
    unit: str
    why: str


PROFILE_LIMITS: dict[str, ProfileLimit] = {
    "[rider] profile": ProfileLimit(
        -1000.0, 1000.0, 100.0, "N*m", "a rider applies tens of N*m to a handlebar"
    ),
    "[rider] probe": ProfileLimit(
        -1000.0, 1000.0, 100.0, "N*m", "a rider applies tens of N*m to a handlebar"
    ),
    "[motorcycle] drive_torque": ProfileLimit(
        -5000.0,
        5000.0,
        1500.0,
        "N*m",
        "a road motorcycle's engine gives up to about 1500 N*m "
        "at the rear wheel in first gear, and its tyres transmit about 1 g",
    ),
    "[motorcycle] brake_torque": ProfileLimit(
        0.0,
        5000.0,
        1500.0,
        "N*m",
        "the tyres of a motorcycle transmit about 1 g of "
        "deceleration, and a brake only slows: a negative value is a drive torque",
    ),
    "[motorcycle] front_brake_torque": ProfileLimit(
        0.0,
        5000.0,
        1500.0,
        "N*m",
        "a motorcycle's front brake stops it at about 1 g with some 1000-1500 N*m, and a "
        "brake only slows: a negative value is a drive torque",
    ),
    "[motorcycle] rear_brake_torque": ProfileLimit(
        0.0,
        5000.0,
        800.0,
        "N*m",
        "the rear wheel unloads while braking: a few hundred N*m lock it",
    ),
    "[road] friction": ProfileLimit(
        0.01,
        3.0,
        1.3,
        "1",
        "tyre-road friction is about 0.1 on ice, 0.5-0.7 wet and 1-1.3 on dry asphalt "
        "(racing tyres up to 1.5)",
    ),
    "[motorcycle] wind_force": ProfileLimit(
        -5000.0,
        5000.0,
        2000.0,
        "N",
        "the drag of a motorcycle and rider is about 0.5 x 1.2 "
        "kg/m^3 x 0.6 m^2 x v^2: 1 kN at 50 m/s, 3 kN in a 40 m/s headwind at 50 m/s",
    ),
    "[motorcycle] side_wind": ProfileLimit(
        -3000.0,
        3000.0,
        1000.0,
        "N",
        "a 30 m/s storm gust on a motorcycle and rider's side (about 1 m^2) pushes about 540 N",
    ),
}
"""Range of each profile's values, by where it is in a scenario. The legal bounds are a few
times the most a real ride sees, so that a unit slip (kN*m for N*m) or a typo (1e6) is refused
before the run rather than found as a run that left the model's range."""


def _profile_bounds(profile: Any) -> tuple[float, float] | None:
    """The least and the greatest value a profile takes (None: read from a file)."""
    if isinstance(profile, ConstantProfile):
        return profile.value, profile.value
    if isinstance(profile, SquareProfile):
        return min(profile.low, profile.high), max(profile.low, profile.high)
    if isinstance(profile, ChirpProfile):
        a = abs(profile.amplitude)
        return profile.offset - a, profile.offset + a
    if isinstance(profile, MultisineProfile):
        return -abs(profile.amplitude), abs(profile.amplitude)
    if isinstance(profile, StepsProfile):  # 0 before the first step
        return min(0.0, *profile.values), max(0.0, *profile.values)
    return None


def check_profile_values(where: str, low: float, high: float, *, key: str | None = None) -> None:
    """Refuse profile values outside the legal range of :data:`PROFILE_LIMITS` ``[where]``.

    Parameters
    ----------
    where : str
        Where the profile is, a key of :data:`PROFILE_LIMITS` (``"[motorcycle] wind_force"``).
    low, high : float
        The least and the greatest value the profile takes, in its unit.
    key : str, optional
        How the message names the profile (default: ``where``).

    Raises
    ------
    MotosimError
        One line naming the profile, the value and the legal range, with why.
    """
    limit = PROFILE_LIMITS[where]
    name = where if key is None else key
    for value in (low, high):
        if not (math.isfinite(value) and limit.low <= value <= limit.high):
            raise MotosimError(
                f"{name} reaches {value:g} {limit.unit}; expected {limit.low:g} to "
                f"{limit.high:g} {limit.unit} ({limit.why})"
            )


# --- paths: what the virtual rider follows ------------------------------------------------


@dataclass(frozen=True, slots=True)
class StraightPath:
    """Straight ahead."""

    kind: ClassVar[str] = "straight"

    def build(self, total: float) -> paths.Path:
        """The path, ``total`` [m] long."""
        return paths.straight(total)


@dataclass(frozen=True, slots=True)
class LaneChangePath:
    """A lane change of ``offset`` [m] (right positive) over ``length`` [m] from ``start`` [m]."""

    offset: float
    length: float
    start: float
    kind: ClassVar[str] = "lane_change"

    def __post_init__(self) -> None:
        _check("offset", self.offset, low=-MAX_OFFSET, high=MAX_OFFSET, unit="m")
        _check("length", self.length, low=0.0, low_open=True, high=MAX_DISTANCE, unit="m")
        _check("start", self.start, low=-MAX_DISTANCE, high=MAX_DISTANCE, unit="m")

    def build(self, total: float) -> paths.Path:
        """The path, ``total`` [m] long."""
        return paths.lane_change(self.offset, length=self.length, start=self.start, total=total)


@dataclass(frozen=True, slots=True)
class SlalomPath:
    """A slalom of ``amplitude`` [m] and ``wavelength`` [m], ``cycles`` times, from ``start``."""

    amplitude: float
    wavelength: float
    cycles: float
    start: float
    kind: ClassVar[str] = "slalom"

    def __post_init__(self) -> None:
        _check("amplitude", self.amplitude, low=0.0, low_open=True, high=MAX_OFFSET, unit="m")
        _check("wavelength", self.wavelength, low=0.0, low_open=True, high=MAX_DISTANCE, unit="m")
        _check("cycles", self.cycles, low=0.0, low_open=True, high=1e4)
        _check("start", self.start, low=-MAX_DISTANCE, high=MAX_DISTANCE, unit="m")

    def build(self, total: float) -> paths.Path:
        """The path, ``total`` [m] long."""
        return paths.slalom(
            self.amplitude,
            wavelength=self.wavelength,
            cycles=self.cycles,
            start=self.start,
            total=total,
        )


@dataclass(frozen=True, slots=True)
class TurnPath:
    """A turn of ``radius`` [m] (negative: left) through ``angle`` [rad] from ``start`` [m]."""

    radius: float
    angle: float
    start: float
    transition: float
    kind: ClassVar[str] = "turn"

    def __post_init__(self) -> None:
        _check("radius", self.radius, low=-MAX_DISTANCE, high=MAX_DISTANCE, unit="m")
        if abs(self.radius) < 1.0:
            raise MotosimError(
                f"radius = {self.radius!r} m; expected a radius of at least 1 m either way "
                "(negative: left), beyond a motorcycle's wheelbase"
            )
        # ten full circles; beyond one, a warning says the angle is in radians
        _check("angle", self.angle, low=-20 * math.pi, high=20 * math.pi, unit="rad")
        _check("start", self.start, low=-MAX_DISTANCE, high=MAX_DISTANCE, unit="m")
        _check("transition", self.transition, low=0.0, low_open=True, high=MAX_DISTANCE, unit="m")

    def build(self, total: float) -> paths.Path:
        """The path, ``total`` [m] long."""
        return paths.constant_radius_turn(
            self.radius,
            angle=self.angle,
            start=self.start,
            transition=self.transition,
            total=total,
        )


@dataclass(frozen=True, slots=True)
class AvoidancePath:
    """Out by ``offset`` [m] over ``length``, held for ``hold`` [m], and back, from ``start``."""

    offset: float
    length: float
    hold: float
    start: float
    kind: ClassVar[str] = "avoidance"

    def __post_init__(self) -> None:
        _check("offset", self.offset, low=-MAX_OFFSET, high=MAX_OFFSET, unit="m")
        _check("length", self.length, low=0.0, low_open=True, high=MAX_DISTANCE, unit="m")
        _check("hold", self.hold, low=0.0, low_open=True, high=MAX_DISTANCE, unit="m")
        _check("start", self.start, low=-MAX_DISTANCE, high=MAX_DISTANCE, unit="m")

    def build(self, total: float) -> paths.Path:
        """The path, ``total`` [m] long."""
        return paths.obstacle_avoidance(
            self.offset, length=self.length, hold=self.hold, start=self.start, total=total
        )


@dataclass(frozen=True, slots=True)
class OpenDrivePath:
    """The reference line of road ``road`` of the OpenDRIVE file ``file`` (see below).

    ``file`` is relative to the scenario file; :func:`motosim.io.runs.load_scenario` (and
    :func:`motosim.io.runs.resolve`) read its ``<planView>`` into ``geometry`` (lines, arcs,
    spirals and cubics, :class:`motosim.sim.paths.RoadGeometry`), which a saved result keeps,
    so that a run is replayed without the file. The line is moved to start at the origin
    heading along x (:func:`motosim.sim.paths.reference_line`) and goes straight on past its
    end.
    """

    file: str
    road: str = ""
    geometry: tuple[paths.RoadGeometry, ...] = ()
    kind: ClassVar[str] = "opendrive"

    def __post_init__(self) -> None:
        if not self.file or len(self.file) > 4096 or "\n" in self.file:
            raise MotosimError(f"file = {short_repr(self.file)}; expected an OpenDRIVE file name")
        if len(self.road) > 256:
            raise MotosimError(f"road = {short_repr(self.road)}; expected a road id")
        if self.geometry:
            paths.road_poses(self.geometry, np.zeros(1))  # one continuous line, or refused

    def build(self, total: float) -> paths.Path:
        """The path, at least ``total`` [m] long."""
        if not self.geometry:
            raise MotosimError(
                f"{self.file}: the OpenDRIVE file was not read; load the scenario with "
                "motosim.io.runs.load_scenario or resolve, which read it"
            )
        return paths.reference_line(self.geometry, total)


PathSpec = StraightPath | LaneChangePath | SlalomPath | TurnPath | AvoidancePath | OpenDrivePath
"""A reference path of the virtual rider, tagged by its ``kind``."""
PATHS: dict[str, type[PathSpec]] = {
    cls.kind: cls
    for cls in (StraightPath, LaneChangePath, SlalomPath, TurnPath, AvoidancePath, OpenDrivePath)
}
"""Path types by ``kind``."""


# --- the tables ---------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Rates:
    """Plant sub-step, control/estimation and measurement rates [Hz]."""

    plant: float = 10_000.0
    control: float = 1000.0
    measurement: float = 1000.0

    def __post_init__(self) -> None:
        _check("plant", self.plant, low=0.0, low_open=True, high=1e6, unit="Hz")
        _check("control", self.control, low=0.0, low_open=True, high=1e5, unit="Hz")
        _check("measurement", self.measurement, low=0.0, low_open=True, high=1e5, unit="Hz")
        for faster, slower, what in (
            (self.plant, self.control, "plant / control"),
            (self.control, self.measurement, "control / measurement"),
        ):
            ratio = faster / slower
            if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
                raise MotosimError(f"{what} = {ratio:g}; expected a whole number >= 1")


@dataclass(frozen=True, slots=True)
class Measurement:
    """Encoder resolution (bits per revolution of the handlebar, 0 for exact) and noise [A]."""

    encoder_bits: int = 14
    current_noise: float = 0.0

    def __post_init__(self) -> None:
        if not 0 <= self.encoder_bits <= 32:
            raise MotosimError(f"encoder_bits = {self.encoder_bits}; expected 0 to 32")
        _check("current_noise", self.current_noise, low=0.0, high=100.0, unit="A")


@dataclass(frozen=True, slots=True)
class Motorcycle:
    """The virtual motorcycle and its longitudinal inputs.

    ``model`` is Sharp's (1971) linear model with eq. (2) (``brake_torque``, ``wind_force``
    and ``side_wind`` act on it) or the multibody motorcycle on tyres
    (:mod:`motosim.model.tyred`: ``front_brake_torque`` and ``rear_brake_torque`` on each
    wheel, ``drive_torque`` on the rear one); ``params`` names a ``sharp`` set (Sharp's
    machine, through the multibody model on his linear tyres) or, for the multibody model, a
    ``multibody`` set with its Magic Formula tyres.
    """

    model: Literal["sharp1971", "multibody"] = "sharp1971"
    params: str = "sharp1971"
    speed: float = 20.0
    input: Literal["estimate", "true"] = "estimate"
    drive_torque: Profile = ConstantProfile(0.0)
    brake_torque: Profile = ConstantProfile(0.0)
    front_brake_torque: Profile = ConstantProfile(0.0)
    rear_brake_torque: Profile = ConstantProfile(0.0)
    wind_force: Profile = ConstantProfile(0.0)
    side_wind: Profile = ConstantProfile(0.0)
    side_wind_height: float = 1.0

    def __post_init__(self) -> None:
        _check("speed", self.speed, low=1.0, high=100.0, unit="m/s")
        _check("side_wind_height", self.side_wind_height, low=0.0, high=3.0, unit="m")
        for key in MOTORCYCLE_PROFILES:
            bounds = _profile_bounds(getattr(self, key))
            if bounds is not None:
                check_profile_values(f"[motorcycle] {key}", *bounds, key=key)
        unused = (
            ("brake_torque", "wind_force", "side_wind")
            if self.model == "multibody"
            else ("front_brake_torque", "rear_brake_torque")
        )
        for key in unused:
            if getattr(self, key) != ConstantProfile(0.0):
                other = (
                    "front_brake_torque and rear_brake_torque (the wheels' brakes; no wind yet)"
                    if self.model == "multibody"
                    else 'brake_torque, or model = "multibody" for a brake on each wheel'
                )
                raise MotosimError(
                    f"[motorcycle] {key} does not act on model = {self.model!r}; expected {other}"
                )


@dataclass(frozen=True, slots=True)
class Road:
    """The road under the multibody motorcycle's tyres."""

    friction: Profile = ConstantProfile(1.0)
    """The tyre-road friction coefficient mu over time [-] (dry asphalt about 1, wet 0.5-0.7,
    ice 0.1); the multibody motorcycle's tyres saturate at mu F_z."""

    def __post_init__(self) -> None:
        friction = self.friction
        if isinstance(friction, StepsProfile) and friction.times[0] > 0.0:
            raise MotosimError(
                f"[road] friction: steps from t = {friction.times[0]:g} s; expected the first "
                "at t = 0 (a road has a friction from the start)"
            )
        bounds = (
            (min(friction.values), max(friction.values))
            if isinstance(friction, StepsProfile)
            else _profile_bounds(friction)
        )
        if bounds is not None:
            check_profile_values("[road] friction", *bounds, key="friction")


@dataclass(frozen=True, slots=True)
class Rider:
    """An open-loop torque profile or a virtual rider following a path.

    On the multibody motorcycle the virtual rider also holds its speed with the throttle and,
    with ``brake_control``, modulates the brake demands so that each wheel's longitudinal
    slip stays at ``brake_slip`` and the rear wheel on the ground (:mod:`motosim.sim.brakes`);
    without it the brakes act as demanded.

    ``hands`` None: the scenario's default grip (:attr:`Scenario.rider_hands`)."""

    kind: Literal["torque", "virtual"] = "torque"
    profile: Profile | None = None
    path: PathSpec | None = None
    probe: Profile | None = None
    lateral_tolerance: float = 0.3
    course_tolerance: float = 0.05
    torque_scale: float = 10.0
    preview: float = 0.3
    max_torque: float = 70.0
    hands: str | Hands | None = None
    hands_off: tuple[tuple[float, ...], ...] = ()
    brake_control: bool = True
    brake_slip: float = 0.1

    def __post_init__(self) -> None:
        if isinstance(self.hands, str) and self.hands not in GRIPS:
            raise MotosimError(
                f"hands = {self.hands!r}; expected one of {', '.join(GRIPS)} or a table "
                "{ inertia = ..., damping = ..., stiffness = ... }"
            )
        for phase in self.hands_off:
            if len(phase) != 2 or not all(math.isfinite(t) for t in phase):
                raise MotosimError(
                    f"hands_off has {list(phase)}; expected [t0, t1] pairs of finite times [s]"
                )
            if not 0.0 <= phase[0] < phase[1]:
                raise MotosimError(f"hands_off has {list(phase)}; expected 0 <= t0 < t1 [s]")
        if self.kind == "torque" and self.profile is None:
            raise MotosimError('missing profile for kind = "torque"')
        if self.kind == "torque" and self.path is not None:
            raise MotosimError('path is for kind = "virtual"; a torque rider has a profile')
        if self.kind == "virtual" and self.profile is not None:
            raise MotosimError('profile is for kind = "torque"; a virtual rider has a path')
        if self.kind == "torque" and self.probe is not None:
            raise MotosimError('probe is for kind = "virtual"; give a torque rider a profile')
        if self.kind == "virtual" and self.path is None:
            object.__setattr__(self, "path", StraightPath())
        _check("lateral_tolerance", self.lateral_tolerance, low=1e-3, high=100.0, unit="m")
        _check("course_tolerance", self.course_tolerance, low=1e-4, high=3.0, unit="rad")
        _check("torque_scale", self.torque_scale, low=1e-2, high=1000.0, unit="N*m")
        _check("preview", self.preview, low=0.0, high=5.0, unit="s")
        _check("max_torque", self.max_torque, low=0.0, low_open=True, high=500.0, unit="N*m")
        _check("brake_slip", self.brake_slip, low=0.0, low_open=True, high=0.5, unit="1")
        for key in ("profile", "probe"):
            bounds = _profile_bounds(getattr(self, key))
            if bounds is not None:
                check_profile_values(f"[rider] {key}", *bounds, key=key)


@dataclass(frozen=True, slots=True)
class Handlebar:
    """The true handlebar (simulated) and the nominal one (used by observer and controller).

    ``nominal`` defaults to ``true``.
    """

    true: str = "simacom_handlebar"
    nominal: str = ""
    inertia_factor: float = 1.0
    damping_factor: float = 1.0
    friction: bool = True

    def __post_init__(self) -> None:
        if not self.nominal:
            object.__setattr__(self, "nominal", self.true)
        _check("inertia_factor", self.inertia_factor, low=0.0, low_open=True, high=10.0)
        _check("damping_factor", self.damping_factor, low=0.0, low_open=True, high=10.0)


@dataclass(frozen=True, slots=True)
class Estimator:
    """Which estimator (a name of :data:`motosim.estimation.registry.ESTIMATORS`)."""

    name: str = next(iter(ESTIMATORS))
    friction_compensation: bool = True
    lipschitz: float = 300.0
    stick_projection: bool = True

    def __post_init__(self) -> None:
        if self.name not in ESTIMATORS and self.name != SENSOR_ESTIMATOR:
            raise MotosimError(
                f"name = {self.name!r}; expected one of {', '.join(ESTIMATORS)}, {SENSOR_ESTIMATOR}"
            )
        _check("lipschitz", self.lipschitz, low=0.0, low_open=True, high=1e7, unit="rad/s^2")


@dataclass(frozen=True, slots=True)
class TorqueSensor:
    """A torque sensor between the grips and the steering column: the rider's torque on the
    handlebar (active and passive), plus ``offset`` [N*m] and white noise of standard
    deviation ``noise`` [N*m], through a first-order low-pass of corner ``low_pass`` [Hz]
    (0: none) in the estimator ``torque_sensor``."""

    noise: float = 0.0
    offset: float = 0.0
    low_pass: float = 0.0

    def __post_init__(self) -> None:
        _check("noise", self.noise, low=0.0, high=100.0, unit="N*m")
        _check("offset", self.offset, low=-100.0, high=100.0, unit="N*m")
        _check("low_pass", self.low_pass, low=0.0, high=1e5, unit="Hz")


@dataclass(frozen=True, slots=True)
class Sensor:
    """Optional sensors beyond the paper's angle and current: ``torque``, a rider-torque
    sensor read by ``[estimator] name = "torque_sensor"``."""

    torque: TorqueSensor | None = None


MAX_RECORDED_ROWS = 10_000_000
"""Most rows a run may record (one per control period, about 200 bytes each in memory)."""
MAX_PLANT_STEPS = 100_000_000
"""Most plant sub-steps of a torque profile sampled for a run (8 bytes each)."""
FEEDFORWARD = ("rider", "reference")
"""Feedforward terms of the stack's command (:func:`motosim.sim.stack.step`)."""


@dataclass(frozen=True, slots=True)
class Controller:
    """The torque-feedback controller.

    ``bandwidth`` None: :func:`motosim.control.torque_feedback.handlebar_bandwidth` of the
    nominal handlebar at the measurement rate (10 Hz, a fifth of the rate below 50 Hz; from
    1 kHz higher for a handlebar whose loop would be softer than the packaged one's at 1 Hz,
    up to 20 Hz). ``integral_corner``: the
    loop-shaping weight's corner as a fraction of the bandwidth
    (:func:`motosim.control.torque_feedback.design_torque_feedback`). ``prediction``: the
    rider-torque cancellation reads tau_r_hat + T_d times its filtered rate, T_d the estimate
    filter's delay (:func:`motosim.sim.stack.design_stack`); None: on where
    :func:`motosim.sim.stack.default_prediction` says, with the cancellation and the
    Walcott-Zak observer. ``grip``: the rider's hands the stack is designed for
    (:attr:`Scenario.stack_hands`).
    """

    kind: Literal["ours", "paper", "none"] = "ours"
    design: str | None = None
    bandwidth: float | None = None
    order: int = 1
    integral_corner: float = INTEGRAL_CORNER
    discretization: Literal["zoh", "tustin"] = "zoh"
    max_current: float = 30.0
    feedforward: tuple[str, ...] | None = None
    prediction: bool | None = None
    grip: str | None = None

    def __post_init__(self) -> None:
        if self.grip is not None and self.grip not in GRIPS:
            raise MotosimError(
                f"grip = {short_repr(self.grip)}; expected one of {', '.join(GRIPS)} (the "
                "rider's hands the stack is designed for)"
            )
        if self.design is not None and self.kind != "ours":
            raise MotosimError(
                f"design = {short_repr(self.design)} with kind = {self.kind!r}: a design file "
                'is the controller of kind = "ours"; expected kind = "ours" with it, or no design'
            )
        if self.feedforward is None:
            default = FEEDFORWARD if self.kind == "ours" else ()
            object.__setattr__(self, "feedforward", default)
        assert self.feedforward is not None
        unknown = [f for f in self.feedforward if f not in FEEDFORWARD]
        if unknown:
            raise MotosimError(
                f"feedforward has {unknown[0]!r}; expected some of {', '.join(FEEDFORWARD)}"
            )
        if self.prediction and "rider" not in self.feedforward:
            raise MotosimError(
                'prediction = true predicts the rider-torque cancellation; expected "rider" in '
                "feedforward"
            )
        if self.bandwidth is not None:  # from the slowest of a rider's steering
            _check("bandwidth", self.bandwidth, low=LOWEST_BANDWIDTH, high=1000.0, unit="Hz")
        if not 0 <= self.order <= MAX_ORDER:
            raise MotosimError(f"order = {self.order}; expected an integer from 0 to {MAX_ORDER}")
        _check("integral_corner", self.integral_corner, low=0.0, low_open=True, high=0.5)
        _check("max_current", self.max_current, low=0.0, low_open=True, high=1000.0, unit="A")


@dataclass(frozen=True, slots=True)
class Scenario:
    """One closed-loop run: the ``[scenario]`` table's keys and one field per other table."""

    name: str = "unnamed"
    description: str = ""
    duration: float = 10.0
    seed: int = 0
    architecture: Literal["closed_loop", "open_loop"] = "closed_loop"
    rates: Rates = Rates()
    measurement: Measurement = Measurement()
    motorcycle: Motorcycle = Motorcycle()
    rider: Rider = Rider("torque", ConstantProfile(0.0))
    handlebar: Handlebar = Handlebar()
    estimator: Estimator = Estimator()
    controller: Controller = Controller()
    sensor: Sensor = Sensor()
    road: Road = Road()

    def __post_init__(self) -> None:
        if self.road != Road() and self.motorcycle.model != "multibody":
            raise MotosimError(
                "[road] friction acts on the multibody motorcycle's tyres; expected [motorcycle] "
                'model = "multibody" (Sharp 1971\'s linear tyres never saturate)'
            )
        _check("duration", self.duration, low=0.0, low_open=True, high=3600.0, unit="s")
        if self.duration * self.rates.control < 2.0:
            raise MotosimError(
                f"duration = {self.duration!r} s; expected at least two control periods "
                f"({2.0 / self.rates.control:g} s at [rates] control = {self.rates.control:g} Hz)"
            )
        rows = self.duration * self.rates.control
        if rows > MAX_RECORDED_ROWS:
            raise MotosimError(
                f"duration x control rate = {rows:.3g} recorded rows; expected at most "
                f"{MAX_RECORDED_ROWS:.0e} (about 2 GB of signals in memory): shorten the run "
                "or lower [rates] control"
            )
        steps = self.duration * self.rates.plant
        if self.rider.kind == "torque" and steps > MAX_PLANT_STEPS:
            raise MotosimError(
                f"duration x plant rate = {steps:.3g} plant steps of the rider's profile; "
                f"expected at most {MAX_PLANT_STEPS:.0e}: shorten the run or lower [rates] plant"
            )
        low, high = RIDER_SPEEDS
        if self.rider.kind == "virtual" and not low <= self.motorcycle.speed <= high:
            raise MotosimError(
                f"[motorcycle] speed = {self.motorcycle.speed!r}; expected {low:g} to "
                f"{high:g} m/s with the virtual rider (its gains are scheduled over these)"
            )
        if self.seed < 0:
            raise MotosimError(f"seed = {self.seed}; expected an integer >= 0")
        # a torque rider's profile is sampled at the plant rate, the others at the control
        # rate (motosim.sim.closed_loop.build_rig): beyond half of it a profile aliases
        mc, rates = self.motorcycle, self.rates
        for where, profile, rate, key in (
            ("[rider] profile", self.rider.profile, rates.plant, "plant"),
            ("[rider] probe", self.rider.probe, rates.control, "control"),
            ("[motorcycle] drive_torque", mc.drive_torque, rates.control, "control"),
            ("[motorcycle] brake_torque", mc.brake_torque, rates.control, "control"),
            ("[motorcycle] front_brake_torque", mc.front_brake_torque, rates.control, "control"),
            ("[motorcycle] rear_brake_torque", mc.rear_brake_torque, rates.control, "control"),
            ("[road] friction", self.road.friction, rates.control, "control"),
            ("[motorcycle] wind_force", mc.wind_force, rates.control, "control"),
            ("[motorcycle] side_wind", mc.side_wind, rates.control, "control"),
        ):
            if isinstance(profile, ChirpProfile | MultisineProfile):
                top = max(profile.f0, profile.f1)
                if top > 0.5 * rate:
                    raise MotosimError(
                        f"{where}: a {profile.kind} up to {top:g} Hz; expected at most "
                        f"{0.5 * rate:g} Hz, half [rates] {key} = {rate:g} Hz, the rate it is "
                        "sampled at (beyond, it is sampled into another frequency)"
                    )
        if self.sensor.torque is not None and self.estimator.name != SENSOR_ESTIMATOR:
            raise MotosimError(
                f"[sensor] torque is read by [estimator] name = {SENSOR_ESTIMATOR!r}; got "
                f"{self.estimator.name!r}"
            )
        grip = self.controller.grip
        if grip not in (None, "off") and self.controller.design is not None:
            raise MotosimError(
                f"[controller] grip = {grip!r} with a design file: its controller was "
                'designed for the handlebar without hands; expected no grip or "off"'
            )
        if grip not in (None, "off") and self.estimator.name == SENSOR_ESTIMATOR:
            raise MotosimError(
                f"[controller] grip = {grip!r} with the torque sensor: it measures the arms' "
                'whole torque, which the stack would then count twice; expected no grip or "off"'
            )
        if self.controller.prediction and self.estimator.name != "walcott_zak":
            raise MotosimError(
                f"[controller] prediction = true with [estimator] name = "
                f'{self.estimator.name!r}; expected "walcott_zak" (the lead is its estimate '
                "filter's delay)"
            )

    @property
    def models_hands(self) -> bool:
        """Whether the stack can be designed for the rider's hands: without a design file
        (designed for the handlebar alone) and without a torque sensor (which measures the
        arms' whole torque: modelled too, they would be counted twice)."""
        return self.controller.design is None and self.estimator.name != SENSOR_ESTIMATOR

    @property
    def rider_hands(self) -> Hands | None:
        """The rider's hands on the handlebar (None, or ``off``'s: a pure torque source).

        ``[rider] hands``; by default :data:`~motosim.sim.grips.DEFAULT_GRIP` where the
        stack models hands (:attr:`models_hands`), else none: the default is never a grip
        the stack cannot be designed for, so it never refuses a scenario nor leaves a stack
        designed for the handlebar alone held by hands it does not model.

        Examples
        --------
        >>> Scenario().rider_hands.stiffness  # the relaxed grip [N*m/rad]
        10.0
        >>> Scenario(estimator=Estimator("torque_sensor")).rider_hands is None
        True
        """
        if self.rider.hands is not None:
            return resolve_hands(self.rider.hands)
        return GRIPS[DEFAULT_GRIP] if self.models_hands else None

    @property
    def stack_hands(self) -> Hands | None:
        """The hands the stack is designed for (None: a pure torque source).

        :func:`~motosim.sim.grips.design_hands` of ``[controller] grip``, by default of the
        rider's hands (:attr:`rider_hands`), except where the stack does not model hands
        (:attr:`models_hands`).
        """
        grip = self.controller.grip
        if grip is None:
            return design_hands(self.rider_hands) if self.models_hands else None
        return design_hands(GRIPS[grip])


# --- plausibility: legal values that no real ride has ---------------------------------------

VALIDATED_SPEEDS = (3.0, 55.0)
"""Speeds [m/s] of a ride the model represents: from 3 m/s, the lowest of Sharp's (1971)
Tables 1-3 (10 ft/s; below, the linearisation about forward running loses its meaning and the
machine falls at walking pace), to 55 m/s, below the 55.4 m/s where wobble turns unstable with
Sharp's steering damper."""

TYPICAL_DURATION = 600.0
"""Longest typical run [s]: the paper's runs last 8 to 20 s, a simulator exercise minutes."""

TYPICAL_RIDER_TORQUE = 100.0
"""Largest steering torque [N*m] a rider applies: tens of N*m in an emergency manoeuvre."""


def _profile_peak(profile: Any) -> float:
    """Largest magnitude a profile takes (0 when it is read from a file)."""
    if isinstance(profile, ConstantProfile):
        return abs(profile.value)
    if isinstance(profile, SquareProfile):
        return max(abs(profile.low), abs(profile.high))
    if isinstance(profile, ChirpProfile):
        return abs(profile.amplitude) + abs(profile.offset)
    if isinstance(profile, MultisineProfile):
        return abs(profile.amplitude)
    if isinstance(profile, StepsProfile):
        return max((abs(v) for v in profile.values), default=0.0)
    return 0.0


def implausible(scenario: "Scenario") -> list[str]:
    """One line for each legal but implausible value of a scenario (empty when none).

    Examples
    --------
    >>> implausible(Scenario(name="x", motorcycle=Motorcycle(speed=90.0)))[0][:40]
    '[motorcycle] speed = 90 m/s is legal but'
    """
    lines = []
    low, high = VALIDATED_SPEEDS
    speed = scenario.motorcycle.speed
    if not low <= speed <= high:
        lines.append(
            f"[motorcycle] speed = {speed:g} m/s is legal but outside the {low:g} to {high:g} m/s "
            "of a ride the model represents (Sharp 1971: the machine falls below, wobble is "
            "unstable above); expect a fall or a wobble"
        )
    if scenario.duration > TYPICAL_DURATION:
        lines.append(
            f"[scenario] duration = {scenario.duration:g} s is legal but longer than "
            f"{TYPICAL_DURATION:g} s; an unattended motorcycle (a torque profile, no rider) "
            "falls within a minute"
        )
    noise = scenario.measurement.current_noise
    limit = scenario.controller.max_current
    if noise > 0.1 * limit:
        lines.append(
            f"[measurement] current_noise = {noise:g} A is legal but more than 10 % of the "
            f"current range ([controller] max_current = {limit:g} A): the noise swamps the "
            "signal the estimator reads"
        )
    bits = scenario.measurement.encoder_bits
    if 0 < bits < 10:
        lines.append(
            f"[measurement] encoder_bits = {bits} is legal but coarser than any handlebar "
            f"encoder ({360 / 2**bits:.2g} deg a count; the paper's has 14 bits)"
        )
    path = scenario.rider.path
    if isinstance(path, TurnPath) and abs(path.angle) > 2.0 * math.pi:
        lines.append(
            f"[rider] path angle = {path.angle:g} rad ({math.degrees(path.angle):.0f} deg) is "
            "legal but more than a full circle; the angle is in radians (90 deg = 1.571)"
        )
    mc = scenario.motorcycle
    for key in MOTORCYCLE_PROFILES:
        bound = PROFILE_LIMITS[f"[motorcycle] {key}"]
        peak = _profile_peak(getattr(mc, key))
        if peak > bound.typical:
            lines.append(
                f"[motorcycle] {key} reaches {peak:g} {bound.unit}, legal but beyond the "
                f"typical {bound.typical:g} {bound.unit}: {bound.why}"
            )
    if scenario.rider.profile is not None:
        peak = _profile_peak(scenario.rider.profile)
        if peak > TYPICAL_RIDER_TORQUE:
            lines.append(
                f"[rider] profile reaches {peak:g} N*m, legal but beyond the "
                f"{TYPICAL_RIDER_TORQUE:g} N*m a rider applies to a handlebar"
            )
    return lines


# --- the parser: TOML onto the constructors -----------------------------------------------

_TABLES = (
    "rates",
    "measurement",
    "motorcycle",
    "rider",
    "handlebar",
    "estimator",
    "controller",
    "sensor",
    "road",
)


def _describe(tp: Any) -> str:
    """What a value of the annotation ``tp`` looks like, in words."""
    if tp is float:
        return "a finite number"
    if tp is int:
        return "an integer"
    if tp is bool:
        return "true or false"
    if tp is str:
        return "a string"
    if get_origin(tp) is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if get_origin(tp) is tuple:
        item = get_args(tp)[0]
        if get_origin(item) is tuple:  # hands_off's [[t0, t1], ...]
            return "a list of " + _describe(item).replace("a list", "lists", 1)
        return f"a list of {'numbers' if item is float else 'strings' if item is str else 'tables'}"
    return "a table"


def _unknown(key: str, known: list[str]) -> MotosimError:
    close = difflib.get_close_matches(key, known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return MotosimError(f"unknown key {key!r}{hint}; expected some of {', '.join(known)}")


def _value(tp: Any, value: Any, key: str, where: str) -> Any:
    """``value`` converted to the field type ``tp``, or a MotosimError naming ``key``."""
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        options = [a for a in get_args(tp) if a is not type(None)]
        if options and all(a in PROFILES.values() for a in options):
            return _tagged(PROFILES, value, key, where, number=True)
        if options and all(a in PATHS.values() for a in options):
            return _tagged(PATHS, value, key, where, number=False)
        if Hands in options:  # a grip's name or a table of the arms' impedance
            if isinstance(value, str):
                return value
            if not isinstance(value, Mapping) or not value:  # {}: no value given, say "off"
                raise MotosimError(
                    f"{key} = {short_repr(value)}; expected one of {', '.join(GRIPS)} or a "
                    "table { inertia = ..., damping = ..., stiffness = ... }"
                )
            return _build(Hands, value, f"{where}.{key}")
        return _value(options[0], value, key, where)  # ``str | None``
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise MotosimError(f"{key} = {short_repr(value)}; expected a finite number")
        try:
            return float(value)
        except OverflowError:
            raise MotosimError(f"{key} = {short_repr(value)}; expected a finite number") from None
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int) or abs(value) > 2**63 - 1:
            raise MotosimError(f"{key} = {short_repr(value)}; expected an integer")
        return value
    if tp is bool or tp is str:
        if not isinstance(value, tp):
            raise MotosimError(f"{key} = {short_repr(value)}; expected {_describe(tp)}")
        return value
    if origin is Literal:
        if value not in get_args(tp):
            raise MotosimError(f"{key} = {short_repr(value)}; expected {_describe(tp)}")
        return value
    if origin is tuple:
        item_type = get_args(tp)[0]
        if not isinstance(value, list) or (item_type is float and not value):
            raise MotosimError(f"{key} = {short_repr(value)}; expected {_describe(tp)}")
        return tuple(_value(item_type, item, f"{key} entry", where) for item in value)
    return _build(tp, value, f"{where}.{key}")


def _tagged(registry: Mapping[str, type], value: Any, key: str, where: str, *, number: bool) -> Any:
    """A profile or a path from its table (``kind`` picks the type); a number is a constant."""
    if number and not isinstance(value, Mapping):
        return ConstantProfile(_value(float, value, key, where))
    if not isinstance(value, Mapping):
        raise MotosimError(f"{key} = {short_repr(value)}; expected a table with a kind")
    kind = value.get("kind")
    if not isinstance(kind, str) or kind not in registry:
        raise MotosimError(
            f"{where}.{key}: kind = {short_repr(kind)}; expected one of {', '.join(registry)}"
        )
    return _build(registry[kind], {k: v for k, v in value.items() if k != "kind"}, f"{where}.{key}")


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """The type hints of a scenario table's class (cached: a campaign parses thousands)."""
    return get_type_hints(cls)


def _build(cls: type, table: Any, where: str) -> Any:
    """Construct the dataclass ``cls`` from a TOML table, checking every key."""
    if not isinstance(table, Mapping):
        raise MotosimError(f"{where}: expected a table, got {short_repr(table)}")
    hints = _hints(cls)
    names = [f.name for f in dataclasses.fields(cls)]
    for key in table:
        if key not in names:
            raise MotosimError(f"{where}: {_unknown(key, names)}")
    try:
        kwargs = {key: _value(hints[key], value, key, where) for key, value in table.items()}
        return cls(**kwargs)
    except MotosimError as err:
        text = str(err)
        raise MotosimError(text if text.startswith(where) else f"{where}: {text}") from None
    except TypeError:  # a required key is missing
        missing = [
            f.name
            for f in dataclasses.fields(cls)
            if f.name not in table
            and f.default is dataclasses.MISSING
            and f.default_factory is dataclasses.MISSING
        ]
        raise MotosimError(f"{where}: missing {', '.join(missing)}") from None


def parse_scenario(data: Mapping[str, Any], *, origin: str) -> Scenario:
    """Validate a parsed scenario document into a :class:`Scenario`.

    Parameters
    ----------
    data : Mapping
        The TOML document.
    origin : str
        Its file name, the prefix of error messages.

    Returns
    -------
    Scenario

    Raises
    ------
    MotosimError
        One line: an unknown table or key, a missing value, a value of the wrong type or out
        of range, inconsistent rates.
    """
    known = ["scenario", *_TABLES]
    for key in data:
        if key not in known:
            raise MotosimError(f"{origin}: {_unknown(key, known)}")
    if "scenario" not in data:
        raise MotosimError(f"{origin}: missing table [scenario]")
    head = data["scenario"]
    if not isinstance(head, Mapping):
        raise MotosimError(f"{origin}: scenario = {short_repr(head)}; expected a table [scenario]")
    own = [n for n in (f.name for f in dataclasses.fields(Scenario)) if n not in _TABLES]
    for key in head:
        if key not in own:
            raise MotosimError(f"{origin} [scenario]: {_unknown(key, own)}")
    hints = _hints(Scenario)
    where = f"{origin} [scenario]"
    try:
        kwargs = {key: _value(hints[key], value, key, where) for key, value in head.items()}
        for table in _TABLES:
            if table in data:
                kwargs[table] = _build(hints[table], data[table], f"{origin} [{table}]")
        if "rider" not in data:
            raise MotosimError(f"{origin}: missing table [rider]")
        return Scenario(**kwargs)
    except MotosimError as err:
        text = str(err)
        raise MotosimError(text if text.startswith(origin) else f"{where}: {text}") from None


def _plain(value: Any) -> Any:
    """A scenario value as plain data: dataclasses as tables (tagged with ``kind``)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        tag = getattr(type(value), "kind", None)
        out = {"kind": tag} if isinstance(tag, str) else {}
        for f in dataclasses.fields(value):
            item = getattr(value, f.name)
            if item is not None:
                out[f.name] = _plain(item)
        return out
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def scenario_dict(scenario: Scenario) -> dict[str, Any]:
    """The scenario as plain data: the ``[scenario]`` keys and one table per section.

    Profiles and paths carry their ``kind``; :func:`scenario_from_dict` reads it back.

    Examples
    --------
    >>> sc = Scenario(name="x")
    >>> scenario_dict(sc)["rider"]["profile"]
    {'kind': 'constant', 'value': 0.0}
    >>> scenario_from_dict(scenario_dict(sc), origin="metadata") == sc
    True
    """
    plain: dict[str, Any] = _plain(scenario)
    return plain


def scenario_from_dict(data: Mapping[str, Any], *, origin: str) -> Scenario:
    """Read back :func:`scenario_dict` (validated like a file)."""
    head = {k: v for k, v in data.items() if k not in _TABLES}
    return parse_scenario(
        {"scenario": head, **{k: data[k] for k in _TABLES if k in data}}, origin=origin
    )
