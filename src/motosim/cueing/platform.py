"""The motion platform and the cueing tuning: a TOML file validated into frozen dataclasses.

A platform file has the tables ``[platform]`` (name, title, source), ``[axes.roll]``,
``[axes.pitch]``, ``[axes.yaw]`` (``angle_deg``, ``rate_deg_s``, ``accel_deg_s2``,
``bandwidth_hz``), ``[head]`` (the rider's head relative to the platform's centre of
rotation, ``x_m``, ``y_m``, ``z_m``, SAE axes), ``[rider]`` (the head on the virtual
motorcycle and its suspension pitch), ``[washout]`` and ``[mpc]`` (the tuning of the two
cueing algorithms). Keys carry their unit when it is not SI; the dataclasses hold SI values
and radians. Unknown keys, missing keys and values out of range are :class:`MotosimError`
naming the key and the expected range.

The packaged ``simacom_platform`` takes its ranges from Arioui et al., IEEE/ASME Trans.
Mechatronics 15(5), 2010, and states every other value as an assumption.
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from motosim.errors import MotosimError
from motosim.params.checks import check_text
from motosim.params.toml import parse_toml, read_toml

__all__ = [
    "AxisLimits",
    "CueingConfig",
    "MpcTuning",
    "Platform",
    "RiderHead",
    "WashoutTuning",
    "list_platforms",
    "load_platform",
    "parse_platform",
]

G = 9.81  # standard gravity used to express the pitch gain per g [m/s^2]


SMALLEST = 1e-6
"""Smallest value of a quantity that must be positive (an angle, rate, acceleration,
frequency, damping, step or weight, in SI units): a millionth of a radian or of a second is
no platform and no tuning, only a unit slip or a typo, and smaller values make the filters
singular."""

MAX_SIZE = 1e4
"""Largest magnitude of any platform or tuning number in SI units (rad/s^2, rad/s, m, Hz)."""


def _check(
    context: str,
    name: str,
    value: float,
    *,
    lower: float,
    upper: float = MAX_SIZE,
    closed: bool = False,
) -> None:
    if not closed and lower == 0.0:  # positive: at least SMALLEST
        lower, closed = SMALLEST, True
    ok = math.isfinite(value) and (value >= lower if closed else value > lower) and value <= upper
    if not ok:
        bound = f"{'>=' if closed else '>'} {lower:g}"
        bound += f" and <= {upper:g}"
        raise MotosimError(f"{context}: {name} = {value!r}; expected a finite number {bound}")


@dataclass(frozen=True, slots=True)
class AxisLimits:
    """Limits and actuator bandwidth of one platform rotation.

    Attributes
    ----------
    angle : float
        Largest angle either side of neutral [rad].
    rate : float
        Largest angular rate [rad/s].
    accel : float
        Largest angular acceleration [rad/s^2].
    bandwidth : float
        Bandwidth of the actuator's position loop, modelled as a first-order lag [rad/s].
    """

    angle: float
    rate: float
    accel: float
    bandwidth: float

    def __post_init__(self) -> None:
        _check("axis", "angle", self.angle, lower=0.0, upper=math.pi / 2)
        for name in ("rate", "accel", "bandwidth"):
            _check("axis", name, getattr(self, name), lower=0.0)


@dataclass(frozen=True, slots=True)
class Platform:
    """A rotational motion platform: three axes and where the rider's head is.

    Attributes
    ----------
    name, title, source : str
        Identification and provenance.
    roll, pitch, yaw : AxisLimits
        The three rotations (SAE: roll about x forward, pitch about y right, yaw about z down).
    head : tuple of float
        Position of the rider's head relative to the centre of rotation, in the platform
        frame (x forward, y right, z down) [m].
    """

    name: str
    title: str
    source: str
    roll: AxisLimits
    pitch: AxisLimits
    yaw: AxisLimits
    head: tuple[float, float, float]

    def __post_init__(self) -> None:
        if len(self.head) != 3 or not all(math.isfinite(x) and abs(x) <= 10.0 for x in self.head):
            raise MotosimError(
                f"platform head = {self.head!r}; expected three numbers within +/-10 m of the "
                "centre of rotation"
            )

    @property
    def axes(self) -> tuple[AxisLimits, AxisLimits, AxisLimits]:
        """The roll, pitch and yaw limits in that order."""
        return (self.roll, self.pitch, self.yaw)


@dataclass(frozen=True, slots=True)
class RiderHead:
    """The rider's head on the virtual motorcycle and the motorcycle's suspension pitch.

    Attributes
    ----------
    x : float
        Head ahead of the rear-wheel contact point [m].
    height : float
        Head above the ground, motorcycle upright [m].
    pitch_gain : float
        Quasi-static pitch per unit longitudinal acceleration, nose up positive [rad/(m/s^2)].
    pitch_frequency : float
        Natural frequency of the suspension pitch mode [rad/s].
    pitch_damping : float
        Its damping ratio.
    """

    x: float
    height: float
    pitch_gain: float
    pitch_frequency: float
    pitch_damping: float

    def __post_init__(self) -> None:
        _check("rider", "x", self.x, lower=-10.0, closed=True, upper=10.0)
        _check("rider", "height", self.height, lower=0.0, closed=True)  # 0: at the contact
        _check("rider", "pitch_gain", self.pitch_gain, lower=0.0, closed=True)
        _check("rider", "pitch_frequency", self.pitch_frequency, lower=0.0)
        _check("rider", "pitch_damping", self.pitch_damping, lower=0.0)


@dataclass(frozen=True, slots=True)
class WashoutTuning:
    """Tuning of the classical washout (see :func:`motosim.cueing.washout.design_washout`).

    Frequencies in [rad/s], angles in [rad], rates in [rad/s]; gains dimensionless.
    """

    roll_scale: float
    roll_sustained: float
    roll_onset_gain: float
    roll_onset_frequency: float
    roll_onset_damping: float
    tilt_scale: float
    tilt_frequency: float
    tilt_damping: float
    tilt_rate: float
    pitch_onset_gain: float
    pitch_onset_frequency: float
    pitch_onset_damping: float
    yaw_gain: float
    yaw_frequency: float
    yaw_damping: float
    horizon_gain: float

    def __post_init__(self) -> None:
        for name in (
            "roll_scale",
            "roll_onset_gain",
            "tilt_scale",
            "pitch_onset_gain",
            "yaw_gain",
            "horizon_gain",
        ):
            _check("washout", name, getattr(self, name), lower=0.0, closed=True)
        _check("washout", "roll_sustained", self.roll_sustained, lower=0.0, upper=math.pi / 2)
        for name in (
            "roll_onset_frequency",
            "roll_onset_damping",
            "tilt_frequency",
            "tilt_damping",
            "tilt_rate",
            "pitch_onset_frequency",
            "pitch_onset_damping",
            "yaw_frequency",
            "yaw_damping",
        ):
            _check("washout", name, getattr(self, name), lower=0.0)


@dataclass(frozen=True, slots=True)
class MpcTuning:
    """Tuning of the MPC cueing (see :func:`motosim.cueing.mpc.design_mpc`).

    Attributes
    ----------
    horizon : int
        Number of prediction steps.
    step : float
        Prediction step [s] (the input is held over it).
    canal_weight, otolith_weight : float
        Weights of the squared perceived angular-velocity and specific-force errors, each
        divided by its perception threshold.
    angle_weight, rate_weight, accel_weight : float
        Weights of the squared platform angle, rate and acceleration, each divided by its
        limit.
    pitch_rate : float
        Largest planned pitch rate [rad/s]: below the pitch threshold, so that a tilt is
        not perceived as a rotation (the tilt-coordination rate limit of the washout).
    prediction_time : float
        Time constant [s] of the vehicle motion's predicted decay over the horizon: the
        motorcycle's present angular velocity, longitudinal force and the roll-acceleration
        part of its lateral force are assumed to fade as ``exp(-t / prediction_time)`` (a
        lean rate does not last: the lean is bounded); the rest of the lateral force is held
        (see :mod:`motosim.cueing.mpc`).
    surge_weight : float
        The otolith weight of the pitch axis (longitudinal specific force, the cue of tilt
        coordination); ``otolith_weight`` is that of the roll axis (lateral force).
    pitch_angle_weight : float
        The angle weight of the pitch axis; ``angle_weight`` is that of roll and yaw.
    false_cue_weight : float
        Weight of the slack of the false-cue constraints (each divided by its threshold).
    false_cue_steps : int
        Prediction steps over which the perceived platform rotation is kept from being a
        false cue (see :mod:`motosim.cueing.mpc`); 0 for none (and no force band either).
    force_false_cue_weight : float
        Weight of the slack of the specific-force false-cue constraints (linear, divided by
        the threshold), over the whole horizon.
    preview_force_false_cue_weight : float
        The same for the roll axis on a road preview (:mod:`motosim.cueing.preview`): the
        predicted lateral force is better known, and a heavier band costs less roll.
    sustained_force_false_cue_weight : float
        The same on a road preview where the curve ahead is sustained, one-signed over the
        horizon and the time its terminal tilt is felt after it
        (:func:`motosim.cueing.preview.curve_persistence`); the weight is blended from
        ``preview_force_false_cue_weight`` (a transient road: a swerve, a lane change) to
        this one (a long curve) by that persistence.
    roll_canal_corner : float
        Corner of the roll plan's perceived roll-rate error cost, in perception thresholds:
        the error's cost is squared up to it and grows linearly beyond (the Huber function,
        of the same slope at the corner), so that a roll rate the platform cannot render
        does not buy false lateral cues; 0 for the squared cost throughout.
    """

    horizon: int
    step: float
    canal_weight: float
    otolith_weight: float
    angle_weight: float
    rate_weight: float
    accel_weight: float
    pitch_rate: float
    prediction_time: float
    surge_weight: float
    pitch_angle_weight: float
    false_cue_weight: float
    false_cue_steps: int
    force_false_cue_weight: float
    preview_force_false_cue_weight: float
    sustained_force_false_cue_weight: float
    roll_canal_corner: float

    def __post_init__(self) -> None:
        if (
            isinstance(self.horizon, bool)
            or not isinstance(self.horizon, int)
            or not (2 <= self.horizon <= 200)
        ):
            raise MotosimError(f"mpc: horizon = {self.horizon!r}; expected an integer 2..200")
        _check("mpc", "step", self.step, lower=0.0, upper=1.0)
        for name in ("canal_weight", "otolith_weight", "angle_weight", "rate_weight"):
            _check("mpc", name, getattr(self, name), lower=0.0, closed=True)
        _check("mpc", "accel_weight", self.accel_weight, lower=0.0)
        _check("mpc", "pitch_rate", self.pitch_rate, lower=0.0)
        _check("mpc", "prediction_time", self.prediction_time, lower=0.0)
        for name in (
            "surge_weight",
            "pitch_angle_weight",
            "false_cue_weight",
            "force_false_cue_weight",
            "preview_force_false_cue_weight",
            "sustained_force_false_cue_weight",
            "roll_canal_corner",
        ):
            _check("mpc", name, getattr(self, name), lower=0.0, closed=True)
        steps = self.false_cue_steps
        if isinstance(steps, bool) or not isinstance(steps, int) or not 0 <= steps <= 200:
            raise MotosimError(f"mpc: false_cue_steps = {steps!r}; expected an integer 0..200")


@dataclass(frozen=True, slots=True)
class CueingConfig:
    """Everything a platform file holds: the platform, the rider's head and the tunings."""

    platform: Platform
    rider: RiderHead
    washout: WashoutTuning
    mpc: MpcTuning


