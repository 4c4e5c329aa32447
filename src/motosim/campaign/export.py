"""One run of a campaign as a scenario file that ``motosim simulate`` runs on its own.

The scenario is the run's (the base with the run's values, its seed as ``seed``); files the
base names relative to its folder are written as absolute paths; when the run sets parameters
of the true handlebar, they go to a parameter file beside the scenario, which it names.
"""

import dataclasses
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from motosim.campaign.plan import Plan, scenario_of
from motosim.errors import MotosimError
from motosim.io.files import write_whole
from motosim.params import ParameterSet, dump_parameter_set
from motosim.sim.scenario import scenario_dict

__all__ = ["export_run", "scenario_toml"]

_FILE_KEYS = (
    ("handlebar", "true"),
    ("handlebar", "nominal"),
    ("motorcycle", "params"),
    ("controller", "design"),
)


def _value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise MotosimError(f"cannot write the non-finite value {value!r} to a scenario file")
        return repr(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{k} = {_value(v)}" for k, v in value.items()) + " }"
    raise MotosimError(f"cannot write {value!r} to a scenario file")


def scenario_toml(data: Mapping[str, Any], *, comment: str = "") -> str:
    """Render a scenario as plain data (:func:`scenario_dict`) as TOML text.

    Examples
    --------
    >>> print(scenario_toml({"name": "x", "rates": {"plant": 1000.0}}))
    [scenario]
    name = "x"
    <BLANKLINE>
    [rates]
    plant = 1000.0
    <BLANKLINE>
    """
    lines = [f"# {line}" for line in comment.splitlines()]
    lines.append("[scenario]")
    lines += [f"{k} = {_value(v)}" for k, v in data.items() if not isinstance(v, Mapping)]
    for key, table in data.items():
        if isinstance(table, Mapping):
            lines += ["", f"[{key}]", *(f"{k} = {_value(v)}" for k, v in table.items())]
    return "\n".join(lines) + "\n"


def export_run(plan: Plan, run_id: str, path: str | Path) -> list[Path]:
    """Write run ``run_id`` as the scenario file ``path`` (and its handlebar file if needed).

    Returns
    -------
    list of Path
        The files written.
    """
    planned = plan.run(run_id)
    scenario, overrides = scenario_of(plan.base, plan.campaign.factors, planned)
    target = Path(path)
    data = scenario_dict(scenario)
    folder = Path(plan.folder)
    for table, key in _FILE_KEYS:
        name = data.get(table, {}).get(key)
        if isinstance(name, str) and name.endswith(".toml") and (folder / name).is_file():
            data[table][key] = str((folder / name).resolve())
    written = []
    if overrides:
        true = plan.true_handlebars[scenario.handlebar.true]
        values = dataclasses.replace(true, **overrides)
        hb_path = target.with_name(f"{target.stem}_true_handlebar.toml")
        pset = ParameterSet(
            name=f"{target.stem}_true_handlebar",
            model="handlebar",
            title=f"True handlebar of run {run_id} of campaign {plan.campaign.name}",
            source=f"{scenario.handlebar.true} with {overrides}",
            values=values,
            sources={k: f"campaign {plan.campaign.name}, run {run_id}" for k in overrides},
        )
        hb_path.parent.mkdir(parents=True, exist_ok=True)
        text = dump_parameter_set(pset)
        write_whole(hb_path, lambda temporary: temporary.write_text(text, encoding="utf-8"))
        written.append(hb_path)
        data["handlebar"]["true"] = hb_path.name
    comment = (
        f"Run {run_id} (index {planned.index}) of campaign {plan.campaign.name}: "
        "`motosim simulate` reproduces it."
    )
    data["name"] = f"{plan.campaign.name}_{run_id}"
    target.parent.mkdir(parents=True, exist_ok=True)
    scenario_text = scenario_toml(data, comment=comment)  # written whole: a rerun refuses a file
    write_whole(target, lambda temporary: temporary.write_text(scenario_text, encoding="utf-8"))
    return [target, *written]
