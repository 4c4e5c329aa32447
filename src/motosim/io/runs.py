"""Runs from scenario files: resolve what a scenario names, simulate, write the result.

The command line and any script build and run a scenario through these functions:
:func:`load_scenario` reads and validates a file, :func:`resolve` loads what it names
(parameter sets, a design file, CSV profiles, an OpenDRIVE road; relative to the scenario's
folder) and designs what it asks for, :func:`load_run` does both, and :func:`run_to_folder`
simulates into a result folder as the run goes. The designs are read from a design cache
(:mod:`motosim.io.cache`) when one is passed in, never otherwise; a campaign that runs one
design on many handlebars builds the stack once (:func:`motosim.sim.build_stack`) and passes
it to :func:`motosim.sim.simulate`.
"""

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from motosim.choices import MOTORCYCLE_PROFILES
from motosim.errors import MotosimError, RunFailedError, StopFlag, warn
from motosim.estimation.walcott_zak import ObserverSettings, WalcottZakObserver, design_with
from motosim.io.cache import DesignCache, cached_controller, cached_rider
from motosim.io.design_file import read_design
from motosim.io.files import FolderLock
from motosim.io.logs import read_log
from motosim.io.opendrive import read_opendrive
from motosim.io.results import ResultWriter
from motosim.model.linear import StateSpace
from motosim.params import HandlebarParameters, load_parameter_set, load_parameters
from motosim.params.toml import read_toml
from motosim.sim import Scenario, parse_scenario
from motosim.sim.closed_loop import SIGNALS, RunInputs, prepare, run_limits, run_metadata, simulate
from motosim.sim.grips import held_handlebar
from motosim.sim.metrics import failure, multibody_reason, range_reason, run_metrics, wheel_locks
from motosim.sim.scenario import CsvProfile, OpenDrivePath, check_profile_values, implausible
from motosim.sim.stack import StackModel
from motosim.timeseries import TimeSeries

