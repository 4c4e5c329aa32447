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


def _function(name: str, doc: str, args: str, outputs: list[tuple[str, sm.Matrix]]) -> str:
    """Python source of one function computing ``outputs`` with common subexpressions."""
    printer = NumPyPrinter({"fully_qualified_modules": False, "inline": True})
    flat = [e for _, m in outputs for e in m]
    temps, reduced = sm.cse(flat, symbols=sm.numbered_symbols("x"), optimizations=None)
    typed = ", ".join(f"{a.strip()}: Array" for a in args.split(","))
    result = "Array" if len(outputs) == 1 else f"tuple[{', '.join(['Array'] * len(outputs))}]"
    lines = [f"def {name}({typed}) -> {result}:", f'    """{doc}"""']
    used = set().union(*(e.free_symbols for e in flat)) if flat else set()
    unpack = [(f"p[{i}]", s) for i, s in enumerate(PARAMETERS) if sm.Symbol(s) in used]
    unpack += [(f"q[{i - 1}]", f"q{i}") for i in range(1, 10) if sm.Symbol(f"q{i}") in used]
    unpack += [(f"u[{i - 1}]", f"u{i}") for i in range(1, 10) if sm.Symbol(f"u{i}") in used]
    unpack += [(f"r[{i}]", s) for i, s in enumerate(INPUTS) if sm.Symbol(s) in used]
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


def main() -> int:
    """Write (or with ``--check`` compare) the generated module."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--check", action="store_true", help="compare, write nothing")
    args = parser.parse_args()
    if os.environ.get("PYTHONHASHSEED") != "0":  # SymPy's term order depends on hashing
        env = dict(os.environ, PYTHONHASHSEED="0")
        return subprocess.call([sys.executable, *sys.argv], env=env)
    text = derive_whipple()
    text = _format(text)
    if args.check:
        same = TARGET.exists() and TARGET.read_text(encoding="utf-8") == text
        print(f"{TARGET.name}: {'up to date' if same else 'differs from the derivation'}")
        return 0 if same else 1
    TARGET.write_text(text, encoding="utf-8")
    print(f"wrote {TARGET.relative_to(ROOT)} ({len(text.splitlines())} lines)")
    return 0


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
