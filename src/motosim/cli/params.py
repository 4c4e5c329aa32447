"""``motosim params``: list and show the packaged parameter sets and parameter files."""

import argparse
from dataclasses import fields
from typing import Any

from motosim.cli._common import print_json
from motosim.params import (
    HandlebarParameters,
    derived_geometry,
    list_parameter_sets,
    load_parameter_set,
)
from motosim.params.multibody import MultibodyParameters
from motosim.params.sharp import SharpParameters

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add ``params list`` and ``params show`` to the subcommands."""
    parser = sub.add_parser("params", help="list and show parameter sets")
    actions = parser.add_subparsers(dest="action", required=True, parser_class=type(parser))
    lister = actions.add_parser("list", help="list the packaged parameter sets")
    lister.add_argument("--json", action="store_true", help="print JSON")
    lister.set_defaults(func=_list)
    show = actions.add_parser("show", help="show one parameter set with units and sources")
    show.add_argument("name", help="a packaged set name or a parameter TOML file")
    show.add_argument("--json", action="store_true", help="print a flat JSON object of SI values")
    show.set_defaults(func=_show)


def _list(args: argparse.Namespace) -> int:
    sets = [load_parameter_set(name) for name in list_parameter_sets()]
    if args.json:
        print_json([{"name": s.name, "model": s.model, "title": s.title} for s in sets])
        return 0
    width = max(len(s.name) for s in sets)
    for s in sets:
        print(f"{s.name:<{width}}  {s.model:<9}  {s.title}")
    return 0


_DERIVED_UNITS = {
    "j": "m",
    "k": "m",
    "l": "m",
    "wheelbase": "m",
    "m": "kg",
    "J_R": "kg*m^2",
    "r_D": "m",
    "m_eq": "kg",
    "mass": "kg",
    "x_G": "m",
    "z_G": "m",
    "J_h": "kg*m^2",
    "beta_vh": "N*m*s/rad",
    "N*k_t": "N*m/A",
}
"""The unit of each derived value ``params show`` prints (:func:`derived_geometry`'s, the
multibody set's mass and mass centre, the handlebar's own inertia, damping and N k_t)."""


def _show(args: argparse.Namespace) -> int:
    pset = load_parameter_set(args.name)
    values = {f.name: float(getattr(pset.values, f.name)) for f in fields(pset.values)}
    if args.json:
        print_json(values)
        return 0
    specs = type(pset.values).SPECS
    print(f"{pset.name} ({pset.model}): {pset.title}")
    if pset.source:
        print(f"source: {pset.source}")
    print()
    width = max(len(n) for n in values)
    for name, value in values.items():
        line = f"  {name:<{width}}  {value:>14.6g}  {specs[name].unit:<10}"
        source = pset.sources.get(name, "")
        print(f"{line}  {source}" if source else line)
    derived: dict[str, float] = {}
    if isinstance(pset.values, SharpParameters):
        derived = derived_geometry(pset.values)
    elif isinstance(pset.values, MultibodyParameters):
        x_G, z_G = pset.values.mass_centre
        derived = {"mass": pset.values.mass, "x_G": x_G, "z_G": z_G}
    elif isinstance(pset.values, HandlebarParameters):
        derived = {
            "J_h": pset.values.J_h,
            "beta_vh": pset.values.beta_vh,
            "N*k_t": pset.values.torque_per_amp,
        }
    if not derived:
        return 0
    print("\nderived:")
    for name, value in derived.items():
        print(f"  {name:<{width}}  {value:>14.6g}  {_DERIVED_UNITS[name]}")
    return 0
