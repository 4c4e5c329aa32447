"""OpenDRIVE roads: the reference line of one road of an ``.xodr`` file.

A scenario's path ``{ kind = "opendrive", file = "road.xodr" }`` names a file of the ASAM
OpenDRIVE format (an XML document); :func:`read_opendrive` reads the ``<planView>`` of one of
its roads into :class:`motosim.sim.paths.RoadGeometry` records, which
:func:`motosim.sim.paths.reference_line` samples. Only the plan view is read (lines, arcs,
spirals, ``paramPoly3`` and the deprecated ``poly3``, ASAM OpenDRIVE 1.6 section 7.4): lanes,
elevation, superelevation and junctions are ignored.

The file is untrusted input: its size is checked before it is read, a document type
declaration (``<!DOCTYPE``, hence any entity) is refused, and it is parsed by
``defusedxml`` when that is installed, else by the standard library's
:mod:`xml.etree.ElementTree`; every number must be finite and in range. Each failure is one
line naming the file and what was expected.
"""

import importlib
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np

from motosim.errors import MotosimError
from motosim.params.toml import read_limited
from motosim.sim.paths import MAX_ROAD_LENGTH, RoadGeometry, road_poses

__all__ = ["MAX_GEOMETRIES", "MAX_XODR_BYTES", "parse_opendrive", "read_opendrive"]

MAX_XODR_BYTES = 20_000_000
"""Largest ``.xodr`` file read [bytes] (a city's map is a few MB)."""
MAX_GEOMETRIES = 100_000
"""Most ``<geometry>`` elements of the chosen road."""
_SHAPES = "<line>, <arc>, <spiral>, <paramPoly3> or <poly3>"


def _parse_xml(raw: bytes, origin: str) -> Any:
    """The document's root element (defusedxml when installed)."""
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise MotosimError(
            f"{origin}: byte {err.start} is not UTF-8; expected an OpenDRIVE file in UTF-8"
        ) from None
    if "<!doctype" in text.lower():
        raise MotosimError(
            f"{origin}: a document type declaration; expected an OpenDRIVE file without one "
            "(<!DOCTYPE> and entities are refused)"
        )
    try:
        fromstring = importlib.import_module("defusedxml.ElementTree").fromstring
    except ImportError:  # no declaration (refused above), so no entity can expand
        fromstring = ET.fromstring
    try:
        root = fromstring(raw)
    except ET.ParseError as err:
        raise MotosimError(
            f"{origin}: not well-formed XML ({err}); expected an OpenDRIVE file"
        ) from None
    except ValueError as err:  # defusedxml's refusals
        raise MotosimError(f"{origin}: {err}; expected a plain OpenDRIVE file") from None
    for element in root.iter():  # OpenDRIVE 1.8 files may carry a namespace: drop it
        if isinstance(element.tag, str) and element.tag.startswith("{"):
            element.tag = element.tag.split("}", 1)[1]
    return root


def _number(element: Any, name: str, where: str) -> float:
    text = element.get(name)
    if text is None:
        raise MotosimError(f"{where}: missing attribute {name!r}; expected a number")
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise MotosimError(f"{where}: {name} = {text[:40]!r}; expected a finite number")
    return value


def _polynomial(shape: Any, length: float, where: str) -> tuple[tuple[float, ...], float]:
    """A ``<paramPoly3>`` or ``<poly3>`` as paramPoly3 coefficients and the end parameter.

    A ``poly3`` (``v = a + b u + c u^2 + d u^3``) is the paramPoly3 ``u(p) = p``; its end is
    where its arc length reaches ``length`` (Newton's iteration from ``u = length``).
    """
    if not 0.0 < length <= MAX_ROAD_LENGTH:
        raise MotosimError(
            f"{where}: length = {length!r}; expected a finite length > 0 and at most "
            f"{MAX_ROAD_LENGTH:g} m"
        )
    if shape.tag == "paramPoly3":
        names = ("aU", "bU", "cU", "dU", "aV", "bV", "cV", "dV")
        coefficients = tuple(_number(shape, n, where) for n in names)
        p_range = shape.get("pRange", "arcLength")
        if p_range not in ("arcLength", "normalized"):
            raise MotosimError(
                f"{where}: pRange = {p_range[:40]!r}; expected 'arcLength' or 'normalized'"
            )
        return coefficients, (length if p_range == "arcLength" else 1.0)
    a, b, c, d = (_number(shape, n, where) for n in ("a", "b", "c", "d"))
    coefficients = (0.0, 1.0, 0.0, 0.0, a, b, c, d)
    nodes, weights = np.polynomial.legendre.leggauss(8)

    def slope(u: Any) -> Any:
        return np.sqrt(1.0 + (b + u * (2.0 * c + 3.0 * d * u)) ** 2)

    u_end = length  # the arc length is at least u, so the end is at most length
    pieces = max(8, min(4096, math.ceil(length / 0.25)))
    for _ in range(50):
        edges = np.linspace(0.0, u_end, pieces + 1)
        half = 0.5 * np.diff(edges)
        mid = 0.5 * (edges[1:] + edges[:-1])
        arc = float(np.sum(half * (slope(mid[:, None] + half[:, None] * nodes) @ weights)))
        step = (arc - length) / float(slope(u_end))
        u_end -= step
        if not (math.isfinite(u_end) and u_end > 0.0):
            raise MotosimError(f"{where}: a poly3 whose arc length never reaches its length")
        if abs(step) <= 1e-12 * length:
            break
    return coefficients, u_end