_DEG = math.pi / 180.0
_AXIS_KEYS = {
    "angle_deg": _DEG,
    "rate_deg_s": _DEG,
    "accel_deg_s2": _DEG,
    "bandwidth_hz": 2 * math.pi,
}
_HEAD_KEYS = {"x_m": 1.0, "y_m": 1.0, "z_m": 1.0}
_RIDER_KEYS = {
    "x_m": 1.0,
    "height_m": 1.0,
    "pitch_deg_per_g": _DEG / G,
    "pitch_frequency_hz": 2 * math.pi,
    "pitch_damping": 1.0,
}
_WASHOUT_KEYS = {
    "roll_scale": 1.0,
    "roll_sustained_deg": _DEG,
    "roll_onset_gain": 1.0,
    "roll_onset_frequency": 1.0,
    "roll_onset_damping": 1.0,
    "tilt_scale": 1.0,
    "tilt_frequency": 1.0,
    "tilt_damping": 1.0,
    "tilt_rate_deg_s": _DEG,
    "pitch_onset_gain": 1.0,
    "pitch_onset_frequency": 1.0,
    "pitch_onset_damping": 1.0,
    "yaw_gain": 1.0,
    "yaw_frequency": 1.0,
    "yaw_damping": 1.0,
    "horizon_gain": 1.0,
}
_MPC_KEYS = {
    "step_s": 1.0,
    "canal_weight": 1.0,
    "otolith_weight": 1.0,
    "angle_weight": 1.0,
    "rate_weight": 1.0,
    "accel_weight": 1.0,
    "pitch_rate_deg_s": _DEG,
    "prediction_time_s": 1.0,
    "surge_weight": 1.0,
    "pitch_angle_weight": 1.0,
    "false_cue_weight": 1.0,
    "force_false_cue_weight": 1.0,
    "preview_force_false_cue_weight": 1.0,
    "sustained_force_false_cue_weight": 1.0,
    "roll_canal_corner": 1.0,
}


