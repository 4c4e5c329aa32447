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
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from motosim.control.statespace import StateSpace
from motosim.errors import MotosimError
from motosim.estimation.walcott_zak import ObserverSettings
from motosim.params.handlebar import HandlebarParameters

__all__ = ["DesignFile", "ObserverSettings", "dump_design", "read_design"]


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


def _get(table: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in table:
        raise MotosimError(f"{where}: missing {key!r}")
    return table[key]


def _state_space(table: Mapping[str, Any], where: str, dt: float = 0.0) -> StateSpace:
    try:
        A, B, C, D = (np.asarray(_get(table, k, where), dtype=float) for k in "ABCD")
        return StateSpace(A, B, C, D, dt=dt)
    except (TypeError, ValueError) as err:
        raise MotosimError(f"{where}: {err}") from None


def read_design(path: str | Path) -> DesignFile:
    """Read and validate a design file written by ``motosim design``.

    Raises
    ------
    MotosimError
        One line: no such file, invalid TOML, a missing table or key, an invalid value.
    """
    source = Path(path)
    if not source.is_file():
        raise MotosimError(f"{path}: no such design file")
    try:
        data = tomllib.loads(source.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise MotosimError(f"{path}: not valid TOML: {err}") from None
    known = {"design", "handlebar", "observer", "controller", "paper_controller"}
    unknown = set(data) - known
    if unknown:
        raise MotosimError(
            f"{path}: unknown table [{sorted(unknown)[0]}]; expected {sorted(known)}"
        )
    design = _get(data, "design", str(path))
    rate = float(_get(design, "rate", f"{path} [design]"))
    if not (math.isfinite(rate) and rate > 0):
        raise MotosimError(f"{path} [design]: rate = {rate!r}; expected a rate > 0 [Hz]")
    hb_table = dict(_get(data, "handlebar", str(path)))
    extra = set(hb_table) - set(HandlebarParameters.SPECS)
    if extra:
        raise MotosimError(f"{path} [handlebar]: unknown parameter {sorted(extra)[0]!r}")
    try:
        handlebar = HandlebarParameters(
            **{k: _get(hb_table, k, f"{path} [handlebar]") for k in HandlebarParameters.SPECS}
        )
    except MotosimError as err:
        raise MotosimError(f"{path}: {err}") from None
    obs = _get(data, "observer", str(path))
    where = f"{path} [observer]"
    observer = ObserverSettings(
        poles=tuple(float(v) for v in _get(obs, "poles", where)),  # type: ignore[arg-type]
        eta=float(_get(obs, "eta", where)),
        injection_bandwidth=float(_get(obs, "injection_bandwidth", where)),
        filter_time_constant=float(_get(obs, "filter_time_constant", where)),
        dead_zone=float(_get(obs, "dead_zone", where)),
        friction_width=float(_get(obs, "friction_width", where)),
        friction_compensation=bool(_get(obs, "friction_compensation", where)),
    )
    ctrl = _get(data, "controller", str(path))
    return DesignFile(
        rate=rate,
        handlebar=handlebar,
        observer=observer,
        controller=_state_space(ctrl, f"{path} [controller]"),
        controller_discrete={
            m: _state_space(
                _get(ctrl, m, f"{path} [controller]"), f"{path} [controller.{m}]", 1.0 / rate
            )
            for m in ("zoh", "tustin")
        },
    )