__all__ = ["load_run", "load_scenario", "parameter_source", "read_road", "resolve", "run_to_folder"]


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file (one-line :class:`MotosimError` otherwise)."""
    source = Path(path)
    data = dict(read_toml(source, what="scenario file"))
    data.pop("realtime", None)  # read by motosim run and rig (motosim.rt.config), not here
    scenario = read_road(parse_scenario(data, origin=str(path)), source.parent)
    for line in implausible(scenario):
        warn(f"{path}: {line}")
    return scenario


def read_road(scenario: Scenario, base: str | Path) -> Scenario:
    """The scenario with its OpenDRIVE path's ``geometry`` read from its file, if it has one.

    The file is relative to the folder ``base``; a path whose ``geometry`` is already there
    (a scenario read back from a result or a campaign) is left as it is.

    Raises
    ------
    MotosimError
        What :func:`motosim.io.opendrive.read_opendrive` refuses.
    """
    path = scenario.rider.path
    if not isinstance(path, OpenDrivePath) or path.geometry:
        return scenario
    geometry = read_opendrive(Path(base) / path.file, road=path.road)
    rider = dataclasses.replace(scenario.rider, path=dataclasses.replace(path, geometry=geometry))
    return dataclasses.replace(scenario, rider=rider)


def parameter_source(name: str, base: str | Path) -> str | Path:
    """Where a scenario's parameter set or design file ``name`` is read from.

    A ``.toml`` file in the scenario's folder ``base`` when there is one, else ``name`` as it
    is (a packaged set, or a path that :func:`motosim.params.load_parameters` checks).
    """
    base = Path(base)
    candidate = base / name
    return candidate if candidate.suffix == ".toml" and candidate.is_file() else name


def resolve(scenario: Scenario, base: str | Path, *, cache: DesignCache | None = None) -> RunInputs:
    """Load what ``scenario`` names, relative to the folder ``base``, and design its controller.

    The controller is the scenario's: none, the paper's eq. (26), the one of a design file
    (whose observer settings the run then uses too), or ours synthesised for the nominal
    handlebar at the scenario's bandwidth (by default
    :func:`~motosim.control.torque_feedback.handlebar_bandwidth` of the handlebar at the
    measurement rate), order and integral corner. With a ``cache``
    (:class:`motosim.io.cache.DesignCache`) the synthesis and the virtual rider's schedule
    are read from it when they were designed before, else designed and stored.

    Raises
    ------
    MotosimError
        On a missing or invalid file, or a bandwidth beyond a fifth of the measurement rate.
    RunFailedError
        If the controller's synthesis fails on the checked scenario.
    """
    folder = Path(base)
    scenario = read_road(scenario, folder)
    hb, mc = scenario.handlebar, scenario.motorcycle
    nominal = load_parameters(parameter_source(hb.nominal, folder), "handlebar")
    tables = _read_tables(scenario, folder)
    controller, observer = _controller(scenario, folder, nominal, cache)
    source = sharp_source = parameter_source(mc.params, folder)
    multibody = None
    if mc.model == "multibody":
        from motosim.model.tyred import load_model

        multibody = load_model(str(source), speed=mc.speed)
        if load_parameter_set(source).model != "sharp":  # Sharp's machine sets the side wind's
            sharp_source = "sharp1971"  # input, which the multibody model does not read
    inputs = prepare(
        scenario,
        sharp=load_parameters(sharp_source, "sharp"),
        multibody=multibody,
        true_handlebar=load_parameters(parameter_source(hb.true, folder), "handlebar"),
        nominal_handlebar=nominal,
        controller=controller,
        observer=observer,
        tables=tables,
    )
    if cache is None:
        return inputs
    with cache.designing(scenario.name):
        return dataclasses.replace(inputs, rider=cached_rider(cache, inputs))


def _read_tables(scenario: Scenario, folder: Path) -> dict[str, TimeSeries]:
    """The CSV profiles the scenario names (file name -> table), each checked in its range."""
    mc = scenario.motorcycle
    profiles = {f"[motorcycle] {key}": getattr(mc, key) for key in MOTORCYCLE_PROFILES} | {
        "[road] friction": scenario.road.friction,
        "[rider] profile": scenario.rider.profile,
        "[rider] probe": scenario.rider.probe,
    }
    tables: dict[str, TimeSeries] = {}
    for where, profile in profiles.items():
        if isinstance(profile, CsvProfile):
            tables[profile.file] = read_log(
                folder / profile.file,
                required=(profile.column,),
                min_samples=2,
                remedy=f"the file's header must name t and the column = {profile.column!r}",
            )
            # its values in their legal range, as a profile written in the scenario: a huge
            # one would overflow in the run's metrics before the run failed
            values = tables[profile.file][profile.column]
            check_profile_values(
                where,
                float(np.min(values)),
                float(np.max(values)),
                key=f"{profile.file}: column {profile.column!r} ({where})",
            )
    return tables


def _controller(
    scenario: Scenario, folder: Path, nominal: HandlebarParameters, cache: DesignCache | None
) -> tuple[StateSpace | None, ObserverSettings | None]:
    """The scenario's controller and, from a design file, its observer settings."""
    c = scenario.controller
    if c.kind == "paper":
        from motosim.control.torque_feedback import PAPER_CONTROLLER

        return PAPER_CONTROLLER, None
    if c.kind != "ours":
        return None, None
    rate = scenario.rates.measurement
    if c.design is None:
        # designed for the handlebar held by the hands the stack models
        return _synthesised(scenario, held_handlebar(nominal, scenario.stack_hands), cache), None
    design = read_design(parameter_source(c.design, folder))
    # the design's own discrete matrices when it was made for this rate
    matches = abs(design.rate - rate) <= 1e-9 * rate
    controller = design.controller_discrete[c.discretization] if matches else design.controller
    if not matches and scenario.estimator.name == "walcott_zak":
        _check_observer_rate(c.design, design.rate, design.observer, nominal, rate)
    _warn_other_handlebar(c.design, design.handlebar, nominal)
    return controller, design.observer


