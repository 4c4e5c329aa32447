"""Campaign files: a base scenario, the factors to vary, how to sample them, what to keep.

A campaign is TOML with a ``[campaign]`` table and a ``[factors]`` table::

    [campaign]
    name = "robustness"                  # names the results
    description = ""
    scenario = "base.toml"               # the base scenario, relative to the campaign file
    sampling = "lhs"                     # "grid" | "lhs" (Latin hypercube) | "random"
    runs = 1000                          # lhs, random: the number of runs; grid: a multiple
                                         # of the number of grid points (default: one each)
    seed = 0                             # the sample and every run's noise seed derive from it
    metrics = ["rms_tau_r_error"]        # default: all of METRICS
    limits = { rms_tracking_error = 0.087 }   # a run beyond a limit is a failure
    task_seconds = 1.0                   # computing time per batch of runs [s]
    series = ["theta_h", "delta"]        # optional: signals kept per run (DIR/series.zarr)
    every = 10                           # keep every 10th recorded instant of them

    [factors]
    "handlebar.inertia_factor" = { distribution = "uniform", low = 0.5, high = 1.5 }
    "true_handlebar.beta_s" = { distribution = "normal", mean = 0.85, std = 0.2, low = 0.0 }
    "rates.measurement" = { values = [100.0, 1000.0] }
    "measurement.encoder_bits" = [10, 12, 14]          # a list is short for { values = [...] }

A factor is a dotted scenario key (``handlebar.inertia_factor``, ``measurement.encoder_bits``,
``rates.measurement``, ``rider.profile.high``, ``duration``) or a parameter of the true
handlebar (``true_handlebar.J_eq``, ``beta_eq``, ``beta_s``, ``N``, ``k_t``, ...). It takes
either listed ``values`` (any scenario type: numbers, integers, booleans, strings) or, for a
number, a ``distribution``: ``uniform`` (low, high), ``loguniform`` (low, high > 0) or
``normal`` (mean, std, optionally truncated to [low, high]). A grid takes each factor's values,
or ``levels`` points spread over [low, high] (geometrically for ``loguniform``).

``series`` names recorded signals (:data:`motosim.signals.RECORDED`) that each run keeps as
time series in a Zarr store (:mod:`motosim.campaign.series`), with their time ``t``,
decimated to every ``every``-th recorded instant.
"""

import dataclasses
import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from motosim.errors import MotosimError
from motosim.params.handlebar import HandlebarParameters
from motosim.params.toml import read_toml
from motosim.signals import RECORDED

__all__ = [
    "METRICS",
    "TRUE_HANDLEBAR",
    "Campaign",
    "Factor",
    "FactorValue",
    "load_campaign",
    "parse_campaign",
]

FactorValue = float | int | bool | str
"""A value a factor takes in one run."""

TRUE_HANDLEBAR = "true_handlebar"
"""Prefix of the factors that set a parameter of the simulated (true) handlebar."""

METRICS: dict[str, str] = {
    "duration": "simulated time [s]",
    "samples": "recorded instants",
    "complete": "1 when the run reached its end",
    "rms_tau_r_error": "RMS of tau_r_hat - tau_r [N*m]",
    "rms_tracking_error": "RMS of theta_h - delta [rad]",
    "rms_rate_error": "RMS of theta_h_dot_hat - theta_h_dot [rad/s]",
    "max_abs_phi": "largest |phi|, roll [rad]",
    "max_abs_e_y": "largest |e_y|, lateral path error [m]",
    "max_abs_tau_r_error": "largest |tau_r_hat - tau_r| [N*m]",
    "max_abs_tracking_error": "largest |theta_h - delta| [rad]",
    "max_abs_i_m": "largest |i_m|, motor current command [A]",
}
"""The metrics a campaign can keep, with their meaning and unit."""

_HANDLEBAR_FIELDS = tuple(f.name for f in dataclasses.fields(HandlebarParameters))


_MAX_RUNS = 10_000_000
"""Most runs of one campaign (a grid's points included)."""


