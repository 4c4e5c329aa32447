"""Validated physical parameters and the packaged reference sets.

A parameter set is a TOML file with a ``[set]`` table (name, model, title, source) and a
``[parameters]`` table. Each parameter is either a bare number in SI units or a table with
``value``, ``unit`` (checked against the expected unit), ``source`` and ``note``::

    [set]
    name = "my_handlebar"
    model = "handlebar"

    [parameters.J_eq]
    value = 0.0415
    unit = "kg*m^2"
    source = "identified with motosim identify, run 2026-11-02"

Unknown keys, missing values, NaN and values out of range are :class:`MotosimError` with a
one-line message naming the value and the expected range.
"""

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any, Literal, TypeAlias, overload

from motosim.errors import MotosimError, warn
from motosim.params._spec import Spec, atypical_fields
from motosim.params.checks import (
    check_keys,
    check_number,
    check_table,
    check_text,
    short_repr,
    suggestion,
)
from motosim.params.handlebar import HandlebarParameters
from motosim.params.multibody import MultibodyParameters
from motosim.params.sharp import SharpParameters, derived_geometry
from motosim.params.toml import parse_toml, read_toml
from motosim.params.tyre import TyreParameters

__all__ = [
    "HandlebarParameters",
    "MultibodyParameters",
    "ParameterSet",
    "SharpParameters",
    "TyreParameters",
    "check_number",
    "derived_geometry",
    "dump_parameter_set",
    "list_parameter_sets",
    "load_parameter_set",
    "load_parameters",
    "parse_parameter_set",
    "read_toml",
]

Parameters: TypeAlias = SharpParameters | HandlebarParameters | TyreParameters | MultibodyParameters
ModelKind: TypeAlias = Literal["sharp", "handlebar", "tyre", "multibody"]

_MODELS: dict[
    str,
    type[SharpParameters]
    | type[HandlebarParameters]
    | type[TyreParameters]
    | type[MultibodyParameters],
] = {
    "sharp": SharpParameters,
    "handlebar": HandlebarParameters,
    "tyre": TyreParameters,
    "multibody": MultibodyParameters,
}
_SET_KEYS = ("name", "model", "title", "source")
_TYRE_KEYS = ("front_tyre", "rear_tyre")
"""Optional ``[set]`` keys of a multibody set: the names of its tyres' parameter sets."""
_ENTRY_KEYS = ("value", "unit", "source", "note")


@dataclass(frozen=True, slots=True)
class ParameterSet:
    """A named parameter set with the provenance of each value.

    Attributes
    ----------
    name : str
        Short name, e.g. ``"sharp1971"``.
    model : {"sharp", "handlebar", "tyre", "multibody"}
        Which model the values belong to.
    title : str
        One-line description.
    source : str
        Where the set as a whole comes from.
    values : SharpParameters, HandlebarParameters, TyreParameters or MultibodyParameters
        The validated values, SI units.
    sources : Mapping[str, str]
        Per-parameter source (paper, table, equation) or, for assumed values, the reason.
    tyres : Mapping[str, str]
        For a multibody set, the ``[set]`` keys ``front_tyre`` and ``rear_tyre`` that are
        given: the names of the tyres' parameter sets. Empty otherwise.
    """

    name: str
    model: ModelKind
    title: str
    source: str
    values: Parameters
    sources: Mapping[str, str]
    tyres: Mapping[str, str] = field(default_factory=dict)


def _packaged_dir() -> Any:
    return resources.files("motosim.params") / "data"


def list_parameter_sets() -> list[str]:
    """Names of the packaged reference parameter sets, sorted."""
    return sorted(
        p.name.removesuffix(".toml") for p in _packaged_dir().iterdir() if p.name.endswith(".toml")
    )


def _as_number(origin: str, name: str, raw: Any, spec: Spec) -> float:
    return check_number(
        raw,
        where=f"{origin}: parameter {name}",
        lower=spec.lower,
        upper=spec.upper,
        lower_closed=spec.lower_closed,
        upper_closed=spec.upper_closed,
        unit=spec.unit,
    )


