"""``motosim trim``: the steady turn of the multibody motorcycle on tyres, and the handling figure.

``--speed V --radius R`` trims one turn (the mass centre's speed and path radius, a right
turn); ``--handling`` sweeps the lateral acceleration at several speeds as far as the tyres
carry, the figure motorcycle engineers read (steer torque and roll against lateral
acceleration).
"""

import argparse
import math
from typing import TYPE_CHECKING, Any

from motosim.cli._common import (
    check_figure_path,
    parse_float_list,
    print_json,
    save_figure,
    warn_atypical,
)
from motosim.errors import MotosimError, RunFailedError
from motosim.params import load_parameter_set

if TYPE_CHECKING:
    from motosim.model.trim import Trim

__all__ = ["register"]

_SPEED = (3.0, 60.0)
"""The admitted speeds [m/s]: from a walking machine to a fast road machine."""
_RADIUS = (2.0, 10_000.0)
"""The admitted radii [m]: a tight hairpin to a motorway bend."""
_DEFAULT_SPEEDS = "10,20,30"
_MAX_SPEEDS = 10
_ANGLES = ("phi", "delta", "alpha_f", "alpha_r", "camber_f", "camber_r")
_KEYS: tuple[tuple[str, str], ...] = (
    ("phi", "deg"),
    ("delta", "deg"),
    ("tau_r", "N*m"),
    ("drive_torque", "N*m"),
    ("F_xf", "N"),
    ("F_xr", "N"),
    ("F_yf", "N"),
    ("F_yr", "N"),
    ("F_zf", "N"),
    ("F_zr", "N"),
    ("kappa_f", "1"),
    ("kappa_r", "1"),
    ("alpha_f", "deg"),
    ("alpha_r", "deg"),
    ("camber_f", "deg"),
    ("camber_r", "deg"),
)


def register(sub: Any) -> None:
    """Add ``trim`` to the subcommands."""
    parser = sub.add_parser(
        "trim",
        help="the steady turn of the multibody motorcycle, the handling figure",
        description=(
            "The steady turn of the multibody motorcycle on tyres at a speed and radius "
            "(the mass centre's; a right turn), or with --handling the steer torque and roll "
            "against lateral acceleration at several speeds."
        ),
    )
    parser.add_argument(
        "--params",
        default="sel2004_motorcycle",
        help="sharp set or multibody set with tyres (default sel2004_motorcycle)",
    )
    parser.add_argument(
        "--speed", type=float, help=f"speed [m/s], {_SPEED[0]:g} to {_SPEED[1]:g} (no default)"
    )
    parser.add_argument(
        "--radius",
        type=float,
        help=f"turn radius [m], {_RADIUS[0]:g} to {_RADIUS[1]:g} (no default)",
    )
    parser.add_argument(
        "--handling",
        action="store_true",
        help="sweep the lateral acceleration 0.05 to 0.9 g at --speeds instead of one turn",
    )
    parser.add_argument(
        "--speeds",
        help=f"with --handling: comma-separated speeds [m/s] (default {_DEFAULT_SPEEDS})",
    )
    parser.add_argument("--json", action="store_true", help="print JSON (SI units) instead")
    parser.add_argument(
        "--plot",
        metavar="FILE",
        help="with --handling: save the figure (.png, .svg or .pdf; default: none)",
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --plot file if it exists"
    )
    parser.set_defaults(func=run)


def _check_speed(option: str, value: float) -> None:
    if not (math.isfinite(value) and _SPEED[0] <= value <= _SPEED[1]):
        raise MotosimError(
            f"{option} {value:g}; expected a speed from {_SPEED[0]:g} to {_SPEED[1]:g} m/s"
        )


def _check(args: argparse.Namespace) -> list[float]:
    """Check the options before anything heavy is imported; the speeds to sweep."""
    if args.handling:
        for option, value in (("--speed", args.speed), ("--radius", args.radius)):
            if value is not None:
                raise MotosimError(f"{option} with --handling; expected --speeds (a sweep)")
        speeds = parse_float_list("--speeds", args.speeds or _DEFAULT_SPEEDS, max_items=_MAX_SPEEDS)
        for speed in speeds:
            _check_speed("--speeds", speed)
        warn_atypical("trim", "--speeds", speeds)
        return speeds
    if args.speeds is not None or args.plot is not None:
        option = "--speeds" if args.speeds is not None else "--plot"
        raise MotosimError(f"{option} without --handling; expected --speed and --radius")
    if args.speed is None or args.radius is None:
        missing = "--speed" if args.speed is None else "--radius"
        raise MotosimError(f"{missing} is missing; expected --speed V --radius R (or --handling)")
    _check_speed("--speed", args.speed)
    warn_atypical("trim", "--speed", args.speed)
    if not (math.isfinite(args.radius) and _RADIUS[0] <= args.radius <= _RADIUS[1]):
        raise MotosimError(
            f"--radius {args.radius:g}; expected a radius from {_RADIUS[0]:g} to {_RADIUS[1]:g} m"
        )
    return [args.speed]


def _si(turn: "Trim") -> dict[str, float]:
    out = {"speed": turn.speed, "radius": turn.radius, "lateral_g": turn.lateral_g}
    return out | {key: float(getattr(turn, key)) for key, _ in _KEYS}


def _print(turn: "Trim") -> None:
    print(
        f"steady turn at {turn.speed:g} m/s on {turn.radius:g} m "
        f"({turn.lateral_g:.3f} g, kinematic roll {math.degrees(turn.phi_kinematic):.2f} deg)"
    )
    for key, unit in _KEYS:
        value = float(getattr(turn, key))
        if key in _ANGLES:
            value = math.degrees(value)
        print(f"  {key:<13} {value:12.4f} {unit}")


def run(args: argparse.Namespace) -> int:
    """Trim one turn, or sweep the handling curves."""
    speeds = _check(args)
    if args.plot is not None:
        check_figure_path(args.plot, overwrite=args.overwrite)
    pset = load_parameter_set(args.params)
    if pset.model not in ("sharp", "multibody"):
        raise MotosimError(
            f"--params {args.params}: is a {pset.model} parameter set; expected a sharp set "
            "or a multibody set with tyres"
        )
    from motosim.model import trim, tyred

    model = tyred.load_model(args.params)
    if not args.handling:
        try:
            turn = trim.steady_turn(model, args.speed, args.radius)
        except trim.NoSteadyTurnError as err:
            raise RunFailedError(str(err)) from None
        if args.json:
            print_json({"params": args.params} | _si(turn))
        else:
            _print(turn)
        return 0
    curves = {speed: trim.handling_curve(model, speed) for speed in speeds}
    if args.json:
        print_json(
            {
                "params": args.params,
                "curves": {f"{s:g}": [_si(t) for t in turns] for s, turns in curves.items()},
            }
        )
    else:
        print(f"{'speed':>7} {'a_y':>6} {'tau_r':>9} {'phi':>7} {'delta':>7}")
        print(f"{'[m/s]':>7} {'[g]':>6} {'[N m]':>9} {'[deg]':>7} {'[deg]':>7}")
        for speed, turns in curves.items():
            for t in turns:
                print(
                    f"{speed:7.1f} {t.lateral_g:6.3f} {t.tau_r:9.3f} "
                    f"{math.degrees(t.phi):7.2f} {math.degrees(t.delta):7.3f}"
                )
    if args.plot is not None:
        from motosim.plotting import plot_handling

        path = save_figure(plot_handling(curves, title=args.params), args.plot)
        if not args.json:
            print(f"\nfigure written to {path}")
    return 0