@dataclass(frozen=True, slots=True)
class Factor:
    """One varied value: listed ``values`` or a ``distribution`` over numbers.

    Attributes
    ----------
    path : str
        Dotted scenario key, or ``true_handlebar.NAME``.
    values : tuple
        The levels (empty when a distribution is given).
    distribution : {"uniform", "loguniform", "normal"} or None
        How a number is drawn.
    low, high : float
        Range of ``uniform`` and ``loguniform``; optional truncation of ``normal``.
    mean, std : float
        Mean and standard deviation of ``normal``.
    levels : int
        Points over [low, high] in a grid (0: the factor cannot be gridded).
    """

    path: str
    values: tuple[FactorValue, ...] = ()
    distribution: Literal["uniform", "loguniform", "normal"] | None = None
    low: float = -math.inf
    high: float = math.inf
    mean: float = math.nan
    std: float = math.nan
    levels: int = 0

    def __post_init__(self) -> None:
        if self.path.startswith(f"{TRUE_HANDLEBAR}."):
            name = self.path.split(".", 1)[1]
            if name not in _HANDLEBAR_FIELDS:
                raise MotosimError(
                    _unknown(self.path, [f"{TRUE_HANDLEBAR}.{n}" for n in _HANDLEBAR_FIELDS])
                )
        if bool(self.values) == (self.distribution is not None):
            raise MotosimError(
                f"{self.path}: expected either values = [...] or a distribution "
                "(uniform, loguniform, normal)"
            )
        if self.levels < 0:
            raise MotosimError(f"{self.path}: levels = {self.levels}; expected an integer >= 0")
        if self.distribution in ("uniform", "loguniform"):
            if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
                raise MotosimError(
                    f"{self.path}: low = {self.low!r}, high = {self.high!r}; expected finite "
                    "numbers with low < high"
                )
            if self.high - self.low < 1e-9 * max(abs(self.low), abs(self.high), 1.0):
                raise MotosimError(
                    f"{self.path}: low = {self.low!r}, high = {self.high!r}; expected a range "
                    "wider than 1e-9 of the values (a narrower one is a constant: set it in the "
                    "base scenario)"
                )
            if self.distribution == "loguniform" and self.low <= 0.0:
                raise MotosimError(f"{self.path}: low = {self.low!r}; expected > 0 (loguniform)")
        if self.distribution == "normal":
            if not (math.isfinite(self.mean) and math.isfinite(self.std) and self.std > 0.0):
                raise MotosimError(
                    f"{self.path}: mean = {self.mean!r}, std = {self.std!r}; expected a finite "
                    "mean and std > 0"
                )
            if (
                not self.low < self.high
                or self.high < self.mean - 6 * self.std
                or (self.low > self.mean + 6 * self.std)
            ):
                raise MotosimError(
                    f"{self.path}: low = {self.low!r}, high = {self.high!r}; expected low < high "
                    "and a range within 6 std of the mean"
                )
            if self.levels:
                raise MotosimError(f"{self.path}: levels is for uniform or loguniform")

    def bounds(self) -> tuple[FactorValue, ...]:
        """The extreme values the factor can take (checked once against the scenario)."""
        if self.values:
            return self.values
        ends = [v for v in (self.low, self.high) if math.isfinite(v)]
        return tuple(ends) if ends else (self.mean,)


