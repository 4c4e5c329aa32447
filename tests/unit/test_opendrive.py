"""OpenDRIVE roads as scenario paths: the file's parser, the path kind, the view's road."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motosim.errors import MotosimError
from motosim.io import opendrive
from motosim.io.opendrive import parse_opendrive, read_opendrive
from motosim.io.runs import load_run, load_scenario
from motosim.sim.paths import RoadGeometry
from motosim.sim.scenario import OpenDrivePath, parse_scenario, scenario_dict, scenario_from_dict

ROOT = Path(__file__).parents[2]
ROAD = ROOT / "scenarios" / "roads" / "curve.xodr"
TEXT = ROAD.read_text(encoding="utf-8")


def _geometry(shape: str, **start: str) -> bytes:
    attrs = {"s": "0", "x": "0", "y": "0", "hdg": "0", "length": "10", **start}
    text = " ".join(f'{k}="{v}"' for k, v in attrs.items())
    return (
        f'<OpenDRIVE><road id="1"><planView><geometry {text}>{shape}</geometry>'
        "</planView></road></OpenDRIVE>"
    ).encode()


def test_reads_lines_arcs_and_spirals() -> None:
    geometry = read_opendrive(ROAD)
    assert [(g.kind, g.length, g.curv_start, g.curv_end) for g in geometry] == [
        ("line", 120.0, 0.0, 0.0),
        ("spiral", 60.0, 0.0, 0.005),
        ("arc", 100.0, 0.005, 0.005),
        ("spiral", 60.0, 0.005, 0.0),
        ("line", 150.0, 0.0, 0.0),
    ]
    assert read_opendrive(ROAD, road="1") == geometry


def test_a_namespace_and_zero_length_geometries_are_accepted() -> None:
    doc = TEXT.replace("<OpenDRIVE>", '<OpenDRIVE xmlns="http://example.org/opendrive">')
    zero = '<geometry s="0" x="100" y="50" hdg="0.3" length="0"><line/></geometry>'
    doc = doc.replace("<planView>", "<planView>" + zero)
    assert parse_opendrive(doc.encode(), origin="r.xodr") == read_opendrive(ROAD)


@pytest.mark.parametrize(
    ("raw", "expected"),
    [
        (
            _geometry('<paramPoly3 aU="0" bU="0.5" cU="0" dU="0" aV="0" bV="0" cV="0" dV="0"/>'),
            "a paramPoly3 whose arc length is 5 m; its length says 10 m",
        ),
        (
            _geometry('<poly3 a="0" b="0" c="5" d="0"/>'),
            "a paramPoly3 with curvature up to 10 1/m; expected at most 1 1/m",
        ),
        (
            _geometry(
                '<paramPoly3 aU="0" bU="0" cU="0" dU="1" aV="0" bV="0" cV="0" dV="0" '
                'pRange="normalized"/>',
                length="1",
            ),
            "a paramPoly3 that stops or turns back (zero speed)",
        ),
        (
            _geometry(
                '<paramPoly3 aU="0" bU="1" cU="0" dU="0" aV="0" bV="0" cV="0" dV="0" '
                'pRange="unit"/>'
            ),
            "pRange = 'unit'; expected 'arcLength' or 'normalized'",
        ),
        (_geometry('<poly3 a="0" b="0" c="0"/>'), "missing attribute 'd'; expected a number"),
        (  # many long geometries are refused before each one's arc length is integrated
            _geometry(
                '<paramPoly3 aU="0" bU="1" cU="0" dU="0" aV="0" bV="0" cV="0" dV="0"/>',
                length="30000",
            ).replace(
                b"</planView>",
                b"".join(
                    b'<geometry s="0" x="0" y="0" hdg="0" length="30000"><paramPoly3 aU="0" '
                    b'bU="1" cU="0" dU="0" aV="0" bV="0" cV="0" dV="0"/></geometry>'
                    for _ in range(1000)
                )
                + b"</planView>",
            ),
            "geometry 2: the geometries reach 60000 m; expected a reference line of at most",
        ),
        (  # u = 100 p - 300 p^3, v = 150 p^2 - 120 p^3: ends heading 184 deg from its start
            _geometry(
                '<paramPoly3 aU="0" bU="100" cU="0" dU="-300" aV="0" bV="0" cV="150" dV="-120" '
                'pRange="normalized"/>',
                length="256.2601696980916",
            ),
            "a paramPoly3 that turns by 180 deg or more from its start heading",
        ),
        (_geometry("<line/>", hdg="nan"), "hdg = 'nan'; expected a finite number"),
        (_geometry("<line/>", x="1e400"), "x = '1e400'; expected a finite number"),
        (_geometry("<line/>", length="-3"), "length = -3.0; expected a finite length > 0"),
        (_geometry('<arc curvature="2"/>'), "curv_start = 2.0; expected a finite number"),
        (_geometry('<spiral curvStart="0"/>'), "missing attribute 'curvEnd'"),
        (_geometry("<line/><line/>"), "<line>, <line>; expected one of"),
        (_geometry("<clothoid/>"), "<clothoid>; expected one of <line>, <arc>, <spiral>"),
        (b"<OpenDRIVE><road id='a'/><road id='b'/></OpenDRIVE>", "2 roads (a, b); choose one"),
        (b"<OpenDRIVE/>", "no <road>"),
        (b"<road/>", "root element <road>; expected <OpenDRIVE>"),
        (b"<OpenDRIVE><road", "not well-formed XML"),
        (b"<OpenDRIVE>\xff\xfe</OpenDRIVE>", "byte 11 is not UTF-8; expected an OpenDRIVE file"),
        ("<OpenDRIVE/>".encode("utf-16"), "byte 0 is not UTF-8"),
        (b'<!DOCTYPE x [<!ENTITY a "b">]><OpenDRIVE/>', "a document type declaration"),
        (
            TEXT.replace('x="214.64', 'x="214.74', 1).encode(),
            "geometry 2 (s = 120 m) starts 0.1 m and 0 rad from where geometry 1 ends",
        ),
        (
            TEXT.replace('s="120.000', 's="121.000', 1).encode(),
            "geometry 2 (s = 121 m) starts at s = 121 m; expected 120 m",
        ),
    ],
)
def test_bad_files_are_refused_in_one_line(raw: bytes, expected: str) -> None:
    with pytest.raises(MotosimError) as info:
        parse_opendrive(raw, origin="road.xodr")
    text = str(info.value)
    assert text.startswith("road.xodr: ") and "\n" not in text and len(text) < 300, text
    assert expected in text, text


def test_a_missing_road_id_and_a_large_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.raises(MotosimError, match=r"no road with id '9'; have 1$"):
        read_opendrive(ROAD, road="9")
    with pytest.raises(MotosimError, match="no such OpenDRIVE file"):
        read_opendrive(tmp_path / "none.xodr")
    monkeypatch.setattr(opendrive, "MAX_XODR_BYTES", 100)
    with pytest.raises(MotosimError, match=r"is \d+ bytes; expected at most 100 bytes"):
        read_opendrive(ROAD)


def test_path_kind_parses_and_round_trips_with_its_geometry() -> None:
    scenario = load_scenario(ROOT / "scenarios" / "opendrive_curve.toml")
    path = scenario.rider.path
    assert isinstance(path, OpenDrivePath) and len(path.geometry) == 5
    # a saved result keeps the geometry: read back without the file
    again = scenario_from_dict(scenario_dict(scenario), origin="metadata")
    assert again == scenario
    assert np.array_equal(again.rider.path.build(10.0).x, path.build(10.0).x)  # type: ignore[union-attr]


def test_a_polynomial_road_is_continuous_and_round_trips() -> None:
    # a gentle poly3 bend, then the line that starts where it ends (as an exporter writes it)
    (bend,) = parse_opendrive(
        _geometry('<poly3 a="0" b="0" c="0.002" d="-2e-5"/>', length="50"), origin="r.xodr"
    )
    x, y, hdg = bend.end()
    line = f'<geometry s="50" x="{x!r}" y="{y!r}" hdg="{hdg!r}" length="30"><line/></geometry>'
    raw = _geometry('<poly3 a="0" b="0" c="0.002" d="-2e-5"/>', length="50")
    geometry = parse_opendrive(
        raw.replace(b"</planView>", line.encode() + b"</planView>"), origin="r.xodr"
    )
    assert [g.kind for g in geometry] == ["paramPoly3", "line"]
    rider = {"kind": "virtual", "path": {"kind": "opendrive", "file": "r.xodr"}}
    doc = {"scenario": {"name": "x"}, "motorcycle": {"speed": 15.0}, "rider": rider}
    plain = parse_scenario(doc, origin="s.toml")
    path = dataclasses.replace(plain.rider.path, geometry=geometry)  # type: ignore[type-var]
    scenario = dataclasses.replace(plain, rider=dataclasses.replace(plain.rider, path=path))
    again = scenario_from_dict(scenario_dict(scenario), origin="metadata")
    assert again == scenario
    road = again.rider.path.build(80.0)  # type: ignore[union-attr]
    assert np.max(np.abs(np.diff(road.psi))) < 0.01  # no kink where the bend meets the line


def test_path_kind_without_its_file_read_says_so() -> None:
    doc = {
        "scenario": {"name": "x"},
        "rider": {"kind": "virtual", "path": {"kind": "opendrive", "file": "r.xodr"}},
    }
    scenario = parse_scenario(doc, origin="s.toml")
    with pytest.raises(MotosimError, match=r"r\.xodr: the OpenDRIVE file was not read"):
        scenario.rider.path.build(10.0)  # type: ignore[union-attr]
    doc["rider"]["path"]["file"] = ""  # type: ignore[index]
    with pytest.raises(MotosimError, match=r"s.toml \[rider\].path: file = ''; expected an"):
        parse_scenario(doc, origin="s.toml")


def test_inline_geometry_must_be_continuous() -> None:
    line = RoadGeometry("line", 0.0, 0.0, 0.0, 0.0, 10.0)
    far = dataclasses.replace(line, s=10.0, x=11.0)
    with pytest.raises(MotosimError, match=r"geometry 2 .* starts 1 m and 0 rad from where"):
        OpenDrivePath("r.xodr", geometry=(line, far))


def test_the_view_draws_the_road_the_rider_follows() -> None:
    pytest.importorskip("starlette")
    from motosim.view.live import SimulatedRig

    inputs = load_run(ROOT / "scenarios" / "opendrive_curve.toml")
    road = SimulatedRig(inputs).road()
    path = inputs.scenario.rider.path.build(100.0)  # type: ignore[union-attr]
    # the road's centre line passes through the path's points (the view resamples it)
    for k in range(0, path.x.size, 400):
        assert np.min(np.hypot(road.x - path.x[k], road.y - path.y[k])) < 0.5
    assert road.y.min() < -150.0  # the left turn is drawn (y to the right)
