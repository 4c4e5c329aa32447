"""The GSX-R1000 of Sharp, Evangelou & Limebeer (2004) reduced to Meijaard's four bodies.

scripts/sel2004_bodies.py reduces the paper's body table (taken from a public transcription,
see the script); these checks re-derive its arithmetic independently: the total mass and the
whole machine's mass centre and inertia are the same from the seven bodies of the table and
from the four of the reduction, the trail is the manufacturer's, and the committed parameter
file is what the script writes and loads as the packaged multibody set with its two tyres.
"""

import importlib.util
import math
import tomllib
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).parents[2]
DATA = ROOT / "src" / "motosim" / "params" / "data" / "sel2004_motorcycle.toml"


@pytest.fixture(scope="module")
def script() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "sel2004_bodies", ROOT / "scripts" / "sel2004_bodies.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _values() -> dict[str, float]:
    data = tomllib.loads(DATA.read_text(encoding="utf-8"))
    return {k: v["value"] for k, v in data["parameters"].items()}


def test_the_committed_file_is_the_scripts_output(script: ModuleType) -> None:
    assert DATA.read_text(encoding="utf-8") == script.render_toml()
    data = tomllib.loads(DATA.read_text(encoding="utf-8"))
    assert data["set"]["model"] == "multibody"
    assert data["set"]["front_tyre"] == "sel2004_front_120_70_zr17"
    assert data["set"]["rear_tyre"] == "sel2004_rear_180_55_zr17"
    for name, entry in data["parameters"].items():
        assert set(entry) == {"value", "unit", "source", "note"}, name
        assert entry["source"], name


def test_total_mass_is_the_tables(script: ModuleType) -> None:
    # SEL 2004 table: 165.13 + 33.68 + 8.0 + 9.99 + 7.25 + 14.7 + 11.9 kg
    p = _values()
    total = p["m_B"] + p["m_R"] + p["m_H"] + p["m_F"]
    assert total == pytest.approx(250.65, abs=1e-9)
    assert total == pytest.approx(sum(b.m for b in script.BODIES), abs=1e-9)


def _whole_from_four(p: dict[str, float]) -> tuple[float, float, float, float, float, float]:
    """Mass centre (x, z down) and central I_xx, I_yy, I_zz, I_xz of the whole machine."""
    parts = [
        (p["m_B"], p["x_B"], p["z_B"], p["I_Bxx"], p["I_Byy"], p["I_Bzz"], p["I_Bxz"]),
        (p["m_H"], p["x_H"], p["z_H"], p["I_Hxx"], p["I_Hyy"], p["I_Hzz"], p["I_Hxz"]),
        # the wheels: centres at r + t above the contacts, symmetric inertias
        (p["m_R"], 0.0, -(p["r_R"] + p["t_R"]), p["I_Rxx"], p["I_Ryy"], p["I_Rxx"], 0.0),
        (p["m_F"], p["w"], -(p["r_F"] + p["t_F"]), p["I_Fxx"], p["I_Fyy"], p["I_Fxx"], 0.0),
    ]
    return _about_centre(parts)


def _about_centre(
    parts: list[tuple[float, float, float, float, float, float, float]],
) -> tuple[float, float, float, float, float, float]:
    m = sum(q[0] for q in parts)
    x = sum(q[0] * q[1] for q in parts) / m
    z = sum(q[0] * q[2] for q in parts) / m
    # inertia about the origin first, then moved to the centre: another route than the script's
    Ixx = sum(q[3] + q[0] * q[2] ** 2 for q in parts) - m * z**2
    Iyy = sum(q[4] + q[0] * (q[1] ** 2 + q[2] ** 2) for q in parts) - m * (x**2 + z**2)
    Izz = sum(q[5] + q[0] * q[1] ** 2 for q in parts) - m * x**2
    Ixz = sum(q[6] - q[0] * q[1] * q[2] for q in parts) + m * x * z
    return x, z, Ixx, Iyy, Izz, Ixz


def test_whole_machine_is_the_same_from_seven_bodies_or_four(script: ModuleType) -> None:
    seven = [(b.m, b.x, -b.z_up, b.I_xx, b.I_yy, b.I_zz, -b.xz_integral) for b in script.BODIES]
    expected = _about_centre(seven)
    got = _whole_from_four(_values())
    assert got == pytest.approx(expected, rel=1e-8, abs=1e-8)


def test_trail_and_caster_are_suzukis() -> None:
    # Suzuki GSX-R1000 (2001) specifications: caster 24.0 deg, trail 96 mm
    p = _values()
    assert math.degrees(p["lam"]) == pytest.approx(24.0, abs=0.01)
    assert p["c"] == pytest.approx(0.096, abs=1e-3)
    # the wheelbase of the same specifications, 1410 mm
    assert p["w"] == pytest.approx(1.410, abs=1e-9)


def test_inertias_are_physical() -> None:
    p = _values()
    for body in ("B", "H"):
        Ixx, Iyy, Izz, Ixz = (p[f"I_{body}{a}"] for a in ("xx", "yy", "zz", "xz"))
        assert Ixx * Izz > Ixz**2  # positive definite in the x-z plane
        assert Ixx + Izz >= Iyy - 1e-9 and Iyy + Izz >= Ixx and Ixx + Iyy >= Izz  # triangle


def test_the_packaged_set_loads_with_its_tyres() -> None:
    from motosim.params import load_parameter_set, load_parameters

    pset = load_parameter_set("sel2004_motorcycle")
    assert pset.model == "multibody"
    assert pset.tyres == {
        "front_tyre": "sel2004_front_120_70_zr17",
        "rear_tyre": "sel2004_rear_180_55_zr17",
    }
    for name in pset.tyres.values():
        load_parameters(name, "tyre")
    assert pset.values.mass == pytest.approx(250.65, abs=0.01)  # the seven bodies' total