@dataclass(frozen=True, slots=True)
class Campaign:
    """A campaign: base scenario, factors, sampling, metrics, seed (see the module docstring).

    Attributes
    ----------
    name : str
        Names the results.
    scenario : str
        Base scenario file, relative to ``folder``.
    folder : str
        Folder of the campaign file (paths in it are relative to it).
    factors : tuple of Factor
        What varies, in column order.
    sampling : {"grid", "lhs", "random"}
        Full factorial grid, Latin hypercube, or independent random draws.
    runs : int
        Number of runs (0: one per grid point).
    seed : int
        Root of the sample and of every run's seed.
    metrics : tuple of str
        Kept metrics, names of :data:`METRICS`.
    task_seconds : float
        Target computing time of one batch of runs [s].
    description : str
        Free text.
    limits : tuple of (str, float)
        Largest acceptable value of some kept metrics (SI units): a run beyond one is a
        failure (its metrics are kept, its reason names the limit).
    series : tuple of str
        Recorded signals each run keeps as time series (none by default).
    every : int
        Keep every ``every``-th recorded instant of the series (1: all of them).
    source : str
        The campaign file, as given (not part of the campaign's identity).
    """

    name: str
    scenario: str
    folder: str
    factors: tuple[Factor, ...]
    sampling: Literal["grid", "lhs", "random"] = "lhs"
    runs: int = 0
    seed: int = 0
    metrics: tuple[str, ...] = tuple(METRICS)
    task_seconds: float = 1.0
    description: str = ""
    limits: tuple[tuple[str, float], ...] = ()
    series: tuple[str, ...] = ()
    every: int = 1
    source: str = ""

    def __post_init__(self) -> None:
        if not self.factors:
            raise MotosimError("[factors]: expected at least one factor")
        paths = [f.path for f in self.factors]
        if len(set(paths)) != len(paths):
            raise MotosimError(f"[factors]: {paths}; expected each key once")
        if self.sampling not in ("grid", "lhs", "random"):
            raise MotosimError(f"sampling = {self.sampling!r}; expected 'grid', 'lhs' or 'random'")
        if not 0 <= self.runs <= _MAX_RUNS:
            raise MotosimError(f"runs = {self.runs}; expected 1 to {_MAX_RUNS}")
        if self.sampling != "grid" and self.runs == 0:
            raise MotosimError(f"runs: missing; expected the number of runs of a {self.sampling}")
        if self.sampling == "grid":
            for f in self.factors:
                if not f.values and not f.levels:
                    raise MotosimError(
                        f"{f.path}: a grid needs values = [...] or levels with low and high"
                    )
            points = self.grid_points()
            if points > _MAX_RUNS:
                levels = " x ".join(str(len(f.values) or f.levels) for f in self.factors)
                raise MotosimError(
                    f"the grid has {levels} = {points:.3g} points; expected at most {_MAX_RUNS} "
                    "runs (fewer levels, or sampling = 'lhs')"
                )
            if self.runs % points:
                raise MotosimError(
                    f"runs = {self.runs}; expected a multiple of the {points} grid points"
                )
        if not 0 <= self.seed < 2**63:
            raise MotosimError(f"seed = {self.seed}; expected an integer >= 0")
        for name in self.metrics:
            if name not in METRICS:
                raise MotosimError(_unknown(name, list(METRICS), what="metric"))
        if not self.metrics:
            raise MotosimError("metrics = []; expected at least one metric")
        for name, limit in self.limits:
            if name not in self.metrics:
                kept = ", ".join(self.metrics)
                raise MotosimError(f"limits: {name!r} is not a kept metric; expected one of {kept}")
            if not math.isfinite(limit):
                raise MotosimError(f"limits: {name} = {limit!r}; expected a finite number")
            if name.startswith(("rms_", "max_abs_", "peak_")) and not limit >= 1e-9:
                raise MotosimError(
                    f"limits: {name} = {limit!r}; expected a limit >= 1e-9 (the metric is a "
                    "magnitude: below that no run could pass)"
                )
        if not (math.isfinite(self.task_seconds) and 0.01 <= self.task_seconds <= 3600.0):
            raise MotosimError(f"task_seconds = {self.task_seconds!r}; expected 0.01 to 3600 [s]")
        signals = [n for n in RECORDED if n != "t"]
        for name in self.series:
            if name not in signals:
                raise MotosimError("series: " + _unknown(name, signals, what="signal"))
        if len(set(self.series)) != len(self.series):
            raise MotosimError(f"series = {list(self.series)}; expected each signal once")
        if not 1 <= self.every <= 1_000_000:
            raise MotosimError(f"every = {self.every}; expected an integer from 1 to 1000000")
        if self.every != 1 and not self.series:
            raise MotosimError(f"every = {self.every}: expected series = [...] with it")

    def grid_points(self) -> int:
        """Number of points of the full factorial grid."""
        return math.prod(len(f.values) or f.levels for f in self.factors)

    def total_runs(self) -> int:
        """Number of runs: ``runs``, or one per grid point."""
        return self.runs or self.grid_points()

    def scenario_path(self) -> Path:
        """The base scenario file."""
        return Path(self.folder) / self.scenario


