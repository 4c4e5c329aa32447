"""The Suzuki GSX-R1000 of Sharp, Evangelou & Limebeer (2004) as four rigid bodies.

    .venv/bin/python scripts/sel2004_bodies.py [OUT.toml]

Reduces the paper's body table (main frame with the rider's lower body, the rider's upper
body, swing arm, upper and lower fork, wheels; Sharp, Evangelou & Limebeer 2004, Multibody
Syst. Dyn. 12:251-283, the parameter tables of the GSX-R1000) to the four bodies of the
Whipple-Carvallo model in Meijaard et al.'s (2007) parameterisation: the rear frame B (main
frame, upper body and swing arm locked together), the rear wheel R, the front frame H (upper
and lower fork locked: no suspension travel) and the front wheel F. Masses add; mass centres
are mass-weighted means; each inertia is moved to the composite mass centre by the parallel-
axis theorem, ``I_xx += m dz^2``, ``I_yy += m (dx^2 + dz^2)``, ``I_zz += m dx^2``,
``I_xz -= m dx dz`` (the tensor's entry, Meijaard's convention). The steering axis passes
through the steering head at the caster angle; the trail is how far ahead of the front
contact it meets the ground. Prints (or writes) the TOML parameter set.

The numbers were taken from a public transcription of the paper's tables (a Julia EoM
example, ``input_ex_GSXR``: points p2-p22, masses, inertias, stiffnesses), not from the
paper itself, which was not reachable. Its coordinates: x forward from the rear contact,
z up; Meijaard's: z down, so every height changes sign. Its products of inertia are
``integral(x z dm)`` in the paper's SAE axes (x forward, z down): the main frame's +3.691
puts its mass low in front and high behind (engine and seat), the upper body's -0.443 a
rider leaning forward. Meijaard's tensor entry is minus that integral.

Assumed (not in the transcription): the upper fork's inertias are about axes parallel to
the global ones (the transcription enters them so); the lower fork is a point mass (no
inertia given); the bell crank has no mass; the wheel radii of the toroidal model are the
axle heights less the tyres' crown radii (axle height = r + t upright), the crown radii
those of the packaged tyre sets (Cossalter & Lot 2002 via Evangelou 2004, sec. 9.3.5).
"""

import math
import sys
from pathlib import Path
from typing import NamedTuple

SEL = "Sharp, Evangelou & Limebeer 2004, Multibody Syst. Dyn. 12:251-283, GSX-R1000 tables"
VIA = "via the public transcription input_ex_GSXR (EoM.jl example)"


class Body(NamedTuple):
    """One body of the paper's table: mass [kg], mass centre x forward, z up [m], inertias
    about the mass centre [kg*m^2] and the product integral(x z dm) in SAE axes [kg*m^2]."""

    name: str
    m: float
    x: float
    z_up: float
    I_xx: float
    I_yy: float
    I_zz: float
    xz_integral: float


# Sharp, Evangelou & Limebeer 2004 (via input_ex_GSXR): p8, p10, p14, p3, p5, p7, p6
MAIN_FRAME = Body(
    "main frame with the rider's lower body", 165.13, 0.6779, 0.4724, 11.085, 22.013, 14.982, 3.691
)
UPPER_BODY = Body("rider's upper body", 33.68, 0.415, 1.14, 1.428, 1.347, 0.916, -0.443)
SWING_ARM = Body("swing arm", 8.0, 0.196, 0.3113, 0.02, 0.259, 0.259, 0.0)
UPPER_FORK = Body("upper fork and handlebar", 9.99, 1.164, 0.77, 1.341, 1.548, 0.4125, 0.0)
LOWER_FORK = Body("lower fork (point mass)", 7.25, 1.365, 0.324, 0.0, 0.0, 0.0, 0.0)
REAR_WHEEL = Body("rear wheel", 14.7, 0.0, 0.297, 0.383, 0.638, 0.383, 0.0)
FRONT_WHEEL = Body("front wheel", 11.9, 1.410, 0.282, 0.27, 0.484, 0.27, 0.0)
BODIES = (MAIN_FRAME, UPPER_BODY, SWING_ARM, UPPER_FORK, LOWER_FORK, REAR_WHEEL, FRONT_WHEEL)

STEERING_HEAD = (1.173, 0.749)  # p2: x, z up [m]
CASTER = 0.4189  # rad, the steering axis from the vertical (24.0 deg)
GRAVITY = 9.81  # m/s^2, as in the paper
CROWN_REAR = 0.09  # m, crown radius of the 180/55 ZR17 set
CROWN_FRONT = 0.06  # m, crown radius of the 120/70 ZR17 set


class Composite(NamedTuple):
    """A composite body in Meijaard's axes (z down): mass, mass centre, inertia tensor."""

    m: float
    x: float
    z: float
    I_xx: float
    I_yy: float
    I_zz: float
    I_xz: float


def combine(*bodies: Body) -> Composite:
    """Lock ``bodies`` together: their composite mass, mass centre and central inertias."""
    m = sum(b.m for b in bodies)
    x = sum(b.m * b.x for b in bodies) / m
    z = sum(b.m * -b.z_up for b in bodies) / m
    I_xx = I_yy = I_zz = I_xz = 0.0
    for b in bodies:
        dx, dz = b.x - x, -b.z_up - z
        I_xx += b.I_xx + b.m * dz * dz
        I_yy += b.I_yy + b.m * (dx * dx + dz * dz)
        I_zz += b.I_zz + b.m * dx * dx
        I_xz += -b.xz_integral - b.m * dx * dz
    return Composite(m, x, z, I_xx, I_yy, I_zz, I_xz)


