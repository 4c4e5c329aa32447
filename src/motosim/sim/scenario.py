"""Scenario files: what one closed-loop run simulates, validated into frozen dataclasses.

A scenario is TOML; every table and key is checked, unknown keys are errors, and each error
is one line naming the key, the value and what was expected. The tables (all optional but
``[scenario]``) and their defaults::

    [scenario]     name, description, duration [s] = 10, seed = 0,
                   architecture = "closed_loop" (Fig. 7) | "open_loop" (Fig. 9)
    [rates]        plant = 10000, control = 1000, measurement = 1000 [Hz]
                   (control a multiple of measurement, plant a multiple of control)
    [measurement]  encoder_bits = 14 (0: exact angle), current_noise = 0 [A]
    [motorcycle]   params = "sharp1971", speed = 20 [m/s], input = "estimate" | "true",
                   drive_torque, brake_torque [N*m], wind_force [N]: a number or a profile
    [rider]        kind = "torque" with profile = {...}, or kind = "virtual" with path = {...}
                   and lateral_tolerance, course_tolerance, torque_scale, preview, max_torque
    [handlebar]    true = "simacom_handlebar", nominal = (true), inertia_factor = 1,
                   damping_factor = 1, friction = true
    [estimator]    name = "walcott_zak", friction_compensation = true, lipschitz = 300
    [controller]   kind = "ours" | "paper" | "none", design = "DESIGN.toml" (optional),
                   bandwidth = 10 [Hz], order = 1, discretization = "zoh" | "tustin",
                   max_current = 30 [A]

Profiles (rider torque, drive, brake, wind) are tables with ``kind``: ``constant`` (value),
``steps`` (times, values: the value after each time), ``square`` (low, high, period, start),
``chirp`` (amplitude, f0, f1, start, offset) or ``csv`` (file, column; sampled and held).
Paths have ``kind``: ``straight``, ``lane_change`` (offset, length, start), ``slalom``
(amplitude, wavelength, cycles, start), ``turn`` (radius, angle, start, transition),
``avoidance`` (offset, length, hold, start); the path is long enough for the run.
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from motosim.errors import MotosimError

__all__ = [
    "Controller",
    "Estimator",
    "Handlebar",
    "Measurement",
    "Motorcycle",
    "PathSpec",
    "Profile",
    "Rates",
    "Rider",
    "Scenario",
    "parse_scenario",
]

_PROFILE_KEYS = {
    "constant": {"value"},
    "steps": {"times", "values"},
    "square": {"low", "high", "period", "start"},
    "chirp": {"amplitude", "f0", "f1", "start", "offset"},
    "csv": {"file", "column"},
}
_PATH_KEYS = {
    "straight": set(),
    "lane_change": {"offset", "length", "start"},
    "slalom": {"amplitude", "wavelength", "cycles", "start"},
    "turn": {"radius", "angle", "start", "transition"},
    "avoidance": {"offset", "length", "hold", "start"},
}


class _Table:
    """Reads one TOML table, checking types and ranges; :meth:`done` rejects unknown keys."""

    def __init__(self, data: Any, where: str) -> None:
        if not isinstance(data, Mapping):
            raise MotosimError(f"{where}: expected a table, got {data!r}")
        self.data, self.where, self.used = data, where, set[str]()

    def number(
        self,
        key: str,
        default: float | None = None,
        *,
        low: float = -math.inf,
        high: float = math.inf,
        low_open: bool = False,
    ) -> float:
        self.used.add(key)
        if key not in self.data:
            if default is None:
                raise MotosimError(f"{self.where}: missing {key}")
            return default
        value = self.data[key]
        bound = f"{'>' if low_open else '>='} {low:g}" if low > -math.inf else ""
        bound += (" and " if bound else "") + (f"<= {high:g}" if high < math.inf else "")
        expected = f"a finite number{' ' + bound if bound else ''}"
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected {expected}")
        ok = math.isfinite(value) and value <= high and (value > low if low_open else value >= low)
        if not ok:
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected {expected}")
        return float(value)

    def integer(self, key: str, default: int, *, low: int = 0) -> int:
        self.used.add(key)
        value = self.data.get(key, default)
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected an integer >= {low}")
        return int(value)

    def string(self, key: str, default: str | None = None, choices: tuple[str, ...] = ()) -> str:
        self.used.add(key)
        value = self.data.get(key, default)
        if value is None:
            raise MotosimError(f"{self.where}: missing {key}")
        if not isinstance(value, str) or (choices and value not in choices):
            wanted = f"one of {', '.join(choices)}" if choices else "a string"
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected {wanted}")
        return value

    def boolean(self, key: str, default: bool) -> bool:
        self.used.add(key)
        value = self.data.get(key, default)
        if not isinstance(value, bool):
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected true or false")
        return value

    def numbers(self, key: str) -> tuple[float, ...]:
        self.used.add(key)
        value = self.data.get(key)
        if not isinstance(value, list) or not value:
            raise MotosimError(f"{self.where}: {key} = {value!r}; expected a list of numbers")
        for item in value:
            if (
                isinstance(item, bool)
                or not isinstance(item, int | float)
                or not math.isfinite(item)
            ):
                raise MotosimError(f"{self.where}: {key} has {item!r}; expected finite numbers")
        return tuple(float(v) for v in value)

    def sub(self, key: str) -> "_Table":
        self.used.add(key)
        return _Table(self.data.get(key, {}), f"{self.where}.{key}")

    def done(self, allowed: set[str] | None = None) -> None:
        unknown = set(self.data) - (allowed if allowed is not None else self.used)
        if unknown:
            name = sorted(unknown)[0]
            keys = sorted(allowed if allowed is not None else self.used)
            raise MotosimError(
                f"{self.where}: unknown key {name!r}; expected some of {', '.join(keys)}"
            )


@dataclass(frozen=True, slots=True)
class Profile:
    """A signal of time: ``kind`` and its settings (see the module docstring)."""

    kind: str
    settings: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class PathSpec:
    """A reference path for the virtual rider: ``kind`` and its lengths [m] and angle [rad]."""

    kind: str
    settings: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class Rates:
    """Plant sub-step, control/estimation and measurement rates [Hz]."""

    plant: float = 10_000.0
    control: float = 1000.0
    measurement: float = 1000.0


@dataclass(frozen=True, slots=True)
class Measurement:
    """Encoder resolution (bits per revolution of the handlebar, 0 for exact) and noise."""

    encoder_bits: int = 14
    current_noise: float = 0.0


@dataclass(frozen=True, slots=True)
class Motorcycle:
    """The virtual motorcycle and its longitudinal inputs."""

    params: str = "sharp1971"
    speed: float = 20.0
    input: str = "estimate"
    drive_torque: Profile = Profile("constant", {"value": 0.0})
    brake_torque: Profile = Profile("constant", {"value": 0.0})
    wind_force: Profile = Profile("constant", {"value": 0.0})


@dataclass(frozen=True, slots=True)
class Rider:
    """An open-loop torque profile or a virtual rider following a path."""

    kind: str
    profile: Profile | None = None
    path: PathSpec | None = None
    lateral_tolerance: float = 0.3
    course_tolerance: float = 0.05
    torque_scale: float = 10.0
    preview: float = 0.3
    max_torque: float = 70.0


@dataclass(frozen=True, slots=True)
class Handlebar:
    """The true handlebar (simulated) and the nominal one (used by observer and controller)."""

    true: str = "simacom_handlebar"
    nominal: str = "simacom_handlebar"
    inertia_factor: float = 1.0
    damping_factor: float = 1.0
    friction: bool = True


@dataclass(frozen=True, slots=True)
class Estimator:
    """Which estimator, with or without dry-friction compensation."""

    name: str = "walcott_zak"
    friction_compensation: bool = True
    lipschitz: float = 300.0


@dataclass(frozen=True, slots=True)
class Controller:
    """The torque-feedback controller."""

    kind: str = "ours"
    design: str | None = None
    bandwidth: float = 10.0
    order: int = 1
    discretization: str = "zoh"
    max_current: float = 30.0


@dataclass(frozen=True, slots=True)
class Scenario:
    """One closed-loop run."""

    name: str
    description: str
    duration: float
    seed: int
    architecture: str
    rates: Rates
    measurement: Measurement
    motorcycle: Motorcycle
    rider: Rider
    handlebar: Handlebar
    estimator: Estimator
    controller: Controller


def _profile(table: _Table) -> Profile:
    kind = table.string("kind", choices=tuple(_PROFILE_KEYS))
    settings: dict[str, Any] = {}
    for key in sorted(_PROFILE_KEYS[kind]):
        if key in ("times", "values"):
            settings[key] = table.numbers(key)
        elif key == "file":
            settings[key] = table.string(key)
        elif key == "column":
            settings[key] = table.string(key, "tau_r")
        elif key in ("period",):
            settings[key] = table.number(key, low=0.0, low_open=True)
        elif key in ("f0", "f1"):
            settings[key] = table.number(key, low=0.0)
        elif key in ("start", "offset"):
            settings[key] = table.number(key, 0.0)
        else:
            settings[key] = table.number(key)
    if kind == "steps" and len(settings["times"]) != len(settings["values"]):
        raise MotosimError(f"{table.where}: times and values have different lengths")
    if kind == "steps" and any(
        b <= a for a, b in zip(settings["times"], settings["times"][1:], strict=False)
    ):
        raise MotosimError(f"{table.where}: times = {settings['times']}; expected increasing times")
    table.done({"kind", *_PROFILE_KEYS[kind]})
    return Profile(kind, settings)


def _signal(parent: _Table, key: str, default: float = 0.0) -> Profile:
    parent.used.add(key)
    value = parent.data.get(key, default)
    if isinstance(value, Mapping):
        return _profile(_Table(value, f"{parent.where}.{key}"))
    return Profile("constant", {"value": parent.number(key, default)})


def _path(table: _Table) -> PathSpec:
    kind = table.string("kind", choices=tuple(_PATH_KEYS))
    positive = {"length", "wavelength", "cycles", "transition", "amplitude", "hold"}
    settings = {
        key: table.number(key, low=0.0, low_open=True) if key in positive else table.number(key)
        for key in sorted(_PATH_KEYS[kind])
    }
    if kind == "turn" and settings["radius"] == 0.0:
        raise MotosimError(f"{table.where}: radius = 0; expected a non-zero radius [m]")
    table.done({"kind", *_PATH_KEYS[kind]})
    return PathSpec(kind, settings)


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
    root = _Table(data, origin)
    head = root.sub("scenario")
    name = head.string("name", "unnamed")
    description = head.string("description", "")
    duration = head.number("duration", 10.0, low=0.0, low_open=True, high=3600.0)
    seed = head.integer("seed", 0)
    architecture = head.string("architecture", "closed_loop", ("closed_loop", "open_loop"))
    head.done()

    r = root.sub("rates")
    rates = Rates(
        plant=r.number("plant", 10_000.0, low=0.0, low_open=True, high=1e6),
        control=r.number("control", 1000.0, low=0.0, low_open=True, high=1e5),
        measurement=r.number("measurement", 1000.0, low=0.0, low_open=True, high=1e5),
    )
    r.done()
    for faster, slower, what in (
        (rates.plant, rates.control, "plant / control"),
        (rates.control, rates.measurement, "control / measurement"),
    ):
        ratio = faster / slower
        if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
            raise MotosimError(
                f"{origin}: [rates] {what} = {ratio:g}; expected a whole number >= 1"
            )

    m = root.sub("measurement")
    measurement = Measurement(
        encoder_bits=m.integer("encoder_bits", 14),
        current_noise=m.number("current_noise", 0.0, low=0.0),
    )
    m.done()
    if measurement.encoder_bits > 32:
        raise MotosimError(
            f"{origin}: [measurement] encoder_bits = {measurement.encoder_bits}; expected 0 to 32"
        )

    mc = root.sub("motorcycle")
    motorcycle = Motorcycle(
        params=mc.string("params", "sharp1971"),
        speed=mc.number("speed", 20.0, low=1.0, high=100.0),
        input=mc.string("input", "estimate", ("estimate", "true")),
        drive_torque=_signal(mc, "drive_torque"),
        brake_torque=_signal(mc, "brake_torque"),
        wind_force=_signal(mc, "wind_force"),
    )
    mc.done()

    rd = root.sub("rider")
    kind = rd.string("kind", "torque", ("torque", "virtual"))
    if kind == "torque":
        rd.used.add("profile")
        if "profile" not in rd.data:
            raise MotosimError(f'{rd.where}: missing profile for kind = "torque"')
        rider = Rider(kind, profile=_profile(_Table(rd.data["profile"], f"{rd.where}.profile")))
    else:
        rd.used.add("path")
        path = _path(_Table(rd.data.get("path", {"kind": "straight"}), f"{rd.where}.path"))
        rider = Rider(
            kind,
            path=path,
            lateral_tolerance=rd.number("lateral_tolerance", 0.3, low=0.0, low_open=True),
            course_tolerance=rd.number("course_tolerance", 0.05, low=0.0, low_open=True),
            torque_scale=rd.number("torque_scale", 10.0, low=0.0, low_open=True),
            preview=rd.number("preview", 0.3, low=0.0, high=5.0),
            max_torque=rd.number("max_torque", 70.0, low=0.0, low_open=True),
        )
    rd.done()

    hb = root.sub("handlebar")
    true = hb.string("true", "simacom_handlebar")
    handlebar = Handlebar(
        true=true,
        nominal=hb.string("nominal", true),
        inertia_factor=hb.number("inertia_factor", 1.0, low=0.0, low_open=True, high=10.0),
        damping_factor=hb.number("damping_factor", 1.0, low=0.0, low_open=True, high=10.0),
        friction=hb.boolean("friction", True),
    )
    hb.done()

    es = root.sub("estimator")
    estimator = Estimator(
        name=es.string("name", "walcott_zak", ("walcott_zak", "inverse_dynamics", "kalman")),
        friction_compensation=es.boolean("friction_compensation", True),
        lipschitz=es.number("lipschitz", 300.0, low=0.0, low_open=True),
    )
    es.done()

    ct = root.sub("controller")
    controller = Controller(
        kind=ct.string("kind", "ours", ("ours", "paper", "none")),
        design=ct.string("design") if "design" in ct.data else None,
        bandwidth=ct.number("bandwidth", 10.0, low=0.0, low_open=True),
        order=ct.integer("order", 1),
        discretization=ct.string("discretization", "zoh", ("zoh", "tustin")),
        max_current=ct.number("max_current", 30.0, low=0.0, low_open=True),
    )
    ct.done()
    root.done(
        {
            "scenario",
            "rates",
            "measurement",
            "motorcycle",
            "rider",
            "handlebar",
            "estimator",
            "controller",
        }
    )
    if "scenario" not in data:
        raise MotosimError(f"{origin}: missing table [scenario]")
    return Scenario(
        name=name,
        description=description,
        duration=duration,
        seed=seed,
        architecture=architecture,
        rates=rates,
        measurement=measurement,
        motorcycle=motorcycle,
        rider=rider,
        handlebar=handlebar,
        estimator=estimator,
        controller=controller,
    )