def _synthesised(
    scenario: Scenario, nominal: HandlebarParameters, cache: DesignCache | None
) -> StateSpace:
    """Our controller synthesised for the nominal handlebar, or read from the cache."""
    c = scenario.controller
    rate = scenario.rates.measurement
    if c.bandwidth is not None:  # bad input, before the synthesis
        from motosim.control.torque_feedback import check_options

        try:
            check_options(bandwidth=c.bandwidth, rate=rate, integral_corner=c.integral_corner)
        except MotosimError as err:
            raise MotosimError(f"[controller] {err}") from None

    def synthesis() -> StateSpace:  # SciPy: only when the design is not cached
        from motosim.control.torque_feedback import (
            INTEGRAL_CORNER,
            handlebar_bandwidth,
            synthesize_controller,
        )

        bandwidth = c.bandwidth
        if bandwidth is None:
            bandwidth, controller = handlebar_bandwidth(nominal, rate=rate, n_starts=4)
        if c.bandwidth is not None or c.order != 1 or c.integral_corner != INTEGRAL_CORNER:
            controller = synthesize_controller(
                nominal,
                rng=np.random.default_rng(0),
                bandwidth=bandwidth,
                order=c.order,
                rate=rate,
                n_starts=4,
                integral_corner=c.integral_corner,
            )
        return controller

    settings = {
        "rate": rate,
        "bandwidth": c.bandwidth,
        "order": c.order,
        "integral_corner": c.integral_corner,
        "n_starts": 4,
        "seed": 0,
    }
    # the scenario is checked by now: a synthesis failing on it is a failed run (exit 3)
    try:
        if cache is None:
            return synthesis()
        with cache.designing(scenario.name):
            return cached_controller(cache, synthesis, handlebar=nominal, settings=settings)
    except MotosimError as err:
        raise RunFailedError(
            f"{scenario.name}: the controller's design failed ([controller] order {c.order}): {err}"
        ) from None


def _summary(
    run: TimeSeries, inputs: RunInputs, *, complete: bool, limits: tuple[float, float, float]
) -> dict[str, Any]:
    """The run's metrics and, under ``failure``, why a run that produced rows failed: it
    stopped outside the model's range, or completed saturated, or with a wheel locked to the
    end (multibody)."""
    sc = inputs.scenario
    summary: dict[str, Any] = run_metrics(
        run.t, run.get, complete=complete, max_current=sc.controller.max_current, limits=limits
    )
    if not complete and inputs.multibody is not None:
        reason: str | None = multibody_reason(run.t, run.__getitem__, inputs.multibody, limits)
    elif not complete:
        reason = range_reason(
            float(run.t[-1]), float(run["phi"][-1]), float(run["v_x"][-1]), limits
        )
    else:
        reason = failure(summary)
        if reason is None and inputs.multibody is not None:
            locks = wheel_locks(run.t, run.__getitem__)
            reason = ", and ".join(locks) + " to the end of the run" if locks else None
    if reason is not None:
        summary["failure"] = reason
    return summary


def _check_observer_rate(
    name: str,
    made_for: float,
    settings: ObserverSettings,
    nominal: HandlebarParameters,
    rate: float,
) -> None:
    """Refuse a design file's observer that is unstable sampled at the scenario's ``rate``.

    Checked before the run, so that the message names the file and both rates and no empty
    partial result is left.
    """
    try:
        WalcottZakObserver(design_with(nominal, settings), dt=1.0 / rate)
    except MotosimError as err:
        raise MotosimError(
            f"{name}: a design for {made_for:g} Hz whose observer, sampled at the scenario's "
            f"measurement rate of {rate:g} Hz, fails ({err}); expected a design for {rate:g} Hz "
            f"(motosim design --rate {rate:g})"
        ) from None


