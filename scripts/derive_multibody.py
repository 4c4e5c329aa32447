"""Derive the multibody motorcycle's equations (Kane's method) and generate their numeric code.

    .venv/bin/python scripts/derive_multibody.py [--check]

Writes ``src/motosim/model/_generated_whipple.py``: plain numeric Python (NumPy functions
only, no SymPy), compiled with numba by :mod:`motosim.model.whipple`. ``--check`` writes
nothing and exits 1 when the committed file differs from what the derivation gives.

The machine is the Whipple-Carvallo bicycle of Meijaard et al. (2007) in the coordinates of
Moore (2012, "Human control of a bicycle", PhD dissertation, UC Davis, ch. "Bicycle
equations of motion"): q1, q2 the rear contact point in the ground plane, q3 yaw, q4 roll, q5
the rear frame's pitch, q6 the rear wheel's angle, q7 steer, q8 the front wheel's angle, all
as successive body-fixed rotations (yaw about the ground's downward z, roll about the yaw
frame's x, pitch about the roll frame's y), with the generalised speeds u_i = q_i'. The
wheels are tori (crown radius t, t = 0 the knife edge).

The equations are generated in the form Kane's method gives for the unconstrained system
(every u_i independent, the wheels free to slide on the ground): the mass matrix M(q) and the
forcing f(q, u, r) with ``M u' = f`` (gravity, the gyroscopic and centripetal terms, and
the input torques r), together with the rolling constraints ``B(q) u = 0`` (the two wheels'
material points at their contacts have no velocity, horizontal at the rear, in all three
directions at the front) and their derivative's velocity part ``d/dt(B) u``. With a basis C
of the null space of B (u = C u_ind), Kane's equations of the constrained system are
``C^T (M u' - f) = 0`` and ``B u' + d/dt(B) u = 0``: :mod:`motosim.model.whipple` solves
these numerically, which is Kane's method with the nonholonomic partial velocities formed
from numbers instead of symbols.
"""

import argparse
import os
import subprocess
import sys
from pathlib import Path

import sympy as sm
import sympy.physics.mechanics as me
from sympy.printing.numpy import NumPyPrinter

ROOT = Path(__file__).resolve().parents[1]
TARGET = ROOT / "src" / "motosim" / "model" / "_generated_whipple.py"
TARGET_TYRED = ROOT / "src" / "motosim" / "model" / "_generated_tyred.py"

PARAMETERS = (
    "rR rF tR tF d1 d2 d3 l1 l2 l3 l4 g mC mD mE mF "
    "IC11 IC22 IC33 IC31 ID11 ID22 IE11 IE22 IE33 IE31 IF11 IF22"
).split()
"""The generated code's parameter vector, in this order (see ``motosim.model.whipple``)."""

INPUTS = ("T4", "T6", "T7", "T8")
"""The input torques [N*m]: roll (on the rear frame about the yaw frame's x, reacted by the
ground), rear wheel (on the wheel, reacted by the rear frame), steer (on the front frame,
reacted by the rear frame), front wheel (on the wheel, reacted by the front frame)."""


