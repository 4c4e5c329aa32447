"""The runs of a campaign: the sample of the factors, each run's seed, id and design.

:func:`plan_campaign` reads the base scenario, checks every factor against it (the key exists,
the type fits, the extreme values make a valid scenario), draws the sample (a full factorial
grid, a Latin hypercube of :mod:`scipy.stats.qmc`, or independent draws), gives each run a seed
from ``numpy.random.SeedSequence(seed).spawn`` and an id (a short hash of the run's values,
seed, base scenario, parameter values and package version), and groups the runs by design:
the runs whose factors leave the nominal handlebar, estimator, controller, rates and motorcycle
unchanged share one designed stack.
"""

import copy
import dataclasses
import difflib
import hashlib
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim import __version__
from motosim.campaign.spec import TRUE_HANDLEBAR, Campaign, Factor, FactorValue
from motosim.errors import MotosimError
from motosim.io.runs import load_scenario, parameter_source
from motosim.params import load_parameter_set, load_parameters
from motosim.params.handlebar import HandlebarParameters
from motosim.sim.scenario import Scenario, scenario_dict, scenario_from_dict

__all__ = [
    "Plan",
    "PlannedRun",
    "is_design_factor",
    "plan_campaign",
    "sample_values",
    "scenario_of",
]

Array = NDArray[np.float64]

_RIG_ONLY = (
    "name",
    "description",
    "duration",
    "seed",
    "measurement.",
    "rider.",
    "handlebar.true",
    "handlebar.inertia_factor",
    "handlebar.damping_factor",
    "motorcycle.drive_torque",
    "motorcycle.brake_torque",
    "motorcycle.wind_force",
    "rates.plant",
    f"{TRUE_HANDLEBAR}.",
)
"""Keys that change only the simulated world around the stack, never its design."""


def is_design_factor(path: str) -> bool:
    """Whether varying the key ``path`` changes the designed stack (then it is redesigned).

    Examples
    --------
    >>> is_design_factor("handlebar.inertia_factor"), is_design_factor("rates.measurement")
    (False, True)
    """
    key = path.removeprefix("scenario.")
    return not any(key == p or (p.endswith(".") and key.startswith(p)) for p in _RIG_ONLY)


@dataclass(frozen=True, slots=True)
class PlannedRun:
    """One run of a campaign.

    Attributes
    ----------
    index : int
        Position in the campaign's sample.
    run_id : str
        Short hash of the run's values, seed, base scenario, parameters and package version.
    seed : int
        The run's noise seed (its scenario's ``seed``), from ``SeedSequence(seed).spawn``.
    values : tuple
        The factors' values, in the campaign's order.
    design : str
        Key of the run's design (runs with the same key share one stack).
    """

    index: int
    run_id: str
    seed: int
    values: tuple[FactorValue, ...]
    design: str


@dataclass(frozen=True, slots=True)
class Plan:
    """A campaign's runs, its base scenario and what it was made from.

    Attributes
    ----------
    campaign : Campaign
        The campaign.
    base : Mapping
        The base scenario as plain data (:func:`motosim.sim.scenario.scenario_dict`).
    folder : str
        Folder of the base scenario (its relative files are taken from there).
    runs : tuple of PlannedRun
        Every run, in sample order.
    designs : Mapping of str to tuple
        For each design key, the values of the factors that change the design.
    true_handlebars : Mapping of str to HandlebarParameters
        The true handlebar parameter sets the runs name, loaded.
    nominal : HandlebarParameters
        The nominal handlebar, loaded.
    fingerprint : str
        Hash of the campaign, base scenario, parameter values and package version.
    """

    campaign: Campaign
    base: Mapping[str, Any]
    folder: str
    runs: tuple[PlannedRun, ...]
    designs: Mapping[str, tuple[FactorValue, ...]]
    true_handlebars: Mapping[str, HandlebarParameters]
    nominal: HandlebarParameters
    fingerprint: str

    def run(self, run_id: str) -> PlannedRun:
        """The planned run ``run_id`` (a MotosimError when the campaign has none)."""
        for planned in self.runs:
            if planned.run_id == run_id:
                return planned
        raise MotosimError(
            f"run id {run_id!r}: not a run of campaign {self.campaign.name!r}; expected one of "
            "the run_id values of its results"
        )


def _hash(payload: Any, length: int = 12) -> str:
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:length]


def _split(path: str) -> list[str]:
    return path.removeprefix("scenario.").split(".")


def _lookup(base: Mapping[str, Any], path: str) -> Any:
    node: Any = base
    for part in _split(path):
        if not isinstance(node, Mapping) or part not in node:
            raise KeyError(path)
        node = node[part]
    return node


