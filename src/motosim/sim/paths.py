"""Reference paths for the virtual rider, sampled uniformly in arc length.

A path is the ground track of the rear-frame ground point: position (x, y) [m] with x along
the initial heading and y to its right (SAE axes seen from above), heading psi [rad] (positive
turning right) and curvature kappa [1/m] (positive for a right turn), every ``ds`` metres.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = [
    "Path",
    "constant_radius_turn",
    "lane_change",
    "obstacle_avoidance",
    "slalom",
    "straight",
]

Array = NDArray[np.float64]
_DS = 0.05  # m, sample spacing


@dataclass(frozen=True, slots=True)
class Path:
    """A planar path sampled every ``ds`` metres of arc length.

    Attributes
    ----------
    ds : float
        Spacing [m].
    x, y, psi, kappa : ndarray, shape (n,)
        Position [m], heading [rad] and curvature [1/m] at s = k ds.
    """

    ds: float
    x: Array
    y: Array
    psi: Array
    kappa: Array

    @property
    def length(self) -> float:
        """Arc length [m]."""
        return self.ds * (self.x.size - 1)


def _positive(name: str, value: float) -> float:
    if not (math.isfinite(value) and value > 0):
        raise MotosimError(f"{name} = {value!r}; expected a finite number > 0 [m]")
    return float(value)


def _from_offset(x: Array, y: Array) -> Path:
    """Resample a graph y(x), x increasing, uniformly in arc length."""
    dy = np.gradient(y, x)
    ddy = np.gradient(dy, x)
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    su = np.arange(0.0, s[-1], _DS)
    return Path(
        ds=_DS,
        x=np.interp(su, s, x),
        y=np.interp(su, s, y),
        psi=np.interp(su, s, np.arctan(dy)),
        kappa=np.interp(su, s, ddy / (1.0 + dy**2) ** 1.5),
    )


def _smoothstep(u: Array) -> Array:
    """0 to 1 with zero slope and curvature at both ends (quintic)."""
    v = np.clip(u, 0.0, 1.0)
    return v**3 * (10.0 - 15.0 * v + 6.0 * v**2)


def straight(length: float) -> Path:
    """A straight line of the given length [m]."""
    x = np.linspace(0.0, _positive("length", length), 2001)
    return _from_offset(x, np.zeros_like(x))


def lane_change(offset: float, *, length: float, start: float, total: float) -> Path:
    """Move ``offset`` metres to the right (negative: left) over ``length`` metres.

    The change begins ``start`` metres down the road; the path is ``total`` metres long.
    """
    if not math.isfinite(offset):
        raise MotosimError(f"offset = {offset!r}; expected a finite lateral offset [m]")
    x = np.linspace(0.0, _positive("total", total), int(total / 0.01) + 1)
    u = (x - start) / _positive("length", length)
    return _from_offset(x, offset * _smoothstep(u))


def obstacle_avoidance(
    offset: float, *, length: float, hold: float, start: float, total: float
) -> Path:
    """Swerve ``offset`` metres aside over ``length``, hold for ``hold`` metres, come back."""
    if not math.isfinite(offset):
        raise MotosimError(f"offset = {offset!r}; expected a finite lateral offset [m]")
    x = np.linspace(0.0, _positive("total", total), int(total / 0.01) + 1)
    out = _smoothstep((x - start) / _positive("length", length))
    back = _smoothstep((x - start - length - hold) / length)
    return _from_offset(x, offset * (out - back))


def slalom(
    amplitude: float, *, wavelength: float, cycles: float, start: float, total: float
) -> Path:
    """A sinusoidal slalom of the given amplitude and wavelength [m], eased in and out."""
    x = np.linspace(0.0, _positive("total", total), int(total / 0.01) + 1)
    lam = _positive("wavelength", wavelength)
    u = (x - start) / lam
    envelope = _smoothstep(u * 2.0) * _smoothstep((cycles - u) * 2.0)
    return _from_offset(x, _positive("amplitude", amplitude) * envelope * np.sin(2 * np.pi * u))


def constant_radius_turn(
    radius: float, *, angle: float, start: float, transition: float, total: float
) -> Path:
    """Straight, a clothoid into a turn of ``radius`` [m] (positive right), the turn, straight.

    ``angle`` [rad] is the heading change of the whole turn, ``transition`` [m] the length of
    each clothoid, ``start`` [m] where the first clothoid begins and ``total`` [m] the length.
    """
    if not (math.isfinite(radius) and abs(radius) > 0):
        raise MotosimError(f"radius = {radius!r}; expected a finite non-zero radius [m]")
    s = np.arange(0.0, _positive("total", total), _DS)
    k_max = 1.0 / radius
    L = _positive("transition", transition)
    arc = abs(angle) * abs(radius) - L  # arc length at full curvature
    if arc < 0:
        raise MotosimError(
            f"angle = {angle!r} rad is too small for two {L:g} m transitions at radius {radius:g} m"
        )
    ramp_in = np.clip((s - start) / L, 0.0, 1.0)
    ramp_out = np.clip((s - start - L - arc) / L, 0.0, 1.0)
    kappa = k_max * (ramp_in - ramp_out)
    psi = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * _DS)])
    x = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(psi[1:]) + np.cos(psi[:-1])) * _DS)])
    y = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(psi[1:]) + np.sin(psi[:-1])) * _DS)])
    return Path(ds=_DS, x=x, y=y, psi=psi, kappa=kappa)