def _bodies() -> dict[str, object]:
    """The four bodies, their frames and points in Moore's coordinates (a dictionary)."""
    q = me.dynamicsymbols("q1:9")
    u = me.dynamicsymbols("u1:9")
    p = dict(zip(PARAMETERS, sm.symbols(PARAMETERS), strict=True))
    T4, T6, T7, T8 = sm.symbols(INPUTS)

    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (q[2], N.z))  # yaw
    B = A.orientnew("B", "Axis", (q[3], A.x))  # roll
    C = B.orientnew("C", "Axis", (q[4], B.y))  # rear frame (pitch)
    D = C.orientnew("D", "Axis", (q[5], C.y))  # rear wheel
    E = C.orientnew("E", "Axis", (q[6], C.z))  # front frame (steer)
    F = E.orientnew("F", "Axis", (q[7], E.y))  # front wheel
    A.set_ang_vel(N, u[2] * N.z)
    B.set_ang_vel(A, u[3] * A.x)
    C.set_ang_vel(B, u[4] * B.y)
    D.set_ang_vel(C, u[5] * C.y)
    E.set_ang_vel(C, u[6] * C.z)
    F.set_ang_vel(E, u[7] * E.y)

    origin = me.Point("O")
    origin.set_vel(N, 0)
    dn = origin.locatenew("dn", q[0] * N.x + q[1] * N.y)  # rear contact
    # rear wheel centre: up the ground normal by the crown radius, then up the wheel plane
    do = dn.locatenew("do", -p["tR"] * A.z - (p["rR"] - p["tR"]) * B.z)
    ce = do.locatenew("ce", p["d1"] * C.x)  # on the steering axis
    fo = ce.locatenew("fo", p["d2"] * C.z + p["d3"] * E.x)  # front wheel centre
    co = do.locatenew("co", p["l1"] * C.x + p["l2"] * C.z)  # rear frame mass centre
    eo = fo.locatenew("eo", p["l3"] * E.x + p["l4"] * E.z)  # front frame mass centre
    # front contact: the lowest point of the torus, down the wheel plane then the normal
    down_in_plane = A.z - A.z.dot(E.y) * E.y
    down_in_plane = down_in_plane / sm.sqrt(1 - A.z.dot(E.y) ** 2)
    fn = fo.locatenew("fn", (p["rF"] - p["tF"]) * down_in_plane + p["tF"] * A.z)

    qd_to_u = {qi.diff(): ui for qi, ui in zip(q, u, strict=True)}
    for point in (do, fo, co, eo):
        point.set_vel(N, point.pos_from(origin).dt(N).xreplace(qd_to_u))

    # the wheels' material points at the contacts
    v_rear = do.vel(N) + D.ang_vel_in(N).cross(dn.pos_from(do))
    v_front = fo.vel(N) + F.ang_vel_in(N).cross(fn.pos_from(fo))

    bodies = [
        me.RigidBody(
            "rear_frame",
            co,
            C,
            p["mC"],
            (me.inertia(C, p["IC11"], p["IC22"], p["IC33"], 0, 0, p["IC31"]), co),
        ),
        me.RigidBody(
            "rear_wheel", do, D, p["mD"], (me.inertia(C, p["ID11"], p["ID22"], p["ID11"]), do)
        ),
        me.RigidBody(
            "front_frame",
            eo,
            E,
            p["mE"],
            (me.inertia(E, p["IE11"], p["IE22"], p["IE33"], 0, 0, p["IE31"]), eo),
        ),
        me.RigidBody(
            "front_wheel", fo, F, p["mF"], (me.inertia(E, p["IF11"], p["IF22"], p["IF11"]), fo)
        ),
    ]
    loads = [(body.masscenter, body.mass * p["g"] * A.z) for body in bodies]
    loads += [
        (D, T6 * C.y),
        (C, T4 * A.x - T6 * C.y - T7 * C.z),
        (E, T7 * C.z - T8 * E.y),
        (F, T8 * E.y),
    ]
    return {
        "q": q,
        "u": u,
        "p": p,
        "N": N,
        "A": A,
        "dn": dn,
        "fn": fn,
        "v_rear": v_rear,
        "v_front": v_front,
        "bodies": bodies,
        "loads": loads,
        "qd_to_u": qd_to_u,
        "O": origin,
    }


def _to_symbols(exprs: list[sm.Expr], q: list[sm.Function], u: list[sm.Function]) -> list:
    names = {qi: sm.Symbol(f"q{i + 1}") for i, qi in enumerate(q)}
    names.update({ui: sm.Symbol(f"u{i + 1}") for i, ui in enumerate(u)})
    return [me.msubs(e, names) for e in exprs]