def _assign(data: dict[str, Any], path: str, value: FactorValue) -> None:
    parts = _split(path)
    node = data
    for part in parts[:-1]:
        node = node[part]
    node[parts[-1]] = value


def _keys(base: Mapping[str, Any], prefix: str = "") -> list[str]:
    out = []
    for key, value in base.items():
        if isinstance(value, Mapping):
            out += _keys(value, f"{prefix}{key}.")
        else:
            out.append(f"{prefix}{key}")
    return out


def _check_factor(factor: Factor, base: Mapping[str, Any], true: HandlebarParameters) -> None:
    """Refuse a factor whose key is unknown, whose type does not fit, or whose ends are invalid."""
    path = factor.path
    if path.startswith(f"{TRUE_HANDLEBAR}."):
        name = path.split(".", 1)[1]
        for value in factor.bounds():
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise MotosimError(f"{path} = {value!r}; expected a number")
            try:
                dataclasses.replace(true, **{name: float(value)})
            except MotosimError as err:
                raise MotosimError(f"{path} = {value!r}: {err}") from None
        return
    try:
        current = _lookup(base, path)
    except KeyError:
        known = [*_keys(base), f"{TRUE_HANDLEBAR}.<parameter>"]
        close = difflib.get_close_matches(path, known, n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise MotosimError(
            f"{path}: not a key of the base scenario{hint}; expected a dotted scenario key "
            f"such as handlebar.inertia_factor, or {TRUE_HANDLEBAR}.NAME"
        ) from None
    if path.endswith(".file") or path.endswith(".kind") or isinstance(current, list):
        raise MotosimError(f"{path}: cannot be a factor; expected a number, boolean or string key")
    kind = type(current)
    if factor.distribution is not None and kind is not float:
        raise MotosimError(
            f"{path} is {'an integer' if kind is int else 'not a number'}; expected values = "
            "[...] for it, not a distribution"
        )
    for value in factor.bounds():
        ok = isinstance(value, kind) or (kind is float and type(value) is int)
        if not ok:
            raise MotosimError(f"{path} = {value!r}; expected a value like {current!r}")
        data = copy.deepcopy(dict(base))
        _assign(data, path, float(value) if kind is float else value)
        try:
            scenario_from_dict(data, origin=f"{path} = {value!r}")
        except MotosimError as err:
            raise MotosimError(str(err)) from None


def _column(factor: Factor, u: Array) -> list[FactorValue]:
    """Map uniform numbers ``u`` in [0, 1) to the factor's values (inverse CDF)."""
    from scipy.special import ndtr, ndtri

    if factor.values:
        n = len(factor.values)
        return [factor.values[min(int(x * n), n - 1)] for x in u]
    lo, hi = factor.low, factor.high
    if factor.distribution == "uniform":
        x = lo + u * (hi - lo)
    elif factor.distribution == "loguniform":
        x = np.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
    else:
        c_lo = float(ndtr((lo - factor.mean) / factor.std)) if math.isfinite(lo) else 0.0
        c_hi = float(ndtr((hi - factor.mean) / factor.std)) if math.isfinite(hi) else 1.0
        q = np.clip(c_lo + u * (c_hi - c_lo), 1e-300, 1.0 - 1e-16)
        x = np.clip(factor.mean + factor.std * ndtri(q), lo, hi)
    return [float(v) for v in x]


def _levels(factor: Factor) -> list[FactorValue]:
    if factor.values:
        return list(factor.values)
    if factor.distribution == "loguniform":
        return [float(v) for v in np.geomspace(factor.low, factor.high, factor.levels)]
    return [float(v) for v in np.linspace(factor.low, factor.high, factor.levels)]


def sample_values(campaign: Campaign) -> list[tuple[FactorValue, ...]]:
    """The factors' values of every run, in sample order.

    Parameters
    ----------
    campaign : Campaign
        The campaign.

    Returns
    -------
    list of tuple
        ``campaign.total_runs()`` rows. A grid repeats each point ``runs / points`` times in a
        row; a Latin hypercube and random draws use ``numpy.random.default_rng(seed)``.
    """
    n = campaign.total_runs()
    factors = campaign.factors
    if campaign.sampling == "grid":
        points = list(itertools.product(*(_levels(f) for f in factors)))
        repeat = n // len(points)
        return [tuple(p) for p in points for _ in range(repeat)]
    rng = np.random.default_rng(campaign.seed)
    if campaign.sampling == "lhs":
        from scipy.stats import qmc

        u = qmc.LatinHypercube(d=len(factors), rng=rng).random(n)
    else:
        u = rng.random((n, len(factors)))
    columns = [_column(f, u[:, j]) for j, f in enumerate(factors)]
    return [tuple(row) for row in zip(*columns, strict=True)]


def run_scenario(plan: Plan, planned: PlannedRun) -> tuple[Scenario, dict[str, float]]:
    """The scenario of one run and the overrides of its true handlebar's parameters."""
    return scenario_of(plan.base, plan.campaign.factors, planned)


def scenario_of(
    base: Mapping[str, Any], factors: Sequence[Factor], planned: PlannedRun
) -> tuple[Scenario, dict[str, float]]:
    """The scenario of ``planned`` (the base with its values and seed) and its handlebar overrides.

    Raises
    ------
    MotosimError
        If the combination of values is not a valid scenario.
    """
    data = copy.deepcopy(dict(base))
    overrides: dict[str, float] = {}
    for factor, value in zip(factors, planned.values, strict=True):
        if factor.path.startswith(f"{TRUE_HANDLEBAR}."):
            overrides[factor.path.split(".", 1)[1]] = float(value)
        else:
            _assign(data, factor.path, value)
    data["seed"] = planned.seed
    return scenario_from_dict(data, origin=f"run {planned.run_id}"), overrides


def _kind(factor: Factor, base: Mapping[str, Any]) -> type:
    if factor.path.startswith(f"{TRUE_HANDLEBAR}."):
        return float
    return type(_lookup(base, factor.path))


def _motorcycle(source: str | Path) -> dict[str, Any]:
    """The motorcycle's parameter set as plain values, with its tyre sets' (a multibody set
    names them): what a campaign's runs depend on of the motorcycle."""
    pset = load_parameter_set(source)
    tyres = {
        key: dataclasses.asdict(load_parameters(name, "tyre"))
        for key, name in sorted(pset.tyres.items())
    }
    return {"set": dataclasses.asdict(pset.values), "tyres": tyres}


def plan_campaign(campaign: Campaign) -> Plan:
    """Check a campaign against its base scenario and list its runs.

    Parameters
    ----------
    campaign : Campaign
        The campaign.

    Returns
    -------
    Plan

    Raises
    ------
    MotosimError
        If the base scenario is invalid, a factor names no scenario key or handlebar
        parameter, a value has the wrong type, or an extreme value makes an invalid scenario.
    """
    path = campaign.scenario_path()
    scenario = load_scenario(path)
    folder = path.parent
    base = scenario_dict(scenario)
    true_names = {scenario.handlebar.true}
    for factor in campaign.factors:
        if factor.path.removeprefix("scenario.") == "handlebar.true":
            true_names |= {str(v) for v in factor.values}
    true_sets = {
        name: load_parameters(parameter_source(name, folder), "handlebar")
        for name in sorted(true_names)
    }
    nominal = load_parameters(parameter_source(scenario.handlebar.nominal, folder), "handlebar")
    motorcycle = _motorcycle(parameter_source(scenario.motorcycle.params, folder))
    for factor in campaign.factors:
        _check_factor(factor, base, true_sets[scenario.handlebar.true])
    kinds = [_kind(f, base) for f in campaign.factors]
    rows = sample_values(campaign)
    rows = [
        tuple(float(v) if k is float else v for v, k in zip(r, kinds, strict=True)) for r in rows
    ]
    fingerprint = _hash(
        {
            "version": __version__,
            "campaign": dataclasses.asdict(dataclasses.replace(campaign, folder="", source="")),
            "base": base,
            "true": {k: dataclasses.asdict(v) for k, v in true_sets.items()},
            "nominal": dataclasses.asdict(nominal),
            "motorcycle": motorcycle,
        },
        length=16,
    )
    base_key = _hash(
        [
            __version__,
            base,
            {k: dataclasses.asdict(v) for k, v in true_sets.items()},
            dataclasses.asdict(nominal),
            motorcycle,
        ]
    )
    design_cols = [j for j, f in enumerate(campaign.factors) if is_design_factor(f.path)]
    seeds = [
        int(s.generate_state(1, np.uint64)[0] >> np.uint64(1))
        for s in np.random.SeedSequence(campaign.seed).spawn(len(rows))
    ]
    paths = [f.path for f in campaign.factors]
    designs: dict[str, tuple[FactorValue, ...]] = {}
    runs = []
    for index, (values, seed) in enumerate(zip(rows, seeds, strict=True)):
        design_values = tuple(values[j] for j in design_cols)
        design = _hash([base_key, design_values], length=8)
        designs.setdefault(design, design_values)
        run_id = _hash([base_key, paths, list(values), seed])
        runs.append(PlannedRun(index, run_id, seed, values, design))
    return Plan(campaign, base, str(folder), tuple(runs), designs, true_sets, nominal, fingerprint)