def parse_opendrive(raw: bytes, *, origin: str, road: str = "") -> tuple[RoadGeometry, ...]:
    """The plan view of one road of an OpenDRIVE document.

    Parameters
    ----------
    raw : bytes
        The document.
    origin : str
        Its name, the prefix of error messages.
    road : str
        The ``id`` of the road; ``""`` for the document's only road.

    Returns
    -------
    tuple of RoadGeometry
        The road's ``<geometry>`` elements in order of ``s`` (zero-length ones dropped).

    Raises
    ------
    MotosimError
        One line: not XML, a DTD, no ``<OpenDRIVE>`` root, no such road (or several and no
        ``road`` given), a missing or non-finite number, a value out of range, a polynomial
        geometry that is not a road (a cusp, a turn of 180 deg, a ``length`` that is not its
        arc length), or geometries that are not one continuous line.

    Examples
    --------
    >>> doc = b'''<OpenDRIVE><road id="7" length="10"><planView>
    ...   <geometry s="0" x="0" y="0" hdg="0" length="10"><line/></geometry>
    ... </planView></road></OpenDRIVE>'''
    >>> parse_opendrive(doc, origin="road.xodr")[0].kind
    'line'
    """
    root = _parse_xml(raw, origin)
    if root.tag != "OpenDRIVE":
        raise MotosimError(f"{origin}: root element <{root.tag[:40]}>; expected <OpenDRIVE>")
    chosen = _chosen_road(root, road, origin)
    label = f"{origin}: road {chosen.get('id', '')!r}"
    elements = chosen.findall("planView/geometry")
    if not elements:
        raise MotosimError(f"{label}: no <planView><geometry>; expected at least one")
    if len(elements) > MAX_GEOMETRIES:
        raise MotosimError(
            f"{label}: {len(elements)} geometries; expected at most {MAX_GEOMETRIES}"
        )
    out = []
    total = 0.0
    for k, element in enumerate(elements, start=1):
        piece, total = _geometry(element, f"{label} geometry {k}", total)
        if piece is not None:
            out.append(piece)
    out.sort(key=lambda g: g.s)
    geometry = tuple(out)
    if not geometry:
        raise MotosimError(f"{label}: only zero-length geometries; expected a road")
    try:
        road_poses(geometry, np.zeros(1))
    except MotosimError as err:
        raise MotosimError(f"{label}: {err}") from None
    return geometry


def _chosen_road(root: ET.Element, road: str, origin: str) -> ET.Element:
    """The ``<road>`` element of id ``road``, or the document's only one for ``""``."""
    roads = root.findall("road")
    ids = [str(r.get("id", "")) for r in roads]
    listed = ", ".join(ids[:10]) + (", ..." if len(ids) > 10 else "")
    if not roads:
        raise MotosimError(f"{origin}: no <road>; expected at least one")
    if road:
        if road not in ids:
            raise MotosimError(f"{origin}: no road with id {road[:40]!r}; have {listed}")
        return roads[ids.index(road)]
    if len(roads) > 1:
        raise MotosimError(
            f'{origin}: {len(roads)} roads ({listed}); choose one with road = "ID" in the path'
        )
    return roads[0]


def _geometry(element: ET.Element, where: str, total: float) -> tuple[RoadGeometry | None, float]:
    """One ``<geometry>`` (None for a zero-length one) and the length of the road up to its
    end [m], ``total`` being that up to its start."""
    shapes = [child for child in element if child.tag != "userData"]
    if len(shapes) != 1:
        names = ", ".join(f"<{c.tag}>" for c in shapes) or "none"
        raise MotosimError(f"{where}: {names}; expected one of {_SHAPES}")
    shape = shapes[0]
    poly: tuple[float, ...] | None = None
    p_end = 0.0
    kind: Any = shape.tag
    if shape.tag == "line":
        curv = (0.0, 0.0)
    elif shape.tag == "arc":
        c = _number(shape, "curvature", where)
        curv = (c, c)
    elif shape.tag == "spiral":
        curv = (_number(shape, "curvStart", where), _number(shape, "curvEnd", where))
    elif shape.tag not in ("paramPoly3", "poly3"):
        raise MotosimError(f"{where}: <{shape.tag[:40]}>; expected one of {_SHAPES}")
    start = [_number(element, name, where) for name in ("s", "x", "y", "hdg", "length")]
    if start[4] == 0.0:
        return None, total  # a zero-length geometry (exporters write them) draws nothing
    total += abs(start[4])
    if total > MAX_ROAD_LENGTH:  # before a cubic's arc length is integrated
        raise MotosimError(
            f"{where}: the geometries reach {total:.6g} m; expected a reference line of at "
            f"most {MAX_ROAD_LENGTH:g} m"
        )
    if shape.tag in ("paramPoly3", "poly3"):
        curv = (0.0, 0.0)
        kind, poly, p_end = "paramPoly3", *_polynomial(shape, start[4], where)
    try:
        s, x, y, hdg, length = start
        geometry = RoadGeometry(kind, s, x, y, hdg, length, *curv, poly, p_end)
    except MotosimError as err:
        raise MotosimError(f"{where}: {err}") from None
    return geometry, total


def read_opendrive(path: str | Path, *, road: str = "") -> tuple[RoadGeometry, ...]:
    """Read the plan view of one road of the OpenDRIVE file ``path``.

    See :func:`parse_opendrive`; the file is at most :data:`MAX_XODR_BYTES` long.

    Raises
    ------
    MotosimError
        One line: no such file, too large, unreadable, or what :func:`parse_opendrive` refuses.
    """
    raw = read_limited(Path(path), what="OpenDRIVE file", max_bytes=MAX_XODR_BYTES)
    return parse_opendrive(raw, origin=str(path), road=road)
