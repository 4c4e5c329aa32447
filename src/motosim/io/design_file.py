"""The design file: the observer and the controller designed for one handlebar.

Written by ``motosim design``; read by the simulator and the real-time loop, which rebuild
the observer from its settings and run the controller's discrete matrices. TOML, SI units::

    [design]      version, date, handlebar (name or file), rate [Hz]
    [handlebar]   the nominal handlebar (every HandlebarParameters field)
    [observer]    Walcott-Zak settings (poles, eta, injection_bandwidth, ...) and L, P, F
    [controller]  bandwidth, order, gamma, gamma_min, num, den, A, B, C, D and, per
                  discretisation (zoh, tustin), its matrices at the rate
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from motosim.control.statespace import StateSpace
from motosim.errors import MotosimError
from motosim.estimation.walcott_zak import ObserverSettings
from motosim.params.checks import check_keys, check_number, check_table, check_text, short_repr
from motosim.params.handlebar import HandlebarParameters
from motosim.params.toml import read_toml

__all__ = [
    "MAX_CONTROLLER_STATES",
    "RATE_RANGE",
    "DesignFile",
    "ObserverSettings",
    "dump_design",
    "read_design",
]


@dataclass(frozen=True, slots=True)
class DesignFile:
    """A design read back: what the simulator and the real-time loop need.

    Attributes
    ----------
    rate : float
        Control and estimation rate [Hz].
    handlebar : HandlebarParameters
        Nominal handlebar.
    observer : ObserverSettings
        Walcott-Zak settings.
    controller : StateSpace
        Continuous controller K [A/rad], positive feedback i_m = K (theta_h - delta).
    controller_discrete : dict of str to StateSpace
        K discretised at ``rate`` by ``zoh`` and ``tustin``.
    """

    rate: float
    handlebar: HandlebarParameters
    observer: ObserverSettings
    controller: StateSpace
    controller_discrete: dict[str, StateSpace]


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, np.ndarray | list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    number = float(value)
    if not math.isfinite(number):
        raise MotosimError(f"cannot write the non-finite value {number!r} to a design file")
    return repr(number)


def _table(name: str, entries: Mapping[str, Any]) -> list[str]:
    return [f"[{name}]", *(f"{key} = {_toml_value(value)}" for key, value in entries.items()), ""]


def _matrices(system: StateSpace) -> dict[str, Any]:
    return {"A": system.A, "B": system.B, "C": system.C, "D": system.D}


def dump_design(
    *,
    header: Mapping[str, Any],
    handlebar: HandlebarParameters,
    observer: ObserverSettings,
    observer_matrices: Mapping[str, Any],
    controller: Mapping[str, Any],
    continuous: StateSpace,
    discrete: Mapping[str, StateSpace],
    paper_controller: Mapping[str, Any],
) -> str:
    """Render a design as TOML text that :func:`read_design` reads back."""
    lines = _table("design", header)
    lines += _table("handlebar", {f.name: getattr(handlebar, f.name) for f in fields(handlebar)})
    settings = {f.name: getattr(observer, f.name) for f in fields(observer)}
    lines += _table("observer", {**settings, **observer_matrices})
    lines += _table("controller", {**controller, **_matrices(continuous)})
    for method, system in discrete.items():
        lines += _table(f"controller.{method}", _matrices(system))
    lines += _table("paper_controller", paper_controller)
    return "\n".join(lines)


MAX_CONTROLLER_STATES = 10
"""Most states of a controller in a design file (``motosim design`` writes at most 4)."""

RATE_RANGE = (10.0, 100_000.0)
"""Control rates admitted [Hz]: a real-time loop runs at 100 Hz to tens of kHz."""

_TABLES = ("design", "handlebar", "observer", "controller", "paper_controller")
_DESIGN_KEYS = ("version", "date", "handlebar", "rate")
_OBSERVER_KEYS = (*(f.name for f in fields(ObserverSettings)), "L", "P", "F")
_MATRIX_KEYS = ("A", "B", "C", "D")
_CONTROLLER_FIGURES = ("bandwidth", "order", "gamma", "gamma_min", "weight_gain", "weight_corner")
_CONTROLLER_KEYS = (*_CONTROLLER_FIGURES, "num", "den", *_MATRIX_KEYS, "zoh", "tustin")


def _get(table: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in table:
        raise MotosimError(f"{where}: missing {key!r}")
    return table[key]


def _matrix(value: Any, where: str) -> NDArray[np.float64]:
    """A 2-D matrix of at most MAX_CONTROLLER_STATES + 1 rows and columns, from nested lists."""
    limit = MAX_CONTROLLER_STATES + 1
    if not isinstance(value, list) or len(value) > limit:
        raise MotosimError(
            f"{where} = {short_repr(value)}; expected a matrix as a list of at most {limit} rows"
        )
    try:
        matrix = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise MotosimError(
            f"{where} = {short_repr(value)}; expected a matrix of numbers, rows of equal length"
        ) from None
    if matrix.ndim != 2 or matrix.shape[1] > limit:
        raise MotosimError(f"{where} has shape {matrix.shape}; expected a 2-D matrix")
    return matrix


def _state_space(table: Any, where: str, dt: float = 0.0) -> StateSpace:
    table = check_table(table, where=where)
    A, B, C, D = (_matrix(_get(table, k, where), f"{where} {k}") for k in _MATRIX_KEYS)
    try:
        system = StateSpace(A, B, C, D, dt=dt)
    except MotosimError as err:
        raise MotosimError(f"{where}: {err}") from None
    if system.B.shape[1] != 1 or system.C.shape[0] != 1:
        raise MotosimError(
            f"{where}: B has shape {system.B.shape} and C {system.C.shape}; expected one input "
            "(theta_h - delta) and one output (i_m)"
        )
    return system


def _loop_matrix(plant: StateSpace, controller: StateSpace) -> NDArray[np.float64]:
    """State matrix of the loop i_m = K (theta_h - delta) (positive feedback, no feedthrough)."""
    Ap, Bp, Cp = plant.A, plant.B, plant.C
    return np.block(
        [[Ap + Bp @ controller.D @ Cp, Bp @ controller.C], [controller.B @ Cp, controller.A]]
    )


def _check_loops(
    handlebar: HandlebarParameters,
    continuous: StateSpace,
    discrete: Mapping[str, StateSpace],
    rate: float,
    where: str,
) -> None:
    """Refuse a controller that does not stabilise the nominal handlebar, continuous or sampled."""
    from scipy.linalg import expm

    from motosim.control.torque_feedback import handlebar_plants

    plant, _ = handlebar_plants(handlebar)
    growth = float(np.max(np.linalg.eigvals(_loop_matrix(plant, continuous)).real))
    if not growth < 0.0:
        raise MotosimError(
            f"{where} [controller]: the loop with the nominal handlebar has a pole with real "
            f"part {growth:.4g} 1/s; expected a stabilising controller (all < 0)"
        )
    n = plant.n_states
    phi = expm(np.block([[plant.A, plant.B], [np.zeros((1, n + 1))]]) / rate)
    sampled = StateSpace(phi[:n, :n], phi[:n, n:], plant.C, plant.D)
    for method, system in discrete.items():
        if system.n_states != continuous.n_states:
            raise MotosimError(
                f"{where} [controller.{method}]: {system.n_states} states; expected "
                f"{continuous.n_states} as the continuous controller"
            )
        radius = float(np.max(np.abs(np.linalg.eigvals(_loop_matrix(sampled, system)))))
        if not radius < 1.0:
            raise MotosimError(
                f"{where} [controller.{method}]: the loop sampled at {rate:g} Hz has a spectral "
                f"radius of {radius:.4g}; expected a stable discrete loop (< 1)"
            )


def _observer(
    table: Mapping[str, Any], handlebar: HandlebarParameters, rate: float, where: str
) -> ObserverSettings:
    """Read the observer settings; refuse them unless the observer sampled at ``rate`` is stable."""
    from motosim.estimation.walcott_zak import WalcottZakObserver, design_with

    check_keys(table, _OBSERVER_KEYS, where=where, what="key")
    poles = _get(table, "poles", where)
    if not isinstance(poles, list) or len(poles) != 2:
        raise MotosimError(f"{where} poles = {short_repr(poles)}; expected two negative numbers")
    keys = ("eta", "injection_bandwidth", "filter_time_constant", "dead_zone", "friction_width")
    number = {
        key: check_number(_get(table, key, where), where=f"{where} {key}", lower=0.0)
        for key in keys
    }
    compensation = _get(table, "friction_compensation", where)
    if not isinstance(compensation, bool):
        raise MotosimError(
            f"{where} friction_compensation = {short_repr(compensation)}; expected true or false"
        )
    factor = {  # optional: 1 when absent
        key: check_number(
            table.get(key, 1.0), where=f"{where} {key}", lower=0.0, lower_closed=False, upper=10.0
        )
        for key in ("damping_factor", "inertia_factor")
    }
    settings = ObserverSettings(
        poles=(
            check_number(poles[0], where=f"{where} poles[0]", upper=0.0, upper_closed=False),
            check_number(poles[1], where=f"{where} poles[1]", upper=0.0, upper_closed=False),
        ),
        friction_compensation=compensation,
        **number,
        **factor,
    )
    for key in ("L", "P"):  # informative copies of what the settings rebuild
        if key in table and _matrix(table[key], f"{where} {key}").shape != (2, 2):
            raise MotosimError(f"{where} {key}: expected a 2 x 2 matrix")
    if "F" in table:
        _matrix([table["F"]], f"{where} F")
    try:
        WalcottZakObserver(design_with(handlebar, settings), dt=1.0 / rate)
    except MotosimError as err:
        raise MotosimError(f"{where}: {err}") from None
    return settings


def read_design(path: str | Path) -> DesignFile:
    """Read and validate a design file written by ``motosim design``.

    Besides the structure and the types, the design must work: the rate in
    :data:`RATE_RANGE`, the handlebar in its physical ranges, the observer rebuilt from its
    settings stable once sampled at the rate, the continuous controller stabilising the
    nominal handlebar, and each discrete controller stabilising it sampled at the rate.

    Raises
    ------
    MotosimError
        One line: no such file, invalid TOML, a missing or unknown table or key, an invalid
        value, an unstable observer or loop.
    """
    data = read_toml(Path(path), what="design file")
    check_keys(data, _TABLES, where=str(path), what="table")
    design = check_table(_get(data, "design", str(path)), where=f"{path}: design")
    check_keys(design, _DESIGN_KEYS, where=f"{path} [design]", what="key")
    for key in ("version", "date", "handlebar"):
        if key in design:
            check_text(design[key], where=f"{path} [design] {key}")
    rate = check_number(
        _get(design, "rate", f"{path} [design]"),
        where=f"{path} [design]: rate",
        lower=RATE_RANGE[0],
        upper=RATE_RANGE[1],
        unit="Hz",
    )
    handlebar = _handlebar(data, str(path))
    obs = check_table(_get(data, "observer", str(path)), where=f"{path}: observer")
    observer = _observer(obs, handlebar, rate, f"{path} [observer]")
    ctrl = check_table(_get(data, "controller", str(path)), where=f"{path}: controller")
    controller = _controller(ctrl, str(path))
    if "paper_controller" in data:  # the paper's eq. (26), for comparison
        paper = check_table(data["paper_controller"], where=f"{path}: paper_controller")
        check_keys(paper, ("num", "den", "gamma"), where=f"{path} [paper_controller]", what="key")
        if "gamma" in paper:
            check_number(paper["gamma"], where=f"{path} [paper_controller] gamma")
        for key in ("num", "den"):
            if key in paper:
                _matrix([paper[key]], f"{path} [paper_controller] {key}")
    discrete = {
        m: _state_space(
            _get(ctrl, m, f"{path} [controller]"), f"{path} [controller.{m}]", 1.0 / rate
        )
        for m in ("zoh", "tustin")
    }
    _check_loops(handlebar, controller, discrete, rate, str(path))
    return DesignFile(
        rate=rate,
        handlebar=handlebar,
        observer=observer,
        controller=controller,
        controller_discrete=discrete,
    )


def _handlebar(data: Mapping[str, Any], label: str) -> HandlebarParameters:
    """The design's ``[handlebar]`` table, checked as a parameter set."""
    table = check_table(_get(data, "handlebar", label), where=f"{label}: handlebar")
    check_keys(table, HandlebarParameters.SPECS, where=f"{label} [handlebar]", what="parameter")
    try:
        return HandlebarParameters(
            **{k: _get(table, k, f"{label} [handlebar]") for k in HandlebarParameters.SPECS}
        )
    except MotosimError as err:
        raise MotosimError(f"{label}: {err}") from None


def _controller(ctrl: Mapping[str, Any], label: str) -> StateSpace:
    """The continuous controller of the ``[controller]`` table; its other keys checked."""
    check_keys(ctrl, _CONTROLLER_KEYS, where=f"{label} [controller]", what="key")
    for key in _CONTROLLER_FIGURES:
        if key in ctrl:  # what the design achieved, for people: numbers all the same
            check_number(ctrl[key], where=f"{label} [controller] {key}")
    for key in ("num", "den"):
        if key in ctrl:
            _matrix([ctrl[key]], f"{label} [controller] {key}")
    controller = _state_space(ctrl, f"{label} [controller]")
    if controller.n_states > MAX_CONTROLLER_STATES:
        raise MotosimError(
            f"{label} [controller]: {controller.n_states} states; expected at most "
            f"{MAX_CONTROLLER_STATES}"
        )
    return controller