def _warn_other_handlebar(
    name: str, designed_for: HandlebarParameters, nominal: HandlebarParameters
) -> None:
    """Warn when a design file was made for another handlebar than the scenario's nominal one.

    The run takes the design's controller and observer gains but the scenario's ``[handlebar]
    nominal`` for the observer's model and the feedforward: mixed parts, legal (a study of a
    mismatched design) but not what a lab that forgot ``nominal`` means.
    """
    differ = [
        f.name
        for f in dataclasses.fields(nominal)
        if not math.isclose(getattr(designed_for, f.name), getattr(nominal, f.name), rel_tol=1e-9)
    ]
    if differ:
        shown = ", ".join(
            f"{k} {getattr(designed_for, k):.4g} against {getattr(nominal, k):.4g}"
            for k in differ[:3]
        )
        warn(
            f"{name}: designed for another handlebar than the scenario's nominal one ({shown}"
            f"{', ...' if len(differ) > 3 else ''}); the run mixes the design's gains with the "
            "scenario's handlebar: set [handlebar] nominal to the design's handlebar file"
        )


def load_run(path: str | Path, *, cache: DesignCache | None = None) -> RunInputs:
    """Read a scenario file and resolve it (:func:`load_scenario` then :func:`resolve`)."""
    return resolve(load_scenario(path), Path(path).parent, cache=cache)


def run_to_folder(
    inputs: RunInputs,
    folder: str | Path,
    *,
    overwrite: bool = False,
    on_rows: Callable[[int], None] | None = None,
    stack: StackModel | None = None,
    lock: FolderLock | None = None,
    stop: StopFlag | None = None,
) -> dict[str, Any]:
    """Simulate ``inputs`` into ``folder`` (``result.h5``, ``result.csv``), block by block.

    Parameters
    ----------
    inputs : RunInputs
        The resolved run.
    folder : str or Path
        Result folder.
    overwrite : bool
        Replace a result already there.
    on_rows : callable, optional
        Called with the number of rows of each block written (for a progress bar).
    stack : StackModel, optional
        The run's designed stack (:func:`motosim.io.cache.cached_stack`); by default
        :func:`motosim.sim.build_stack` of ``inputs``.
    lock, stop : FolderLock, StopFlag, optional
        The caller's held lock of ``folder``, its stop flag (see :class:`ResultWriter`).

    Returns
    -------
    dict
        The run's metrics (:func:`motosim.sim.metrics.run_metrics`), also stored in the file.

    Raises
    ------
    RunFailedError
        If the run diverged (its rows kept, marked partial), left the model's range of
        validity (:func:`motosim.sim.metrics.validity_limits`: it fell, or its speed left
        it; stopped at that instant) or completed saturating the motor most of the time; the
        last two are written whole, flagged (summary ``failure``), the one-line reason
        naming the time and the value.
    """
    sc = inputs.scenario
    rows = round(sc.duration * sc.rates.control)
    writer = ResultWriter(
        Path(folder),
        SIGNALS,
        run_metadata(inputs),
        overwrite=overwrite,
        expected_rows=rows,
        lock=lock,
        stop=stop,
    )
    summary, run = _record(writer, inputs, stack, on_rows)
    if "failure" in summary:
        raise RunFailedError(
            f"{sc.name}: {summary['failure']}; the result is in {folder}, flagged",
            time=float(run.t[-1]) if run.t.size < rows else None,
        )
    return summary


def _record(
    writer: ResultWriter,
    inputs: RunInputs,
    stack: StackModel | None,
    on_rows: Callable[[int], None] | None,
) -> tuple[dict[str, Any], TimeSeries]:
    """Simulate into ``writer`` block by block and close it with the summary; the summary
    and the run."""
    sc = inputs.scenario
    limits = run_limits(inputs)

    def on_block(block: np.ndarray) -> None:
        writer.append(block)
        if on_rows is not None:
            on_rows(block.shape[0])

    try:
        with writer:
            rng = np.random.default_rng(sc.seed)
            run = simulate(inputs, rng=rng, stack=stack, on_block=on_block, stop_outside=limits)
            complete = run.t.size == round(sc.duration * sc.rates.control)
            summary = _summary(run, inputs, complete=complete, limits=limits)
            writer.close(summary)
    except RunFailedError as err:
        raise RunFailedError(
            f"{sc.name}: {err}; the {writer.rows} rows computed are kept in "
            f"{writer.location}, marked partial",
            time=err.time,
        ) from None
    return summary, run