def _table(data: Mapping[str, Any], key: str, origin: str) -> Mapping[str, Any]:
    value = data.get(key)
    if not isinstance(value, Mapping):
        raise MotosimError(f"{origin}: missing table [{key}]")
    return value


def _numbers(
    table: Mapping[str, Any], keys: Mapping[str, float], where: str, origin: str
) -> list[float]:
    """The values of ``keys`` in order, converted to SI, with one-line errors."""
    unknown = set(table) - set(keys)
    if unknown:
        raise MotosimError(
            f"{origin}: unknown key {sorted(unknown)[0]!r} in [{where}]; expected {', '.join(keys)}"
        )
    out = []
    for key, scale in keys.items():
        if key not in table:
            raise MotosimError(f"{origin}: missing key {key!r} in [{where}]")
        raw = table[key]
        if isinstance(raw, bool) or not isinstance(raw, int | float) or not math.isfinite(raw):
            raise MotosimError(f"{origin}: [{where}] {key} = {raw!r}; expected a finite number")
        out.append(float(raw) * scale)
    return out


def parse_platform(data: Mapping[str, Any], *, origin: str) -> CueingConfig:
    """Validate the contents of a platform file.

    Parameters
    ----------
    data : Mapping
        The parsed TOML document.
    origin : str
        Where it came from, the prefix of error messages.

    Returns
    -------
    CueingConfig
        The platform, the rider's head and the two tunings, in SI units and radians.

    Raises
    ------
    MotosimError
        One line naming the table and key: unknown or missing key, a value that is not a
        finite number in its range.
    """
    tables = {"platform", "axes", "head", "rider", "washout", "mpc"}
    unknown = set(data) - tables
    if unknown:
        raise MotosimError(
            f"{origin}: unknown table [{sorted(unknown)[0]}]; expected {', '.join(sorted(tables))}"
        )
    head = _table(data, "platform", origin)
    extra = set(head) - {"name", "title", "source"}
    if extra or not isinstance(head.get("name"), str):
        raise MotosimError(
            f"{origin}: [platform] needs a string name (and optional title, source); "
            f"got keys {sorted(head)}"
        )
    for key in ("name", "title", "source"):
        if key in head:
            check_text(head[key], where=f"{origin}: [platform] {key}", one_line=key == "name")
    axes_table = _table(data, "axes", origin)
    extra = set(axes_table) - {"roll", "pitch", "yaw"}
    if extra:
        raise MotosimError(
            f"{origin}: unknown axis {sorted(extra)[0]!r}; expected roll, pitch, yaw"
        )
    try:
        axes = []
        for axis in ("roll", "pitch", "yaw"):
            values = _numbers(_table(axes_table, axis, origin), _AXIS_KEYS, f"axes.{axis}", origin)
            try:
                axes.append(AxisLimits(*values))
            except MotosimError as err:
                raise MotosimError(
                    f"{origin}: [axes.{axis}] {str(err).removeprefix('axis: ')}"
                ) from None
        hx, hy, hz = _numbers(_table(data, "head", origin), _HEAD_KEYS, "head", origin)
        platform = Platform(
            name=str(head["name"]),
            title=str(head.get("title", "")),
            source=str(head.get("source", "")),
            roll=axes[0],
            pitch=axes[1],
            yaw=axes[2],
            head=(hx, hy, hz),
        )
        rider = RiderHead(*_numbers(_table(data, "rider", origin), _RIDER_KEYS, "rider", origin))
        washout = WashoutTuning(
            *_numbers(_table(data, "washout", origin), _WASHOUT_KEYS, "washout", origin)
        )
        mpc_table = dict(_table(data, "mpc", origin))
        if "horizon" not in mpc_table:
            raise MotosimError(f"{origin}: missing key 'horizon' in [mpc]")
        horizon = mpc_table.pop("horizon")
        if "false_cue_steps" not in mpc_table:
            raise MotosimError(f"{origin}: missing key 'false_cue_steps' in [mpc]")
        steps = mpc_table.pop("false_cue_steps")
        (
            step,
            canal,
            otolith,
            angle,
            rate,
            accel,
            pitch_rate,
            prediction,
            surge,
            pitch_angle,
            false_cue,
            force_false_cue,
            preview_force,
            sustained_force,
            roll_corner,
        ) = _numbers(mpc_table, _MPC_KEYS, "mpc", origin)
        mpc = MpcTuning(
            horizon,
            step,
            canal,
            otolith,
            angle,
            rate,
            accel,
            pitch_rate,
            prediction,
            surge,
            pitch_angle,
            false_cue,
            steps,
            force_false_cue,
            preview_force,
            sustained_force,
            roll_corner,
        )
    except MotosimError as err:
        message = str(err)
        raise MotosimError(
            message if message.startswith(origin) else f"{origin}: {message}"
        ) from None
    return CueingConfig(platform, rider, washout, mpc)


