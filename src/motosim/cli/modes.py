"""``motosim modes``: capsize, weave and wobble of the motorcycle against speed.

``--model sharp1971`` is Sharp's linear model, ``--model multibody`` the same machine
through the multibody model on its linear relaxing tyres; the default follows the
parameter set's kind.
"""

import argparse
from typing import TYPE_CHECKING, Any

from motosim.cli._common import (
    check_figure_path,
    parse_float_list,
    parse_range,
    print_json,
    save_figure,
    warn_atypical,
)
from motosim.errors import MotosimError
from motosim.params import load_parameter_set
from motosim.params.sharp import SharpParameters

if TYPE_CHECKING:
    import numpy as np

    from motosim.model.sharp import ModeTable

__all__ = ["register"]

_DEFAULT_RANGE = "2:60:2"
_MAX_SPEEDS = 2_000
"""Most speeds in one table: a step of 0.075 m/s over the whole admitted range, in 1 s."""


def register(sub: Any) -> None:
    """Add ``modes`` to the subcommands."""
    parser = sub.add_parser(
        "modes",
        help="eigenvalues and modes of the motorcycle against speed",
        description="Capsize, weave and wobble of Sharp's (1971) machine at each speed: its "
        "linear model, or the machine through the multibody model on tyres (--model multibody).",
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--speeds", help="comma-separated speeds [m/s], e.g. 3,5,10 (default: --range)"
    )
    where.add_argument(
        "--range", dest="speed_range", help=f"start:stop:step [m/s] (default {_DEFAULT_RANGE})"
    )
    parser.add_argument(
        "--params", default="sharp1971", help="Sharp parameter set name or TOML file"
    )
    parser.add_argument(
        "--model",
        choices=("sharp1971", "multibody"),
        help="Sharp's linear model or the multibody model on tyres, for a sharp parameter set "
        "(default: sharp1971)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument(
        "--plot", metavar="FILE", help="save a figure (.png, .svg or .pdf; default: none)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace the --plot file if it exists"
    )
    parser.set_defaults(func=run)


def _pairs(values: "np.ndarray") -> list[list[float]]:
    return [[float(z.real), float(z.imag)] for z in values]


def _payload(table: "ModeTable", params: str) -> dict[str, Any]:
    from motosim.model.sharp import MODE_NAMES, ModeTable

    payload: dict[str, Any] = {
        "params": params,
        "speeds": [float(s) for s in table.speeds],
        "eigenvalues": [_pairs(row) for row in table.eigenvalues],
        "modes": {},
    }
    for name in MODE_NAMES:
        values = table.mode(name)
        payload["modes"][name] = {
            "eigenvalue": _pairs(values),
            "frequency_hz": [float(f) for f in ModeTable.frequency_hz(values)],
            "damping_ratio": [float(z) for z in ModeTable.damping_ratio(values)],
            "stable": [bool(z.real < 0) for z in values],
        }
    return payload


def _print_table(table: "ModeTable") -> None:
    import numpy as np

    from motosim.model.sharp import MODE_NAMES, ModeTable

    print(
        f"{'speed':>7}  {'capsize':>9}  {'weave':^27}  {'wobble':^27}\n"
        f"{'[m/s]':>7}  {'Re [1/s]':>9}  {'Re [1/s]':>9} {'f [Hz]':>7} {'zeta':>8}  "
        f"{'Re [1/s]':>9} {'f [Hz]':>7} {'zeta':>8}"
    )
    for k, speed in enumerate(table.speeds):
        cells = [f"{speed:7.2f}", f"{table.capsize[k].real:9.3f}"]
        for name in ("weave", "wobble"):
            z = table.mode(name)[k]
            f = ModeTable.frequency_hz(np.array([z]))[0]
            zeta = ModeTable.damping_ratio(np.array([z]))[0]
            cells.append(f"{z.real:9.3f} {f:7.3f} {zeta:8.3f}")
        unstable = [n for n in MODE_NAMES if table.mode(n)[k].real > 0]
        note = "  unstable: " + ", ".join(unstable) if unstable else ""
        print("  ".join(cells) + note)


def run(args: argparse.Namespace) -> int:
    """Compute, print and optionally plot the modes."""
    speeds = (
        parse_float_list("--speeds", args.speeds, max_items=_MAX_SPEEDS)
        if args.speeds is not None
        else parse_range(
            "--range",
            _DEFAULT_RANGE if args.speed_range is None else args.speed_range,
            max_points=_MAX_SPEEDS,
        )
    )
    if args.plot is not None:
        check_figure_path(args.plot, overwrite=args.overwrite)
    pset = load_parameter_set(args.params)
    model = args.model or "sharp1971"
    if not isinstance(pset.values, SharpParameters):
        raise MotosimError(
            f"--params {args.params}: is a {pset.model} parameter set; expected a sharp "
            "parameter set (the modes of a multibody set need its tyres' linearisation)"
        )
    if model == "multibody":
        from motosim.model.tyred import sharp_modes

        table = sharp_modes(pset.values, speeds)
    else:
        from motosim.model.sharp import modes

        table = modes(pset.values, speeds)
    if args.speeds is not None or args.speed_range is not None:  # the default spans 2-60 m/s
        warn_atypical("modes", "--speeds" if args.speeds is not None else "--range", speeds)
    if args.json:
        print_json(_payload(table, args.params))
    else:
        _print_table(table)
    if args.plot is not None:
        from motosim.plotting import plot_modes

        path = save_figure(plot_modes(table), args.plot)
        if not args.json:
            print(f"\nfigure written to {path}")
    return 0