def trail() -> float:
    """Where the steering axis meets the ground, ahead of the front contact [m]."""
    x_head, z_head = STEERING_HEAD
    return x_head + z_head * math.tan(CASTER) - FRONT_WHEEL.x


Entry = tuple[float, str, str, str]  # value, unit, source, note


def meijaard_parameters() -> dict[str, Entry]:
    """Meijaard et al.'s (2007) Table 1 fields, plus the crown radii, for the GSX-R1000."""
    B = combine(MAIN_FRAME, UPPER_BODY, SWING_ARM)
    H = combine(UPPER_FORK, LOWER_FORK)
    table = f"{SEL} {VIA}"
    derived = f"computed by scripts/sel2004_bodies.py from {table}"
    rear, front = REAR_WHEEL, FRONT_WHEEL
    p: dict[str, Entry] = {
        "w": (front.x - rear.x, "m", f"{table}: front axle p6 x", "wheelbase"),
        "c": (trail(), "m", derived, "trail: the steering axis through p2 at the caster angle"),
        "lam": (CASTER, "rad", f"{table}: caster", "steering axis from the vertical"),
        "g": (GRAVITY, "m/s^2", f"{table}", "gravity"),
        "r_R": (
            rear.z_up - CROWN_REAR,
            "m",
            derived,
            "axle height p7 less the crown radius t_R (axle height = r_R + t_R)",
        ),
        "m_R": (rear.m, "kg", table, "rear wheel"),
        "I_Rxx": (rear.I_xx, "kg*m^2", table, "rear wheel, diametral"),
        "I_Ryy": (rear.I_yy, "kg*m^2", table, "rear wheel, spin"),
    }
    for key, body, what in (
        ("B", B, "rear frame: main frame, upper body, swing arm"),
        ("H", H, "front frame: upper and lower fork"),
    ):
        p[f"x_{key}"] = (body.x, "m", derived, f"{what}: mass centre")
        p[f"z_{key}"] = (body.z, "m", derived, f"{what}: mass centre (z down)")
        p[f"m_{key}"] = (body.m, "kg", derived, what)
        for axis in ("xx", "yy", "zz", "xz"):
            value = getattr(body, f"I_{axis}")
            p[f"I_{key}{axis}"] = (value, "kg*m^2", derived, f"{what}: about its mass centre")
    p.update(
        {
            "r_F": (
                front.z_up - CROWN_FRONT,
                "m",
                derived,
                "axle height p6 less the crown radius t_F (axle height = r_F + t_F)",
            ),
            "m_F": (front.m, "kg", table, "front wheel"),
            "I_Fxx": (front.I_xx, "kg*m^2", table, "front wheel, diametral"),
            "I_Fyy": (front.I_yy, "kg*m^2", table, "front wheel, spin"),
            "t_R": (
                CROWN_REAR,
                "m",
                "Cossalter & Lot 2002 via Evangelou 2004, sec. 9.3.5",
                "crown radius of the rear tyre (sel2004_rear_180_55_zr17)",
            ),
            "t_F": (
                CROWN_FRONT,
                "m",
                "Cossalter & Lot 2002 via Evangelou 2004, sec. 9.3.5",
                "crown radius of the front tyre (sel2004_front_120_70_zr17)",
            ),
        }
    )
    return p


ORDER = (
    "w",
    "c",
    "lam",
    "g",
    "r_R",
    "m_R",
    "I_Rxx",
    "I_Ryy",
    "x_B",
    "z_B",
    "m_B",
    "I_Bxx",
    "I_Byy",
    "I_Bzz",
    "I_Bxz",
    "x_H",
    "z_H",
    "m_H",
    "I_Hxx",
    "I_Hyy",
    "I_Hzz",
    "I_Hxz",
    "r_F",
    "m_F",
    "I_Fxx",
    "I_Fyy",
    "t_R",
    "t_F",
)


def _quoted(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def render_toml() -> str:
    """The parameter set as TOML, in the packaged sets' format."""
    p = meijaard_parameters()
    lines = [
        "# Generated by scripts/sel2004_bodies.py: edit the script, not this file.",
        "[set]",
        'name = "sel2004_motorcycle"',
        'model = "multibody"',
        'title = "Suzuki GSX-R1000 with rider, four rigid bodies (Sharp, Evangelou & '
        'Limebeer 2004)"',
        f"source = {_quoted(SEL + ', ' + VIA + '; reduced by scripts/sel2004_bodies.py')}",
        'front_tyre = "sel2004_front_120_70_zr17"',
        'rear_tyre = "sel2004_rear_180_55_zr17"',
    ]
    for name in ORDER:
        value, unit, source, note = p[name]
        lines += [
            "",
            f"[parameters.{name}]",
            f"value = {round(value, 9)!r}",
            f"unit = {_quoted(unit)}",
            f"source = {_quoted(source)}",
            f"note = {_quoted(note)}",
        ]
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    """Print the TOML, or write it to the path given."""
    text = render_toml()
    if argv:
        Path(argv[0]).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
