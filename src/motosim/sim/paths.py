"""Reference paths for the virtual rider, sampled uniformly in arc length.

A path is the ground track of the rear-frame ground point: position (x, y) [m] with x along
the initial heading and y to its right (SAE axes seen from above), heading psi [rad] (positive
turning right) and curvature kappa [1/m] (positive for a right turn), every ``ds`` metres.

Besides the built-in shapes, :func:`reference_line` samples the reference line of an
OpenDRIVE road: its ``<planView>`` geometries (:class:`RoadGeometry`: lines, arcs, spirals,
the spirals clothoids whose curvature changes linearly with arc length, and parametric cubic
curves), as the ASAM OpenDRIVE 1.6 standard (section 7.4, "Geometry") defines them. Reading
the ``.xodr`` file is :func:`motosim.io.opendrive.read_opendrive`'s part.
"""

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError

__all__ = [
    "MAX_ROAD_LENGTH",
    "Path",
    "RoadGeometry",
    "constant_radius_turn",
    "lane_change",
    "obstacle_avoidance",
    "reference_line",
    "road_poses",
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


# --- OpenDRIVE reference lines --------------------------------------------------------------

MAX_ROAD_LENGTH = 50_000.0
"""Longest reference line accepted [m]: 50 km, a million samples of a path (32 MB)."""
MAX_CURVATURE = 1.0
"""Largest curvature of a road accepted [1/m]: a radius under 1 m is no road a motorcycle
rides (and the scenario's turns refuse it too)."""
MAX_COORDINATE = 1e7
"""Largest start coordinate accepted [m] (projected map coordinates reach millions)."""
GAP = 0.01
"""Largest distance [m] between where one geometry ends and where the next starts."""
GAP_HEADING = 1e-3
"""Largest heading jump [rad] between one geometry's end and the next one's start."""
_STEP = 0.25  # m, longest interval of the Gauss-Legendre integration
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(5)


@dataclass(frozen=True, slots=True)
class RoadGeometry:
    """One ``<geometry>`` of an OpenDRIVE ``<planView>``, in the file's frame and units.

    Attributes
    ----------
    kind : {"line", "arc", "spiral", "paramPoly3"}
        The element inside ``<geometry>`` (a ``<poly3>`` is read as the ``paramPoly3`` with
        ``u = p``).
    s : float
        Start position along the reference line [m].
    x, y : float
        Start position [m] (OpenDRIVE's inertial frame: x east, y north, y to the left of a
        road heading along x).
    hdg : float
        Start heading [rad], counter-clockwise from x.
    length : float
        Length [m], > 0.
    curv_start, curv_end : float
        Curvature at the start and at the end [1/m], positive turning left (counter-clockwise):
        both 0 for a line, both the arc's ``curvature`` for an arc, ``curvStart`` and
        ``curvEnd`` for a spiral, unused (0) for a ``paramPoly3``.
    poly : tuple of 8 floats, optional
        A ``paramPoly3``'s ``(aU, bU, cU, dU, aV, bV, cV, dV)``: the curve is
        ``u(p) = aU + bU p + cU p^2 + dU p^3``, ``v(p)`` likewise, in the frame at ``(x, y)``
        turned by ``hdg`` (u forward, v to the left) [m, m/p, ...].
    p_end : float
        The parameter at the curve's end: ``length`` for ``pRange = "arcLength"``, 1 for
        ``"normalized"`` [m or 1]; its arc length from 0 to ``p_end`` must be ``length``.
    """

    kind: Literal["line", "arc", "spiral", "paramPoly3"]
    s: float
    x: float
    y: float
    hdg: float
    length: float
    curv_start: float = 0.0
    curv_end: float = 0.0
    poly: tuple[float, ...] | None = None
    p_end: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("line", "arc", "spiral", "paramPoly3"):
            raise MotosimError(
                f"kind = {self.kind!r}; expected 'line', 'arc', 'spiral' or 'paramPoly3'"
            )
        for name, value, bound in (
            ("s", self.s, MAX_ROAD_LENGTH),
            ("x", self.x, MAX_COORDINATE),
            ("y", self.y, MAX_COORDINATE),
            ("hdg", self.hdg, 1e3),
            ("curv_start", self.curv_start, MAX_CURVATURE),
            ("curv_end", self.curv_end, MAX_CURVATURE),
        ):
            if not (
                isinstance(value, int | float) and math.isfinite(value) and abs(value) <= bound
            ):
                raise MotosimError(
                    f"{name} = {value!r}; expected a finite number within +-{bound:g}"
                )
        if not (math.isfinite(self.length) and 0.0 < self.length <= MAX_ROAD_LENGTH):
            raise MotosimError(
                f"length = {self.length!r}; expected a finite length > 0 and at most "
                f"{MAX_ROAD_LENGTH:g} m"
            )
        if self.kind == "line" and (self.curv_start != 0.0 or self.curv_end != 0.0):
            raise MotosimError(
                f"a line with curvature {self.curv_start!r}, {self.curv_end!r}; expected 0"
            )
        if self.kind == "arc" and self.curv_start != self.curv_end:
            raise MotosimError(
                f"an arc with curvature {self.curv_start!r} to {self.curv_end!r}; expected one "
                "constant curvature"
            )
        if (self.kind == "paramPoly3") != (self.poly is not None):
            raise MotosimError(
                f"poly = {self.poly!r} for a {self.kind}; expected the 8 coefficients for a "
                "paramPoly3 and none otherwise"
            )
        if self.poly is not None:
            _check_poly(self.poly, self.p_end, self.length)

    def heading(self, u: Array) -> Array:
        """Heading [rad] (file frame) at the distances ``u`` [m] from the start."""
        if self.poly is not None:
            return self._cubic_pose(self.poly, u)[2]
        rate = (self.curv_end - self.curv_start) / self.length
        return self.hdg + self.curv_start * u + 0.5 * rate * u**2

    def curvature(self, u: Array) -> Array:
        """Curvature [1/m] (positive left) at the distances ``u`` [m] from the start."""
        if self.poly is not None:
            return self._cubic_pose(self.poly, u)[3]
        rate = (self.curv_end - self.curv_start) / self.length
        return self.curv_start + rate * u

    def positions(self, u: Array) -> tuple[Array, Array]:
        """Position (x, y) [m] (file frame) at the sorted distances ``u`` [m] from the start.

        The integral of (cos, sin) of :meth:`heading` from 0 to each ``u``, by five-point
        Gauss-Legendre quadrature on intervals of at most 0.25 m: exact to rounding for a line
        and an arc, and to far below a micrometre for a clothoid of curvature up to 1/m. A
        ``paramPoly3`` is evaluated where its arc length is ``u`` (:func:`_poly_parameter`).
        """
        u = np.asarray(u, dtype=np.float64)
        if self.poly is not None:
            x, y = self._cubic_pose(self.poly, u)[:2]
            return x, y
        n = max(1, math.ceil(self.length / _STEP))
        grid = np.union1d(
            np.concatenate([[0.0], np.clip(u, 0.0, None)]), np.linspace(0.0, self.length, n + 1)
        )
        a, b = grid[:-1], grid[1:]
        half = 0.5 * (b - a)
        nodes = 0.5 * (a + b)[:, None] + half[:, None] * _NODES[None, :]
        psi = self.heading(nodes)
        dx = half * (np.cos(psi) @ _WEIGHTS)
        dy = half * (np.sin(psi) @ _WEIGHTS)
        cx = np.concatenate([[0.0], np.cumsum(dx)])
        cy = np.concatenate([[0.0], np.cumsum(dy)])
        idx = np.searchsorted(grid, u)
        return self.x + cx[idx], self.y + cy[idx]

    def pose(self, u: Array) -> tuple[Array, Array, Array, Array]:
        """x, y [m], heading [rad] and curvature [1/m] (file frame) at the sorted distances
        ``u`` [m] from the start (a ``paramPoly3``'s arc length inverted once for all four)."""
        if self.poly is not None:
            return self._cubic_pose(self.poly, u)
        x, y = self.positions(u)
        return x, y, self.heading(u), self.curvature(u)

    def end(self) -> tuple[float, float, float]:
        """Where the geometry ends: x, y [m] and heading [rad], file frame."""
        x, y, psi, _ = self.pose(np.array([self.length]))
        return float(x[0]), float(y[0]), float(psi[0])

    def _cubic_pose(self, poly: tuple[float, ...], u: Array) -> tuple[Array, Array, Array, Array]:
        """:meth:`pose` of a ``paramPoly3`` (``poly``, its coefficients), evaluated where its
        arc length is ``u``."""
        p = _poly_parameter(poly, self.p_end, self.length, np.asarray(u, dtype=np.float64))
        pu, pv, du, dv, ddu, ddv = _poly_values(poly, p)
        c, s = math.cos(self.hdg), math.sin(self.hdg)
        kappa: Array = (du * ddv - dv * ddu) / np.hypot(du, dv) ** 3
        return (
            self.x + c * pu - s * pv,
            self.y + s * pu + c * pv,
            self.hdg + np.arctan2(dv, du),
            kappa,
        )


def _poly_values(poly: tuple[float, ...], p: Array) -> tuple[Array, ...]:
    """u, v and their first and second derivatives in p of a paramPoly3 at ``p``."""
    aU, bU, cU, dU, aV, bV, cV, dV = poly
    return (
        aU + p * (bU + p * (cU + p * dU)),
        aV + p * (bV + p * (cV + p * dV)),
        bU + p * (2.0 * cU + 3.0 * dU * p),
        bV + p * (2.0 * cV + 3.0 * dV * p),
        2.0 * cU + 6.0 * dU * p,
        2.0 * cV + 6.0 * dV * p,
    )


def _speed(poly: tuple[float, ...], p: Array) -> Array:
    """|d(u, v)/dp| of a paramPoly3 [m per unit of p]."""
    d = _poly_values(poly, p)
    return np.hypot(d[2], d[3])


def _arc_table(poly: tuple[float, ...], p_end: float, length: float) -> tuple[Array, Array]:
    """Parameters ``p_k`` from 0 to ``p_end`` and the arc lengths at them [m]: five-point
    Gauss-Legendre on intervals of at most about 0.25 m (at least 64)."""
    n = max(64, math.ceil(length / _STEP))
    grid = np.linspace(0.0, p_end, n + 1)
    half = 0.5 * (grid[1:] - grid[:-1])
    nodes = 0.5 * (grid[1:] + grid[:-1])[:, None] + half[:, None] * _NODES[None, :]
    pieces = half * (_speed(poly, nodes) @ _WEIGHTS)
    return grid, np.concatenate([[0.0], np.cumsum(pieces)])


def _poly_parameter(poly: tuple[float, ...], p_end: float, length: float, u: Array) -> Array:
    """The parameter p where a paramPoly3's arc length is ``u`` [m] (clipped to the curve).

    From the interval of the arc-length table that holds ``u``, Newton's iteration on
    ``S(p) - u`` with ``S`` integrated by Gauss-Legendre from the interval's start:
    converged to rounding in a few steps, as ``S`` is smooth and increasing.
    """
    grid, arc = _arc_table(poly, p_end, length)
    target = np.clip(np.asarray(u, dtype=np.float64), 0.0, arc[-1])
    k = np.clip(np.searchsorted(arc, target, side="right") - 1, 0, grid.size - 2)
    p0, p1, s0 = grid[k], grid[k + 1], arc[k]
    width = arc[k + 1] - s0
    p = p0 + (p1 - p0) * np.where(
        width > 0.0, (target - s0) / np.where(width > 0.0, width, 1.0), 0.0
    )
    for _ in range(6):
        half = 0.5 * (p - p0)
        nodes = 0.5 * (p + p0)[:, None] + half[:, None] * _NODES[None, :]
        covered = s0 + half * (_speed(poly, nodes) @ _WEIGHTS)
        p = np.clip(p - (covered - target) / _speed(poly, p), p0, p1)
    return p


def _check_poly(poly: tuple[float, ...], p_end: float, length: float) -> None:
    """Refuse a paramPoly3 that is not a road: bad numbers, a stop or cusp, a sharp turn, a
    ``length`` that is not its arc length."""
    if len(poly) != 8 or not all(
        isinstance(c, int | float) and math.isfinite(c) and abs(c) <= MAX_COORDINATE for c in poly
    ):
        raise MotosimError(
            f"poly = {poly!r}; expected 8 finite coefficients within +-{MAX_COORDINATE:g}"
        )
    if not (math.isfinite(p_end) and 0.0 < p_end <= MAX_ROAD_LENGTH):
        raise MotosimError(f"p_end = {p_end!r}; expected a finite parameter range > 0")
    grid, arc = _arc_table(poly, p_end, length)
    fine = np.linspace(0.0, p_end, 8 * grid.size + 1)
    if np.min(_speed(poly, fine)) <= 1e-9 * max(1.0, arc[-1] / p_end):
        raise MotosimError("a paramPoly3 that stops or turns back (zero speed); expected a road")
    if abs(arc[-1] - length) > max(GAP, 1e-6 * length):
        raise MotosimError(
            f"a paramPoly3 whose arc length is {arc[-1]:.6g} m; its length says {length:.6g} m"
        )
    _, _, du, dv, ddu, ddv = _poly_values(poly, fine)
    kappa = (du * ddv - dv * ddu) / np.hypot(du, dv) ** 3
    if np.max(np.abs(kappa)) > MAX_CURVATURE:
        raise MotosimError(
            f"a paramPoly3 with curvature up to {np.max(np.abs(kappa)):.3g} 1/m; expected at "
            f"most {MAX_CURVATURE:g} 1/m"
        )
    turn = np.unwrap(np.arctan2(dv, du))
    if np.max(np.abs(turn - turn[0])) >= math.pi:
        raise MotosimError(
            "a paramPoly3 that turns by 180 deg or more from its start heading; expected less "
            "(split it into several geometries)"
        )


def road_poses(geometry: tuple[RoadGeometry, ...], s: Array) -> tuple[Array, Array, Array, Array]:
    """Pose of a road's reference line at the sorted arc lengths ``s`` [m] from its start.

    In the file's frame: x, y [m], heading [rad] (counter-clockwise, continuous across the
    geometries) and curvature [1/m] (positive left). Past the last geometry the line goes
    straight on.

    Raises
    ------
    MotosimError
        When the geometries are not one continuous line: a geometry's ``s`` is not where the
        previous one ends, or it starts more than :data:`GAP` m or :data:`GAP_HEADING` rad away
        from the previous one's end.
    """
    s = np.asarray(s, dtype=np.float64)
    if not geometry:
        raise MotosimError("a road without geometry; expected at least one line, arc or spiral")
    _check_continuous(geometry)
    x, y, psi, kappa = (np.empty(s.size) for _ in range(4))
    starts = np.array([g.s for g in geometry]) - geometry[0].s
    which = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(geometry) - 1)
    turn = 0.0  # multiple of 2 pi added to the file's headings to keep the line continuous
    for k, g in enumerate(geometry):
        if k > 0:
            previous = geometry[k - 1].end()[2] + turn
            turn += 2.0 * math.pi * round((previous - g.hdg - turn) / (2.0 * math.pi))
        sel = which == k
        u = np.minimum(s[sel] - starts[k], g.length)
        gx, gy, gpsi, gkappa = g.pose(u)
        x[sel], y[sel], psi[sel], kappa[sel] = gx, gy, gpsi + turn, gkappa
        if k == len(geometry) - 1:  # straight on past the end
            beyond = np.maximum(s[sel] - starts[k] - g.length, 0.0)
            end_psi = float(g.heading(np.array([g.length]))[0]) + turn
            x[sel] += beyond * math.cos(end_psi)
            y[sel] += beyond * math.sin(end_psi)
            psi[sel] = np.where(beyond > 0.0, end_psi, psi[sel])
            kappa[sel] = np.where(beyond > 0.0, 0.0, kappa[sel])
    return x, y, psi, kappa


