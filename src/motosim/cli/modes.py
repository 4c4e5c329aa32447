"""``motosim modes``: capsize, weave and wobble of the motorcycle against speed.

``--model sharp1971`` is Sharp's linear model of a ``sharp`` set; ``--model multibody`` is
the multibody model on tyres linearised about upright straight running: a ``sharp`` set's
machine on Sharp's linear relaxing tyres, or a ``multibody`` set with its Magic Formula
tyres (e.g. ``sel2004_motorcycle``). The default follows the parameter set's kind.
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
from motosim.params import ParameterSet, load_parameter_set
from motosim.params.multibody import MultibodyParameters
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
        description="Capsize, weave and wobble of a motorcycle at each speed: Sharp's (1971) "
        "linear model of a sharp set, or the multibody model on tyres linearised about upright "
        "straight running (--model multibody; a sharp set's machine on Sharp's tyres, or a "
        "multibody set with its Magic Formula tyres, e.g. sel2004_motorcycle).",
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--speeds", help="comma-separated speeds [m/s], e.g. 3,5,10 (default: --range)"
    )
    where.add_argument(
        "--range", dest="speed_range", help=f"start:stop:step [m/s] (default {_DEFAULT_RANGE})"
    )
    parser.add_argument(
        "--params",
        default="sharp1971",
        help="sharp or multibody (with tyres) parameter set name or TOML file (default: sharp1971)",
    )
    parser.add_argument(
        "--model",
        choices=("sharp1971", "multibody"),
        help="Sharp's linear model (a sharp set only) or the multibody model on tyres "
        "(default: sharp1971 for a sharp set, multibody for a multibody set)",
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


def _check_model(name: str, pset: ParameterSet, model: str | None) -> str:
    """The model to linearise: ``model`` if the set admits it, else the set kind's default.

    Raises
    ------
    MotosimError
        If the set is neither a sharp set nor a multibody set with both tyres, or
        ``sharp1971`` is asked of a multibody set.
    """
    if isinstance(pset.values, SharpParameters):
        return model or "sharp1971"
    if not isinstance(pset.values, MultibodyParameters):
        raise MotosimError(
            f"--params {name}: is a {pset.model} parameter set; expected a sharp parameter set "
            "or a multibody set with tyres (e.g. sel2004_motorcycle)"
        )
    if model == "sharp1971":
        raise MotosimError(
            f"--model sharp1971 with --params {name}: Sharp's linear model takes a sharp "
            "parameter set; expected --model multibody (the default) for a multibody set"
        )
    missing = [key for key in ("front_tyre", "rear_tyre") if key not in pset.tyres]
    if missing:
        raise MotosimError(
            f"--params {name}: is a multibody set without tyres (names no {missing[0]}); "
            "expected a multibody set with tyres (e.g. sel2004_motorcycle), whose "
            "linearisation the modes need"
        )
    return "multibody"


def _title(pset: ParameterSet, model: str) -> str:
    if model == "sharp1971":
        return f"{pset.name}, Sharp's (1971) linear model: modes against speed (shaded: unstable)"
    tyres = "Sharp's tyres" if isinstance(pset.values, SharpParameters) else "its MF tyres"
    return f"{pset.name}, the multibody model on {tyres}: modes against speed (shaded: unstable)"


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
    model = _check_model(args.params, pset, args.model)
    if isinstance(pset.values, SharpParameters) and model == "sharp1971":
        from motosim.model.sharp import modes

        table = modes(pset.values, speeds)
    elif isinstance(pset.values, SharpParameters):
        from motosim.model.tyred import sharp_modes

        table = sharp_modes(pset.values, speeds)
    else:
        from motosim.model.tyred import lateral_modes, load_model

        table = lateral_modes(load_model(args.params), speeds)
    if args.speeds is not None or args.speed_range is not None:  # the default spans 2-60 m/s
        warn_atypical("modes", "--speeds" if args.speeds is not None else "--range", speeds)
    if args.json:
        print_json(_payload(table, args.params))
    else:
        _print_table(table)
    if args.plot is not None:
        from motosim.plotting import plot_modes

        path = save_figure(plot_modes(table, title=_title(pset, model)), args.plot)
        if not args.json:
            print(f"\nfigure written to {path}")
    return 0