def _function(
    name: str,
    doc: str,
    args: str,
    outputs: list[tuple[str, sm.Matrix]],
    parameters: tuple[str, ...] | list[str] = tuple(PARAMETERS),
    inputs: tuple[str, ...] = INPUTS,
) -> str:
    """Python source of one function computing ``outputs`` with common subexpressions."""
    printer = NumPyPrinter({"fully_qualified_modules": False, "inline": True})
    flat = [e for _, m in outputs for e in m]
    temps, reduced = sm.cse(flat, symbols=sm.numbered_symbols("x"), optimizations=None)
    typed = ", ".join(f"{a.strip()}: Array" for a in args.split(","))
    result = "Array" if len(outputs) == 1 else f"tuple[{', '.join(['Array'] * len(outputs))}]"
    lines = [f"def {name}({typed}) -> {result}:", f'    """{doc}"""']
    used = set().union(*(e.free_symbols for e in flat)) if flat else set()
    unpack = [(f"p[{i}]", s) for i, s in enumerate(parameters) if sm.Symbol(s) in used]
    unpack += [(f"q[{i - 1}]", f"q{i}") for i in range(1, 10) if sm.Symbol(f"q{i}") in used]
    unpack += [(f"u[{i - 1}]", f"u{i}") for i in range(1, 10) if sm.Symbol(f"u{i}") in used]
    unpack += [(f"r[{i}]", s) for i, s in enumerate(inputs) if sm.Symbol(s) in used]
    lines += [f"    {symbol} = {source}" for source, symbol in unpack]
    lines += [f"    {t} = {printer.doprint(e)}" for t, e in temps]
    k = 0
    for out_name, matrix in outputs:
        rows, cols = matrix.shape
        shape = f"({rows}, {cols})" if cols > 1 else f"{rows}"
        lines.append(f"    {out_name} = np.zeros({shape}, dtype=q.dtype)")
        for i in range(rows):
            for j in range(cols):
                e = reduced[k]
                k += 1
                if e != 0:
                    index = f"{i}, {j}" if cols > 1 else f"{i}"
                    lines.append(f"    {out_name}[{index}] = {printer.doprint(e)}")
    lines.append(f"    return {', '.join(n for n, _ in outputs)}")
    return "\n".join(lines) + "\n"


def derive_whipple() -> str:
    """The generated module's text for the rigid-contact (Whipple-Carvallo) model."""
    s = _bodies()
    q, u, A = s["q"], s["u"], s["A"]
    kinematics = [qi.diff() - ui for qi, ui in zip(q, u, strict=True)]
    kane = me.KanesMethod(s["N"], q_ind=q, u_ind=u, kd_eqs=kinematics)
    kane.kanes_equations(s["bodies"], s["loads"])
    mass = kane.mass_matrix
    forcing = kane.forcing.xreplace(s["qd_to_u"])

    holonomic = sm.Matrix([s["fn"].pos_from(s["dn"]).dot(A.z)])
    constraints = sm.Matrix(
        [
            s["v_rear"].dot(A.x),
            s["v_rear"].dot(A.y),
            s["v_front"].dot(A.x),
            s["v_front"].dot(A.y),
            s["v_front"].dot(A.z),
        ]
    )
    B = constraints.jacobian(u)
    Bdot_u = (B * sm.Matrix(u)).jacobian(q) * sm.Matrix(u)

    energy = sm.Matrix(
        [
            sum(body.kinetic_energy(s["N"]) for body in s["bodies"])
            - sum(
                body.mass * s["p"]["g"] * body.masscenter.pos_from(s["O"]).dot(A.z)
                for body in s["bodies"]
            )
        ]
    )

    def sym(m: sm.Matrix) -> sm.Matrix:
        return sm.Matrix(m.shape[0], m.shape[1], _to_symbols(list(m), q, u))

    header = (
        '"""Generated by scripts/derive_multibody.py (Kane\'s method, SymPy): do not edit.\n\n'
        "The Whipple-Carvallo bicycle in Moore's (2012) coordinates q1..q8, speeds u_i = q_i'.\n"
        "``p`` is the parameter vector of ``PARAMETERS``, ``r`` the input torques of ``INPUTS``.\n"
        '"""\n\n'
        "from typing import Any, TypeAlias\n\n"
        "import numpy as np\nimport numpy.typing as npt\nfrom numpy import cos, sin, sqrt\n\n"
        '__all__ = [\n    "INPUTS",\n    "PARAMETERS",\n    "constraint_bias",\n'
        '    "constraint_matrix",\n    "energy",\n    "holonomic",\n    "mass_forcing",\n]\n\n'
        "Array: TypeAlias = npt.NDArray[Any]\n\n"
        f"PARAMETERS = {tuple(PARAMETERS)!r}\n"
        f"INPUTS = {INPUTS!r}\n"
    )
    parts = [
        header,
        _function(
            "holonomic",
            "Height of the front contact above the ground (0 on the ground) and its q5 slope.",
            "p, q",
            [("h", sym(holonomic)), ("dh_dq5", sym(holonomic.jacobian([q[4]])))],
        ),
        _function(
            "constraint_matrix",
            "Rolling constraints B(q) with B u = 0 (rear x, y; front x, y, z, yaw axes).",
            "p, q",
            [("B", sym(B))],
        ),
        _function(
            "constraint_bias",
            "The velocity part of the constraints' derivative, d/dt(B) u.",
            "p, q, u",
            [("b", sym(Bdot_u))],
        ),
        _function(
            "mass_forcing",
            "Mass matrix M(q) and forcing f(q, u, r) of the unconstrained system, M u' = f.",
            "p, q, u, r",
            [("M", sym(mass)), ("f", sym(forcing))],
        ),
        _function(
            "energy",
            "Kinetic plus gravitational potential energy [J] (zero potential at the ground).",
            "p, q, u",
            [("e", sym(energy))],
        ),
    ]
    return "\n\n".join(parts)