def parse_parameter_set(data: Mapping[str, Any], *, origin: str) -> ParameterSet:
    """Validate the contents of a parameter file into a :class:`ParameterSet`.

    Parameters
    ----------
    data : Mapping
        The parsed TOML document.
    origin : str
        Where it came from, used as the prefix of error messages.

    Returns
    -------
    ParameterSet
        The validated set.

    Raises
    ------
    MotosimError
        On an unknown or missing key, a unit that is not the expected one, a value that is not
        a finite number in its range.
    """
    check_keys(data, ("set", "parameters"), where=origin, what="table")
    if "set" not in data:
        raise MotosimError(f"{origin}: missing table [set] with name and model")
    head = check_table(data["set"], where=f"{origin}: set")
    model_given = head.get("model")
    set_keys = _SET_KEYS + (_TYRE_KEYS if model_given == "multibody" else ())
    check_keys(head, set_keys, where=f"{origin}: [set]", what="key")
    if "model" not in head:
        raise MotosimError(f"{origin}: [set] has no model; expected one of {', '.join(_MODELS)}")
    model = check_text(head["model"], where=f"{origin}: [set] model")
    if model not in _MODELS:
        raise MotosimError(
            f"{origin}: [set] model = {short_repr(model)}{suggestion(model, _MODELS)} "
            f"(expected one of {', '.join(_MODELS)})"
        )
    texts = {
        key: check_text(head.get(key, ""), where=f"{origin}: [set] {key}", one_line=key == "name")
        for key in ("name", "title", "source")
    }
    tyres = {
        key: check_text(head[key], where=f"{origin}: [set] {key}")
        for key in _TYRE_KEYS
        if key in head
    }
    cls = _MODELS[model]
    specs = cls.SPECS
    if "parameters" not in data:
        raise MotosimError(f"{origin}: missing table [parameters]")
    table = check_table(data["parameters"], where=f"{origin}: parameters")
    check_keys(table, specs, where=f"{origin}: [parameters]", what=f"{model} parameter")
    values: dict[str, float] = {}
    sources: dict[str, str] = {}
    for name, entry in table.items():
        if isinstance(entry, Mapping):
            check_keys(entry, _ENTRY_KEYS, where=f"{origin}: parameter {name}", what="key")
            if "value" not in entry:
                raise MotosimError(f"{origin}: parameter {name} has no value")
            unit = check_text(entry.get("unit", specs[name].unit), where=f"{origin}: {name}.unit")
            if unit != specs[name].unit:
                raise MotosimError(
                    f"{origin}: parameter {name} has unit {short_repr(unit)}; "
                    f"expected {specs[name].unit!r}"
                )
            values[name] = _as_number(origin, name, entry["value"], specs[name])
            for key in ("source", "note"):
                check_text(entry.get(key, ""), where=f"{origin}: {name}.{key}", one_line=False)
            sources[name] = entry.get("source", "")
        else:
            values[name] = _as_number(origin, name, entry, specs[name])
            sources[name] = ""
    missing = [n for n in specs if n not in values]
    if missing:
        raise MotosimError(
            f"{origin}: missing parameter {missing[0]} ({specs[missing[0]].description}, "
            f"{specs[missing[0]].expected()})"
        )
    try:
        params = cls(**values)
    except MotosimError as err:
        raise MotosimError(f"{origin}: {err}") from None
    return ParameterSet(
        name=texts["name"] or Path(origin).stem,
        model=model,  # type: ignore[arg-type]  # checked against _MODELS above
        title=texts["title"],
        source=texts["source"],
        values=params,
        sources=sources,
        tyres=tyres,
    )


def load_parameter_set(name_or_path: str | Path) -> ParameterSet:
    """Load a packaged set by name, or a parameter file by path.

    Parameters
    ----------
    name_or_path : str or Path
        A name from :func:`list_parameter_sets` or the path of a TOML file.

    Returns
    -------
    ParameterSet
        The validated set.

    Raises
    ------
    MotosimError
        If there is no such set or file, the file is not valid TOML, or a value is invalid.
    """
    origin = str(name_or_path)
    if isinstance(name_or_path, str) and name_or_path in list_parameter_sets():
        text = (_packaged_dir() / f"{name_or_path}.toml").read_text(encoding="utf-8")
        data = parse_toml(text, origin=origin)
    else:
        path = Path(name_or_path)
        if not os.path.lexists(path):  # a link loop or a broken link: read_toml names it
            sets = list_parameter_sets()
            raise MotosimError(
                f"{origin}: no such parameter file or packaged set{suggestion(origin, sets)} "
                f"(packaged sets are {', '.join(sets)})"
            )
        data = read_toml(path, what="parameter file")
    pset = parse_parameter_set(data, origin=origin)
    for line in atypical_fields(pset.values, context=origin):
        warn(line)
    return pset


@overload
def load_parameters(name_or_path: str | Path, model: Literal["sharp"]) -> SharpParameters: ...
@overload
def load_parameters(
    name_or_path: str | Path, model: Literal["handlebar"]
) -> HandlebarParameters: ...
@overload
def load_parameters(name_or_path: str | Path, model: Literal["tyre"]) -> TyreParameters: ...
@overload
def load_parameters(
    name_or_path: str | Path, model: Literal["multibody"]
) -> MultibodyParameters: ...
@overload
def load_parameters(name_or_path: str | Path, model: None = None) -> Parameters: ...
def load_parameters(name_or_path: str | Path, model: ModelKind | None = None) -> Parameters:
    """Load only the validated values of a parameter set.

    Parameters
    ----------
    name_or_path : str or Path
        A packaged set name or a file path.
    model : {"sharp", "handlebar", "tyre", "multibody"}, optional
        When given, the set must be of this model.

    Returns
    -------
    SharpParameters, HandlebarParameters, TyreParameters or MultibodyParameters

    Raises
    ------
    MotosimError
        If the set is invalid or of the wrong model.

    Examples
    --------
    >>> load_parameters("simacom_handlebar", "handlebar").J_eq
    0.0415
    """
    pset = load_parameter_set(name_or_path)
    if model is not None and pset.model != model:
        raise MotosimError(
            f"{name_or_path}: is a {pset.model} parameter set; expected a {model} parameter set"
        )
    return pset.values


def _toml_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
    return f'"{escaped}"'


def dump_parameter_set(pset: ParameterSet) -> str:
    """Render a parameter set as TOML text that :func:`load_parameter_set` reads back.

    Parameters
    ----------
    pset : ParameterSet
        The set to write.

    Returns
    -------
    str
        TOML text, each value with its unit and source.
    """
    lines = [
        "[set]",
        f"name = {_toml_string(pset.name)}",
        f"model = {_toml_string(pset.model)}",
        f"title = {_toml_string(pset.title)}",
        f"source = {_toml_string(pset.source)}",
    ]
    lines += [f"{key} = {_toml_string(value)}" for key, value in pset.tyres.items()]
    specs = type(pset.values).SPECS
    for f in fields(pset.values):
        value = float(getattr(pset.values, f.name))
        assert math.isfinite(value)
        lines += [
            "",
            f"[parameters.{f.name}]",
            f"value = {value!r}",
            f"unit = {_toml_string(specs[f.name].unit)}",
            f"source = {_toml_string(pset.sources.get(f.name, ''))}",
        ]
    return "\n".join(lines) + "\n"