def _check_continuous(geometry: tuple[RoadGeometry, ...]) -> None:
    """Refuse geometries that do not follow each other (one-line error naming the first)."""
    total = sum(g.length for g in geometry)
    if total > MAX_ROAD_LENGTH:
        raise MotosimError(
            f"a reference line of {total:.6g} m; expected at most {MAX_ROAD_LENGTH:g} m"
        )
    for k in range(1, len(geometry)):
        before, g = geometry[k - 1], geometry[k]
        x, y, hdg = before.end()
        where = f"geometry {k + 1} (s = {g.s:g} m)"
        if abs(g.s - (before.s + before.length)) > GAP:
            raise MotosimError(
                f"{where} starts at s = {g.s:g} m; expected {before.s + before.length:g} m, "
                "where the previous one ends"
            )
        gap = math.hypot(g.x - x, g.y - y)
        jump = abs(math.remainder(g.hdg - hdg, 2.0 * math.pi))
        if gap > GAP or jump > GAP_HEADING:
            raise MotosimError(
                f"{where} starts {gap:.3g} m and {jump:.3g} rad from where geometry {k} ends; "
                f"expected a continuous reference line (within {GAP:g} m and {GAP_HEADING:g} rad)"
            )


def reference_line(geometry: tuple[RoadGeometry, ...], total: float) -> Path:
    """The reference line of an OpenDRIVE road as a motosim path of at least ``total`` m.

    The line is moved so that it starts at the origin heading along x, and mirrored into
    motosim's frame (y to the right, heading and curvature positive turning right; OpenDRIVE's
    y is to the left). Past its end the path goes straight on, up to ``total`` [m].

    Parameters
    ----------
    geometry : tuple of RoadGeometry
        The road's ``<planView>``, in order.
    total : float
        Shortest length of the path [m].

    Returns
    -------
    Path

    Raises
    ------
    MotosimError
        When the geometries are not one continuous line (:func:`road_poses`).

    Examples
    --------
    >>> road = (RoadGeometry("line", 0.0, 5.0, 5.0, math.pi / 2, 10.0),
    ...         RoadGeometry("arc", 10.0, 5.0, 15.0, math.pi / 2, math.pi * 5.0, 0.1, 0.1))
    >>> path = reference_line(road, 100.0)  # 10 m, a quarter turn left of radius 10 m, on
    >>> round(float(path.x[-1]), 6), round(float(path.psi[-1]), 6)
    (20.0, -1.570796)
    """
    road = sum(g.length for g in geometry)
    s = np.arange(0.0, max(_positive("total", total), road) + 0.5 * _DS, _DS)
    x, y, psi, kappa = road_poses(geometry, s)
    g0 = geometry[0]
    dx, dy = x - g0.x, y - g0.y
    c, si = math.cos(g0.hdg), math.sin(g0.hdg)
    return Path(
        ds=_DS,
        x=c * dx + si * dy,
        y=-(-si * dx + c * dy),
        psi=-(psi - g0.hdg),
        kappa=-kappa,
    )