PARAMETERS_TYRED = (*PARAMETERS, "la1", "la2")
"""The tyred model's parameter vector: the rigid model's and the aerodynamic centre (la1, la2,
in the rear frame's axes from the rear wheel centre, as l1, l2)."""

INPUTS_TYRED = ("Ts", "Tr", "Tf")
"""The tyred model's input torques [N*m]: steer (front frame on rear frame), rear wheel (on
the wheel, reacted by the rear frame), front wheel (on the wheel, reacted by the front frame)."""


def derive_tyred() -> str:
    """The generated module's text for the model with tyres (the rear frame free in space).

    Coordinates: q1, q2, q3 the rear wheel centre in the ground axes (z down), q4 yaw, q5
    roll, q6 the rear frame's pitch, q7 the rear wheel's angle, q8 steer, q9 the front
    wheel's angle. Speeds: u1, u2, u3 the rear wheel centre's velocity in the yaw frame's
    axes (forward, right, down), u4..u9 the angles' rates.
    """
    q = me.dynamicsymbols("q1:10")
    u = me.dynamicsymbols("u1:10")
    p = dict(zip(PARAMETERS_TYRED, sm.symbols(PARAMETERS_TYRED), strict=True))
    Ts, Tr, Tf = sm.symbols(INPUTS_TYRED)

    N = me.ReferenceFrame("N")
    A = N.orientnew("A", "Axis", (q[3], N.z))
    B = A.orientnew("B", "Axis", (q[4], A.x))
    C = B.orientnew("C", "Axis", (q[5], B.y))
    D = C.orientnew("D", "Axis", (q[6], C.y))
    E = C.orientnew("E", "Axis", (q[7], C.z))
    F = E.orientnew("F", "Axis", (q[8], E.y))
    A.set_ang_vel(N, u[3] * N.z)
    B.set_ang_vel(A, u[4] * A.x)
    C.set_ang_vel(B, u[5] * B.y)
    D.set_ang_vel(C, u[6] * C.y)
    E.set_ang_vel(C, u[7] * C.z)
    F.set_ang_vel(E, u[8] * E.y)

    origin = me.Point("O")
    origin.set_vel(N, 0)
    do = origin.locatenew("do", q[0] * N.x + q[1] * N.y + q[2] * N.z)
    do.set_vel(N, u[0] * A.x + u[1] * A.y + u[2] * A.z)
    kinematics = [
        q[0].diff() - (u[0] * sm.cos(q[3]) - u[1] * sm.sin(q[3])),
        q[1].diff() - (u[0] * sm.sin(q[3]) + u[1] * sm.cos(q[3])),
        q[2].diff() - u[2],
        *[qi.diff() - ui for qi, ui in zip(q[3:], u[3:], strict=True)],
    ]
    qd_to_u = sm.solve(kinematics, [qi.diff() for qi in q], dict=True)[0]

    ce = do.locatenew("ce", p["d1"] * C.x)
    fo = ce.locatenew("fo", p["d2"] * C.z + p["d3"] * E.x)
    co = do.locatenew("co", p["l1"] * C.x + p["l2"] * C.z)
    eo = fo.locatenew("eo", p["l3"] * E.x + p["l4"] * E.z)
    ao = do.locatenew("ao", p["la1"] * C.x + p["la2"] * C.z)  # aerodynamic centre
    for point, frame, base in ((ce, C, do), (fo, E, ce), (co, C, do), (eo, E, fo), (ao, C, do)):
        point.v2pt_theory(base, N, frame)

    def contact(centre: me.Point, axle: me.Vector, r: sm.Symbol, t: sm.Symbol) -> me.Point:
        down = A.z - A.z.dot(axle) * axle
        down = down / sm.sqrt(1 - A.z.dot(axle) ** 2)
        return centre.locatenew("P", (r - t) * down + t * A.z)

    rear = contact(do, C.y, p["rR"], p["tR"])
    front = contact(fo, E.y, p["rF"], p["tF"])

    bodies = [
        me.RigidBody(
            "rear_frame",
            co,
            C,
            p["mC"],
            (me.inertia(C, p["IC11"], p["IC22"], p["IC33"], 0, 0, p["IC31"]), co),
        ),
        me.RigidBody(
            "rear_wheel", do, D, p["mD"], (me.inertia(C, p["ID11"], p["ID22"], p["ID11"]), do)
        ),
        me.RigidBody(
            "front_frame",
            eo,
            E,
            p["mE"],
            (me.inertia(E, p["IE11"], p["IE22"], p["IE33"], 0, 0, p["IE31"]), eo),
        ),
        me.RigidBody(
            "front_wheel", fo, F, p["mF"], (me.inertia(E, p["IF11"], p["IF22"], p["IF11"]), fo)
        ),
    ]
    loads = [(body.masscenter, body.mass * p["g"] * A.z) for body in bodies]
    loads += [(D, Tr * C.y), (C, -Tr * C.y - Ts * C.z), (E, Ts * C.z - Tf * E.y), (F, Tf * E.y)]
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kinematics)
    kane.kanes_equations(bodies, loads)
    mass = kane.mass_matrix
    forcing = kane.forcing.xreplace(qd_to_u)

    def rows(point: me.Point, centre: me.Point, wheel: me.ReferenceFrame, axle: me.Vector):
        """The contact's kinematics and the Jacobian of its force and moments."""
        heading = axle.cross(A.z)
        heading = heading / sm.sqrt(1 - A.z.dot(axle) ** 2)
        lateral = A.z.cross(heading)
        v_material = centre.vel(N) + wheel.ang_vel_in(N).cross(point.pos_from(centre))
        height = point.pos_from(origin).dot(N.z)
        kinematic = sm.Matrix(
            [
                point.pos_from(origin).dot(N.x),
                point.pos_from(origin).dot(N.y),
                height,
                height.diff(me.dynamicsymbols._t).xreplace(qd_to_u),
                v_material.dot(heading),
                v_material.dot(lateral),
                centre.vel(N).dot(heading),
                axle.dot(A.z),
            ]
        )
        omega = wheel.ang_vel_in(N)
        jacobian = sm.Matrix(
            [
                [v_material.dot(heading).diff(ui) for ui in u],
                [v_material.dot(lateral).diff(ui) for ui in u],
                [v_material.dot(A.z).diff(ui) for ui in u],
                [omega.dot(heading).diff(ui) for ui in u],
                [omega.dot(A.z).diff(ui) for ui in u],
            ]
        )
        return kinematic, jacobian

    kin_r, jac_r = rows(rear, do, D, C.y)
    kin_f, jac_f = rows(front, fo, F, E.y)
    aero = sm.Matrix([[ao.vel(N).dot(A.x).diff(ui) for ui in u]])
    qdot = sm.Matrix([qd_to_u[qi.diff()] for qi in q])
    energy = sm.Matrix(
        [
            sum(body.kinetic_energy(N) for body in bodies)
            - sum(body.mass * p["g"] * body.masscenter.pos_from(origin).dot(N.z) for body in bodies)
        ]
    )

    def sym(m: sm.Matrix) -> sm.Matrix:
        return sm.Matrix(m.shape[0], m.shape[1], _to_symbols(list(m), q, u))

    header = (
        '"""Generated by scripts/derive_multibody.py (Kane\'s method, SymPy): do not edit.\n\n'
        "The multibody motorcycle with tyres: the rear frame free in space (q1..q6), the wheels'\n"
        "angles q7, q9 and steer q8; u1..u3 the rear wheel centre's velocity in the yaw axes.\n"
        "``p`` is the parameter vector of ``PARAMETERS``, ``r`` the input torques of ``INPUTS``.\n"
        '"""\n\n'
        "from typing import Any, TypeAlias\n\n"
        "import numpy as np\nimport numpy.typing as npt\nfrom numpy import cos, sin, sqrt\n\n"
        '__all__ = [\n    "INPUTS",\n    "PARAMETERS",\n    "aero_jacobian",\n'
        '    "contacts",\n    "energy",\n    "kinematics",\n    "mass_forcing",\n]\n\n'
        "Array: TypeAlias = npt.NDArray[Any]\n\n"
        f"PARAMETERS = {PARAMETERS_TYRED!r}\n"
        f"INPUTS = {INPUTS_TYRED!r}\n"
    )
    common = {"parameters": PARAMETERS_TYRED, "inputs": INPUTS_TYRED}
    parts = [
        header,
        _function(
            "mass_forcing",
            "Mass matrix M(q) and forcing f(q, u, r) without tyre forces: M u' = f + Q_tyres.",
            "p, q, u, r",
            [("M", sym(mass)), ("f", sym(forcing))],
            **common,
        ),
        _function(
            "kinematics",
            "The coordinates' derivatives q' from the speeds.",
            "p, q, u",
            [("qd", sym(qdot))],
            **common,
        ),
        _function(
            "contacts",
            "Per wheel (rear, front): contact x, y, depth below the ground, its rate, the\n"
            "    wheel's material point's velocity along the heading and across it, the wheel\n"
            "    centre's velocity along the heading, sin(camber); and the Jacobians (rows:\n"
            "    force along the heading, across, down; moment about the heading, the normal).",
            "p, q, u",
            [("kr", sym(kin_r)), ("kf", sym(kin_f)), ("Jr", sym(jac_r)), ("Jf", sym(jac_f))],
            **common,
        ),
        _function(
            "aero_jacobian",
            "Partial velocities of the aerodynamic centre along the yaw frame's x axis.",
            "p, q",
            [("Ja", sym(aero))],
            **common,
        ),
        _function(
            "energy",
            "Kinetic plus gravitational potential energy [J] (zero potential at the ground).",
            "p, q, u",
            [("e", sym(energy))],
            **common,
        ),
    ]
    return "\n\n".join(parts)


def main() -> int:
    """Write (or with ``--check`` compare) the generated module."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--check", action="store_true", help="compare, write nothing")
    args = parser.parse_args()
    if os.environ.get("PYTHONHASHSEED") != "0":  # SymPy's term order depends on hashing
        env = dict(os.environ, PYTHONHASHSEED="0")
        return subprocess.call([sys.executable, *sys.argv], env=env)
    status = 0
    for target, derive in ((TARGET, derive_whipple), (TARGET_TYRED, derive_tyred)):
        text = _format(derive())
        if args.check:
            same = target.exists() and target.read_text(encoding="utf-8") == text
            print(f"{target.name}: {'up to date' if same else 'differs from the derivation'}")
            status = status or (0 if same else 1)
        else:
            target.write_text(text, encoding="utf-8")
            print(f"wrote {target.relative_to(ROOT)} ({len(text.splitlines())} lines)")
    return status


def _format(text: str) -> str:
    """The text as ``ruff format`` writes it (so the committed file passes the lint)."""
    ruff = Path(sys.executable).with_name("ruff")
    done = subprocess.run(
        [str(ruff), "format", "--stdin-filename", str(TARGET), "-"],
        input=text,
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout


if __name__ == "__main__":
    sys.exit(main())