def _packaged_dir() -> Any:
    return resources.files("motosim.cueing") / "data"


def list_platforms() -> list[str]:
    """Names of the packaged platform files, sorted."""
    return sorted(
        p.name.removesuffix(".toml") for p in _packaged_dir().iterdir() if p.name.endswith(".toml")
    )


def load_platform(name_or_path: str | Path) -> CueingConfig:
    """Load a packaged platform by name, or a platform file by path.

    Parameters
    ----------
    name_or_path : str or Path
        A name from :func:`list_platforms` (``"simacom_platform"``) or a TOML file.

    Returns
    -------
    CueingConfig
        The validated file.

    Raises
    ------
    MotosimError
        If there is no such platform or file, the file is not TOML, or a value is invalid.

    Examples
    --------
    >>> cfg = load_platform("simacom_platform")
    >>> round(math.degrees(cfg.platform.roll.angle), 6), round(math.degrees(cfg.platform.roll.rate))
    (20.0, 30)
    """
    origin = str(name_or_path)
    if isinstance(name_or_path, str) and name_or_path in list_platforms():
        text = (_packaged_dir() / f"{name_or_path}.toml").read_text(encoding="utf-8")
        data = parse_toml(text, origin=origin)
    else:
        path = Path(name_or_path)
        if not path.exists():  # a folder or a device: refused by read_toml, saying which
            raise MotosimError(
                f"{origin}: no such platform file or packaged platform; packaged platforms are "
                f"{', '.join(list_platforms())}"
            )
        data = read_toml(path, what="platform file")
    return parse_platform(data, origin=origin)