def _unknown(key: str, known: list[str], what: str = "key") -> str:
    close = difflib.get_close_matches(key, known, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return f"unknown {what} {key!r}{hint}; expected one of {', '.join(known)}"


def _number(value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MotosimError(f"{key} = {value!r}; expected a finite number")
    if not math.isfinite(value):
        raise MotosimError(f"{key} = {value!r}; expected a finite number")
    return float(value)


def _integer(value: Any, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise MotosimError(f"{key} = {value!r}; expected an integer")
    return value


def _factor(path: str, raw: Any) -> Factor:
    """A factor from its TOML value: a list of values or a table."""
    if isinstance(raw, list):
        raw = {"values": raw}
    if not isinstance(raw, Mapping):
        raise MotosimError(f"{path} = {raw!r}; expected a list of values or a table")
    known = ["values", "distribution", "low", "high", "mean", "std", "levels"]
    for key in raw:
        if key not in known:
            raise MotosimError(f"{path}: {_unknown(key, known)}")
    kwargs: dict[str, Any] = {}
    if "values" in raw:
        values = raw["values"]
        if not isinstance(values, list) or not values:
            raise MotosimError(f"{path}: values = {values!r}; expected a non-empty list")
        kinds = {type(v) for v in values}
        if not kinds <= {int, float, bool, str} or (len(kinds) > 1 and kinds != {int, float}):
            raise MotosimError(
                f"{path}: values = {values!r}; expected numbers, booleans or strings, one kind"
            )
        if len(set(values)) != len(values):
            raise MotosimError(f"{path}: values = {values!r}; expected distinct values")
        kwargs["values"] = tuple(values)
    if "distribution" in raw:
        dist = raw["distribution"]
        if dist not in ("uniform", "loguniform", "normal"):
            raise MotosimError(
                f"{path}: distribution = {dist!r}; expected 'uniform', 'loguniform' or 'normal'"
            )
        kwargs["distribution"] = dist
    for key in ("low", "high", "mean", "std"):
        if key in raw:
            kwargs[key] = _number(raw[key], f"{path}: {key}")
    if "levels" in raw:
        kwargs["levels"] = _integer(raw["levels"], f"{path}: levels")
    return Factor(path, **kwargs)


def parse_campaign(data: Mapping[str, Any], *, origin: str, folder: str | Path) -> Campaign:
    """Validate a parsed campaign document into a :class:`Campaign`.

    Parameters
    ----------
    data : Mapping
        The TOML document.
    origin : str
        Its file name, the prefix of error messages.
    folder : str or Path
        The folder relative paths are taken from.

    Returns
    -------
    Campaign

    Raises
    ------
    MotosimError
        One line naming the key, the value and what was expected.

    Examples
    --------
    >>> doc = {"campaign": {"scenario": "s.toml", "runs": 10},
    ...        "factors": {"handlebar.inertia_factor": {"distribution": "uniform",
    ...                                                  "low": 0.5, "high": 1.5}}}
    >>> parse_campaign(doc, origin="c.toml", folder=".").factors[0].high
    1.5
    """
    for key in data:
        if key not in ("campaign", "factors"):
            raise MotosimError(f"{origin}: {_unknown(key, ['campaign', 'factors'], 'table')}")
    head, factors = data.get("campaign"), data.get("factors")
    if not isinstance(head, Mapping):
        raise MotosimError(f"{origin}: missing table [campaign]")
    if not isinstance(factors, Mapping):
        raise MotosimError(f"{origin}: missing table [factors]")
    known = [
        "name",
        "description",
        "scenario",
        "sampling",
        "runs",
        "seed",
        "metrics",
        "task_seconds",
        "limits",
        "series",
        "every",
    ]
    where = f"{origin} [campaign]"
    try:
        for key in head:
            if key not in known:
                raise MotosimError(_unknown(key, known))
        if "scenario" not in head:
            raise MotosimError("missing scenario (the base scenario file)")
        kwargs: dict[str, Any] = {"name": Path(origin).stem}
        for key in ("name", "description", "scenario", "sampling"):
            if key in head:
                if not isinstance(head[key], str):
                    raise MotosimError(f"{key} = {head[key]!r}; expected a string")
                kwargs[key] = head[key]
        for key in ("runs", "seed", "every"):
            if key in head:
                kwargs[key] = _integer(head[key], key)
        sampling = kwargs.get("sampling", "lhs")
        if kwargs.get("runs") == 0 and sampling != "grid":
            raise MotosimError(
                f"runs = 0; expected 1 to {_MAX_RUNS}, the number of runs of the {sampling} "
                "sampling"
            )
        if "task_seconds" in head:
            kwargs["task_seconds"] = _number(head["task_seconds"], "task_seconds")
        if "metrics" in head:
            names = head["metrics"]
            if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
                raise MotosimError(f"metrics = {names!r}; expected a list of metric names")
            kwargs["metrics"] = tuple(names)
        if "series" in head:
            names = head["series"]
            if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
                raise MotosimError(f"series = {names!r}; expected a list of signal names")
            kwargs["series"] = tuple(names)
        if "limits" in head:
            limits = head["limits"]
            if not isinstance(limits, Mapping):
                raise MotosimError(f"limits = {limits!r}; expected a table of metric = limit")
            kwargs["limits"] = tuple(
                (str(k), _number(v, f"limits: {k}")) for k, v in limits.items()
            )
    except MotosimError as err:
        raise MotosimError(f"{where}: {err}") from None
    try:
        parsed = tuple(_factor(str(path), raw) for path, raw in factors.items())
    except MotosimError as err:
        raise MotosimError(f"{origin} [factors] {err}") from None
    try:
        return Campaign(folder=str(folder), factors=parsed, **kwargs)
    except MotosimError as err:
        raise MotosimError(f"{origin}: {err}") from None


def load_campaign(path: str | Path) -> Campaign:
    """Read and validate a campaign file (a one-line :class:`MotosimError` otherwise)."""
    source = Path(path)
    data = read_toml(source, what="campaign file")
    campaign = parse_campaign(data, origin=str(path), folder=source.parent)
    return dataclasses.replace(campaign, source=str(path))
