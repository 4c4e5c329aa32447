"""OpenDRIVE reference lines against closed forms: the Fresnel integrals and the circle.

ASAM OpenDRIVE 1.6, section 7.4, defines a spiral as a clothoid, whose curvature changes
linearly with arc length; its position is the Fresnel integrals' (Abramowitz & Stegun 7.3.1
and 7.3.2), here evaluated by ``scipy.special.fresnel`` (independent of the Gauss-Legendre
quadrature of :meth:`motosim.sim.paths.RoadGeometry.positions`). OpenDRIVE stores each
geometry's start (x, y, hdg): the integrated end of one must be the start of the next.

Its polynomial geometries (section 7.4.4-7.4.5) are checked on the parabola v = c u^2, whose
arc length has the closed form s(u) = u sqrt(1 + 4 c^2 u^2) / 2 + asinh(2 c u) / (4 c), heading
atan(2 c u) and curvature 2 c / (1 + 4 c^2 u^2)^(3/2) (any calculus text), written as a
``poly3`` and as a ``paramPoly3`` with both ``pRange`` values, and on a ``paramPoly3`` that is a
straight line.
"""

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import fresnel

from motosim.io.opendrive import parse_opendrive, read_opendrive
from motosim.io.runs import load_scenario
from motosim.sim.paths import RoadGeometry, reference_line, road_poses

ROOT = Path(__file__).parents[2]
ROAD = ROOT / "scenarios" / "roads" / "curve.xodr"


def _clothoid(
    x0: float, y0: float, h0: float, k0: float, k1: float, length: float, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Position along a clothoid by the Fresnel integrals (scipy: S, C of pi t^2 / 2).

    heading(u) = h0 + k0 u + c u^2 / 2 = phi0 + (c / 2) (u + k0 / c)^2 with c = (k1 - k0) / L,
    so that with a = sqrt(|c| / pi) and t = u + k0 / c, the integral of exp(i heading) from 0
    to u is exp(i phi0) [C(a t) + i sign(c) S(a t)] / a between t(0) and t(u).
    """
    c = (k1 - k0) / length
    a, sign = math.sqrt(abs(c) / math.pi), math.copysign(1.0, c)
    phi0 = h0 - k0**2 / (2.0 * c)
    s_u, c_u = fresnel(a * (u + k0 / c))
    s_0, c_0 = fresnel(a * (k0 / c))
    z = np.exp(1j * phi0) * ((c_u - c_0) + 1j * sign * (s_u - s_0)) / a
    return x0 + z.real, y0 + z.imag


@pytest.mark.parametrize(
    ("k0", "k1", "length"),
    [
        (0.0, 0.005, 60.0),
        (0.005, 0.0, 60.0),
        (0.0, -0.2, 40.0),
        (-0.01, 0.03, 150.0),
        (0.9, 1.0, 12.0),
    ],
)
def test_spiral_is_the_fresnel_clothoid(k0: float, k1: float, length: float) -> None:
    g = RoadGeometry("spiral", 0.0, 12.0, -7.0, 0.4, length, k0, k1)
    u = np.linspace(0.0, length, 37)
    x, y = g.positions(u)
    x_ref, y_ref = _clothoid(12.0, -7.0, 0.4, k0, k1, length, u)
    # quadrature against the closed form: far below a micrometre
    np.testing.assert_allclose(x, x_ref, atol=1e-9, rtol=0)
    np.testing.assert_allclose(y, y_ref, atol=1e-9, rtol=0)
    np.testing.assert_allclose(g.curvature(u), k0 + (k1 - k0) * u / length, atol=1e-15)


@pytest.mark.parametrize("curvature", [0.005, -0.05, 1.0])
def test_arc_is_a_circle(curvature: float) -> None:
    length = 2.0 / abs(curvature)  # two radians of the circle
    g = RoadGeometry("arc", 0.0, 3.0, 4.0, -1.0, length, curvature, curvature)
    u = np.linspace(0.0, length, 25)
    x, y = g.positions(u)
    # the circle through the start with its centre 1/curvature to the left of the heading
    h = -1.0 + curvature * u
    np.testing.assert_allclose(x, 3.0 + (np.sin(h) - math.sin(-1.0)) / curvature, atol=1e-9)
    np.testing.assert_allclose(y, 4.0 - (np.cos(h) - math.cos(-1.0)) / curvature, atol=1e-9)


def test_line() -> None:
    g = RoadGeometry("line", 0.0, 1.0, 2.0, 0.5, 10.0)
    x, y = g.positions(np.array([0.0, 10.0]))
    assert np.allclose([x[1], y[1]], [1.0 + 10 * math.cos(0.5), 2.0 + 10 * math.sin(0.5)])


def _road(shape: str, length: float) -> bytes:
    start = f's="0" x="2" y="-1" hdg="0.3" length="{length!r}"'
    text = f"<OpenDRIVE><road id='1'><planView><geometry {start}>{shape}</geometry></planView>"
    return (text + "</road></OpenDRIVE>").encode()


@pytest.mark.parametrize("c", [0.01, -0.03, 0.4])
def test_polynomials_are_the_parabola(c: float) -> None:
    def arc(u: float) -> float:  # closed-form arc length of v = c u^2
        return u * math.sqrt(1 + 4 * c * c * u * u) / 2 + math.asinh(2 * c * u) / (4 * c)

    end = 30.0 if abs(c) < 0.1 else 2.0  # curvature within the 1/m accepted
    length = arc(end)
    k = end / length  # u per unit of p when p runs over the arc length
    shapes = [
        f'<poly3 a="0" b="0" c="{c!r}" d="0"/>',
        f'<paramPoly3 aU="0" bU="{end!r}" cU="0" dU="0" aV="0" bV="0" cV="{c * end**2!r}" '
        'dV="0" pRange="normalized"/>',
        f'<paramPoly3 aU="0" bU="{k!r}" cU="0" dU="0" aV="0" bV="0" cV="{c * k * k!r}" dV="0"/>',
    ]
    s = np.linspace(0.0, length, 23)
    u = np.array([brentq(lambda x, t=t: arc(x) - t, 0.0, end + 1.0, xtol=1e-14) for t in s])
    lx, ly = u, c * u**2
    x_ref = 2.0 + math.cos(0.3) * lx - math.sin(0.3) * ly
    y_ref = -1.0 + math.sin(0.3) * lx + math.cos(0.3) * ly
    for shape in shapes:
        (g,) = parse_opendrive(_road(shape, length), origin="parabola.xodr")
        x, y, psi, kappa = road_poses((g,), s)
        np.testing.assert_allclose(x, x_ref, atol=1e-9, rtol=0)
        np.testing.assert_allclose(y, y_ref, atol=1e-9, rtol=0)
        np.testing.assert_allclose(psi, 0.3 + np.arctan(2 * c * u), atol=1e-12)
        np.testing.assert_allclose(kappa, 2 * c / (1 + 4 * c * c * u * u) ** 1.5, atol=1e-12)


def test_a_straight_param_poly3_is_the_line() -> None:
    line = RoadGeometry("line", 0.0, 1.0, 2.0, 0.5, 10.0)
    (poly,) = parse_opendrive(
        _road(
            '<paramPoly3 aU="0" bU="1" cU="0" dU="0" aV="0" bV="0" cV="0" dV="0"/>', 10.0
        ).replace(b'x="2" y="-1" hdg="0.3"', b'x="1" y="2" hdg="0.5"'),
        origin="line.xodr",
    )
    u = np.linspace(0.0, 10.0, 11)
    np.testing.assert_allclose(poly.positions(u), line.positions(u), atol=1e-12)
    np.testing.assert_allclose(poly.heading(u), line.heading(u), atol=1e-15)
    assert np.all(poly.curvature(u) == 0.0)


def test_each_geometry_ends_where_the_file_starts_the_next() -> None:
    geometry = read_opendrive(ROAD)
    assert [g.kind for g in geometry] == ["line", "spiral", "arc", "spiral", "line"]
    for before, after in itertools.pairwise(geometry):
        x, y, hdg = before.end()
        # the file's starts were computed with the Fresnel integrals (its header comment)
        assert math.hypot(x - after.x, y - after.y) < 1e-3
        assert abs(hdg - after.hdg) < 1e-9


def test_reference_line_in_motosim_frame() -> None:
    geometry = read_opendrive(ROAD)
    path = reference_line(geometry, 600.0)
    # starts at the origin heading along x; the file's left turn is a right-negative one
    assert (path.x[0], path.y[0], path.psi[0]) == (0.0, 0.0, 0.0)
    assert path.length >= 600.0 - path.ds
    np.testing.assert_allclose(np.hypot(np.diff(path.x), np.diff(path.y)), path.ds, atol=2e-6)
    # heading: 0.8 rad to the left in all (0.15 + 0.5 + 0.15), then straight on
    assert path.psi[-1] == pytest.approx(-0.8, abs=1e-12)
    s = np.arange(path.x.size) * path.ds
    in_arc = (s > 181.0) & (s < 279.0)
    np.testing.assert_allclose(path.kappa[in_arc], -1.0 / 200.0, atol=1e-15)
    # every sample is the file's point, rotated and mirrored
    x, y, _, _ = road_poses(geometry, s)
    g0 = geometry[0]
    back_x = g0.x + math.cos(g0.hdg) * path.x + math.sin(g0.hdg) * path.y
    back_y = g0.y + math.sin(g0.hdg) * path.x - math.cos(g0.hdg) * path.y
    np.testing.assert_allclose(back_x, x, atol=1e-9)
    np.testing.assert_allclose(back_y, y, atol=1e-9)


def test_the_scenario_reads_the_road() -> None:
    scenario = load_scenario(ROOT / "scenarios" / "opendrive_curve.toml")
    assert scenario.rider.path is not None
    assert scenario.rider.path.geometry == read_opendrive(ROAD)  # type: ignore[union-attr]
