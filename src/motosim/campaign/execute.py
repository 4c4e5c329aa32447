"""Running a campaign: one design per distinct design, runs batched into tasks, on a backend.

:func:`run_campaign` plans the campaign (:func:`motosim.campaign.plan.plan_campaign`), skips
the runs whose ids the result folder already holds, designs the stack once per design key
that the remaining runs need (:func:`motosim.io.runs.resolve` and
:func:`motosim.sim.build_stack`: parameter sets, controller synthesis, observer, motorcycle),
cuts the runs into tasks of about ``task_seconds`` of computing each, and runs the tasks on
all local cores with joblib (loky processes) or on a Dask cluster (a ``LocalCluster`` of local
processes, or any scheduler by its address, for example one started by dask-jobqueue on SLURM
or PBS). Each task simulates its runs with :func:`motosim.sim.simulate` on the shared stack
and returns one row per run; the parent writes each task's rows as one Parquet part as soon
as it arrives (:class:`motosim.campaign.results.ResultStore`). A run that diverges
(:class:`~motosim.errors.RunFailedError`) or whose combination of values is invalid is a
row with ``status = "failed"`` and its reason, and so is a run that left the model's range (it
fell, or its speed left 3-60 m/s: it stops there, as ``motosim simulate`` does, and keeps the
metrics of its rows until then) or whose metrics exceed the campaign's ``limits`` (its metrics
kept). With ``series``, the worker writes each run's
signals to ``DIR/series.zarr`` (:mod:`motosim.campaign.series`) before returning its row, so
a run whose row is in a part has its series too.
"""

import dataclasses
import importlib
import logging
import math
import os
import time
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from motosim.campaign.plan import Plan, PlannedRun, is_design_factor, plan_campaign, scenario_of
from motosim.campaign.results import ResultStore
from motosim.campaign.series import SeriesSpec, open_series_store
from motosim.campaign.spec import TRUE_HANDLEBAR, Campaign, Factor
from motosim.control.statespace import StateSpace
from motosim.errors import MotosimError, RunFailedError
from motosim.estimation.walcott_zak import ObserverSettings
from motosim.io.cache import DesignCache, cached_stack
from motosim.io.files import FolderLock
from motosim.io.runs import parameter_source, resolve
from motosim.model.tyred import TyredModel
from motosim.params import load_parameters
from motosim.params.handlebar import HandlebarParameters
from motosim.params.sharp import SharpParameters
from motosim.sim import RunInputs, Scenario, build_stack, prepare, simulate
from motosim.sim.closed_loop import (
    RigModel,
    build_rig,
    design_virtual_rider,
    perturb_rig,
    rider_design,
    rider_route,
    rig_key,
    route_length,
    run_limits,
)
from motosim.sim.metrics import multibody_reason, range_reason, run_metrics
from motosim.sim.multibody_rider import MultibodyRider
from motosim.sim.rider import RiderGains
from motosim.sim.stack import StackModel
from motosim.timeseries import TimeSeries

__all__ = [
    "STEPS_PER_SECOND",
    "CampaignSummary",
    "Design",
    "Task",
    "design_for",
    "rerun",
    "rerun_series",
    "run_campaign",
    "run_task",
]

_log = logging.getLogger(__name__)

STEPS_PER_SECOND = 7.0e5
"""Stack periods of a whole run (rig and stack) one core simulates per second, to size tasks
(measured with bench/bench_campaign.py: 10,000 periods in 10-14 ms of CPU on this machine)."""

Backend = Literal["joblib", "dask"]


@dataclass(frozen=True, slots=True)
class Design:
    """What every run of one design shares: the designed stack and the resolved inputs.

    Attributes
    ----------
    key : str
        The design key.
    stack : StackModel
        The designed stack.
    sharp : SharpParameters
        The virtual motorcycle.
    nominal : HandlebarParameters
        The nominal handlebar as loaded (before :func:`motosim.sim.prepare`).
    controller : StateSpace or None
        The controller.
    observer : ObserverSettings or None
        Observer settings of a design file.
    tables : Mapping of str to TimeSeries
        CSV profiles.
    true_handlebars : Mapping of str to HandlebarParameters
        The true handlebar sets the runs name.
    rider : RiderGains or MultibodyRider or None
        The virtual rider's schedule for the design's first run's rider settings
        (:func:`motosim.sim.closed_loop.rider_design`); the runs whose rider differs design
        their own, once per worker.
    rider_settings : str
        Those settings, as :class:`_Worker` compares them.
    """

    key: str
    stack: StackModel
    sharp: SharpParameters
    nominal: HandlebarParameters
    controller: StateSpace | None
    observer: ObserverSettings | None
    tables: Mapping[str, TimeSeries]
    true_handlebars: Mapping[str, HandlebarParameters]
    rider: RiderGains | MultibodyRider | None = None
    rider_settings: str = ""
    multibody: TyredModel | None = None
    """The multibody motorcycle of the runs (None: Sharp 1971's ``sharp``)."""


@dataclass(frozen=True, slots=True)
class Task:
    """A batch of runs of one design, sent to a worker as one unit."""

    design: Design
    base: Mapping[str, Any]
    factors: tuple[Factor, ...]
    runs: tuple[PlannedRun, ...]
    metrics: tuple[str, ...]
    limits: tuple[tuple[str, float], ...] = ()
    series: SeriesSpec | None = None


@dataclass(frozen=True, slots=True)
class CampaignSummary:
    """What a call of :func:`run_campaign` did and how long it took.

    Attributes
    ----------
    name : str
        The campaign.
    folder : str
        The result folder.
    runs : int
        Runs of the campaign.
    skipped : int
        Runs already in the folder, not run again.
    computed : int
        Runs computed by this call.
    failed : int
        Of these, the failed ones.
    designs : int
        Stacks designed by this call.
    tasks : int
        Tasks run.
    workers : int
        Worker processes.
    wall : float
        Wall time of the call [s].
    design_time : float
        Planning and designing [s].
    busy : float
        Sum over tasks of their time in a worker [s].
    cpu : float
        Sum over tasks of the CPU time they used [s] (below ``busy`` when other processes
        share the cores).
    compute : float
        Sum over runs of their simulation time [s].
    overhead : float
        Fraction of the workers' time in the run phase not spent in a task (start-up,
        scheduling, transfer, writing, waiting on the last tasks).
    shortened_to : int or None
        With ``runs`` (``--runs``): the number of the plan's first runs this call was
        limited to.
    """

    name: str
    folder: str
    runs: int
    skipped: int
    computed: int
    failed: int
    designs: int
    tasks: int
    workers: int
    wall: float
    design_time: float
    busy: float
    cpu: float
    compute: float
    overhead: float
    shortened_to: int | None = None


def design_for(plan: Plan, key: str, *, cache: DesignCache | None = None) -> Design:
    """Design the stack shared by the runs of design ``key`` (once per distinct design).

    With a ``cache`` (:class:`motosim.io.cache.DesignCache`), the designs are read from it
    when they were made before (by any command), else made and stored.
    """
    first = next(r for r in plan.runs if r.design == key)
    scenario, _ = scenario_of(plan.base, plan.campaign.factors, first)
    folder = Path(plan.folder)
    if cache is None:
        inputs = resolve(scenario, folder)
        stack = build_stack(inputs)
    else:
        with cache.designing(f"{plan.campaign.name}, design {key}"):
            inputs = resolve(scenario, folder, cache=cache)
            stack = cached_stack(cache, inputs)
    nominal = load_parameters(parameter_source(scenario.handlebar.nominal, folder), "handlebar")
    return Design(
        key=key,
        stack=stack,
        sharp=inputs.sharp,
        nominal=nominal,
        controller=inputs.controller,
        observer=inputs.observer,
        tables=inputs.tables,
        true_handlebars=plan.true_handlebars,
        rider=inputs.rider,
        rider_settings=_settings_key(rider_design(inputs.scenario)),
        multibody=inputs.multibody,
    )


def _settings_key(settings: Mapping[str, Any]) -> str:
    """The virtual rider's design settings as a key: arrays as lists, which ``repr`` writes
    without NumPy's array printing, run after run."""
    return repr(
        sorted((k, v.tolist() if isinstance(v, np.ndarray) else v) for k, v in settings.items())
    )


class _Worker:
    """What a worker builds once and reuses run after run of a task: the rig (perturbed in
    place while the runs differ only in their true handlebar and seed), the virtual rider's
    paths and gain schedules."""

    def __init__(self) -> None:
        self.rig_key: Any = None
        self.last_rig: RigModel | None = None
        self.routes: dict[Any, tuple[np.ndarray, float]] = {}
        self.riders: dict[tuple[str, str], RiderGains | MultibodyRider] = {}

    def rider(self, design: Design, scenario: Scenario) -> RiderGains | MultibodyRider:
        """The schedule of ``scenario``'s rider: the design's, or one designed here once."""
        settings = rider_design(scenario)
        key = (design.key, _settings_key(settings))
        if key not in self.riders:
            shared = design.rider if key[1] == design.rider_settings else None
            self.riders[key] = shared or design_virtual_rider(
                RunInputs(
                    scenario,
                    design.sharp,
                    design.nominal,
                    design.nominal,
                    None,
                    {},
                    multibody=design.multibody,
                )
            )
        return self.riders[key]

    def rig(self, design: Design, inputs: RunInputs, rng: np.random.Generator) -> RigModel:
        """The rig of a run: the previous run's perturbed, or built (with a shared path)."""
        sc = inputs.scenario
        key = (design.key, rig_key(sc))
        if self.last_rig is not None and key == self.rig_key:
            return perturb_rig(self.last_rig, inputs, rng=rng)
        route = None
        if sc.rider.kind == "virtual":
            where = (sc.rider.path, route_length(sc))
            if where not in self.routes:
                if len(self.routes) >= 8:
                    self.routes.clear()
                self.routes[where] = rider_route(sc)
            route = self.routes[where]
        self.last_rig, self.rig_key = build_rig(inputs, rng=rng, route=route), key
        return self.last_rig


_NEEDS = {
    "rms_tau_r_error": ("tau_r_hat", "tau_r"),
    "rms_tracking_error": ("theta_h", "delta"),
    "rms_rate_error": ("theta_h_dot_hat", "theta_h_dot"),
    "max_abs_phi": ("phi",),
    "max_abs_e_y": ("e_y",),
}
"""The signals each metric of :func:`motosim.sim.metrics.run_metrics` that a campaign keeps
is computed from (each from its own signals only)."""


def _metrics(ts: TimeSeries, names: Sequence[str]) -> list[float]:
    # run_metrics sees only the signals of the kept metrics: the same values, without the
    # fidelity figures and the spectrum of the current that a campaign does not keep
    used = {s for n in names for s in _NEEDS.get(n, ())}
    found = run_metrics(ts.t, lambda n: ts[n] if n in used else None, complete=True)
    extra = {
        "max_abs_tau_r_error": ("tau_r_hat", "tau_r"),
        "max_abs_tracking_error": ("theta_h", "delta"),
    }
    for key, (a, b) in extra.items():
        if key in names:
            found[key] = float(np.max(np.abs(ts[a] - ts[b])))
    if "max_abs_i_m" in names:
        found["max_abs_i_m"] = float(np.max(np.abs(ts["i_m"])))
    return [found.get(n, math.nan) for n in names]


def _run_one(
    task: Task, planned: PlannedRun, worker: _Worker | None = None
) -> tuple[str, str, float, list[float], TimeSeries | None]:
    """Simulate one run: (status, reason, failure time [s], metrics, signals or None).

    ``worker`` holds what the task's previous runs built (by default nothing is reused).
    """
    nan = [math.nan] * len(task.metrics)
    d = task.design
    worker = _Worker() if worker is None else worker
    try:
        scenario, overrides = scenario_of(task.base, task.factors, planned)
        true = d.true_handlebars[scenario.handlebar.true]
        if overrides:
            true = dataclasses.replace(true, **overrides)
        inputs = prepare(
            scenario,
            sharp=d.sharp,
            true_handlebar=true,
            nominal_handlebar=d.nominal,
            controller=d.controller,
            observer=d.observer,
            tables=d.tables,
            rider=worker.rider(d, scenario),
            multibody=d.multibody,
        )
    except MotosimError as err:
        return "failed", f"invalid: {err}", math.nan, nan, None
    limits = run_limits(inputs)
    try:
        rig = worker.rig(d, inputs, np.random.default_rng(scenario.seed))
        ts = simulate(
            inputs,
            rng=np.random.default_rng(scenario.seed),
            stack=d.stack,
            chunk=scenario.duration,
            stop_outside=limits,
            rig=rig,
        )
    except RunFailedError as err:
        return "failed", str(err), math.nan if err.time is None else err.time, nan, None
    values = _metrics(ts, task.metrics)
    if ts.t.size < round(scenario.duration * scenario.rates.control):
        t_end = float(ts.t[-1])
        if d.multibody is not None:
            reason = multibody_reason(ts.t, ts.__getitem__, d.multibody, limits)
        else:
            reason = range_reason(t_end, float(ts["phi"][-1]), float(ts["v_x"][-1]), limits)
        return "failed", reason, t_end, values, ts
    found = dict(zip(task.metrics, values, strict=True))
    beyond = [f"{k} = {found[k]:.4g} > {v:g}" for k, v in task.limits if not found[k] <= v]
    if beyond:
        return "failed", "beyond the limit: " + ", ".join(beyond), math.nan, values, ts
    return "ok", "", math.nan, values, ts


def run_task(task: Task) -> tuple[dict[str, list[Any]], float, float]:
    """Run a task's runs; returns their rows as columns, the task's time and CPU time [s].

    The columns are those of :mod:`motosim.campaign.results`. With ``task.series``, each
    run that produced signals writes them (:meth:`SeriesSpec.write`) before its row is
    returned; ``elapsed`` includes that write.
    """
    start, cpu = time.perf_counter(), time.process_time()
    paths = [f.path for f in task.factors]
    columns: dict[str, list[Any]] = {
        k: []
        for k in ("run_id", "index", "seed", "design", "status", "reason", "failed_at", "elapsed")
    }
    columns.update({p: [] for p in paths})
    columns.update({m: [] for m in task.metrics})
    worker = _Worker()
    for planned in task.runs:
        t0 = time.perf_counter()
        status, reason, failed_at, values, ts = _run_one(task, planned, worker)
        if task.series is not None and ts is not None:
            task.series.write(planned.run_id, planned.seed, ts)
        columns["elapsed"].append(time.perf_counter() - t0)
        columns["run_id"].append(planned.run_id)
        columns["index"].append(planned.index)
        columns["seed"].append(planned.seed)
        columns["design"].append(planned.design)
        columns["status"].append(status)
        columns["reason"].append(reason)
        columns["failed_at"].append(failed_at)
        for p, v in zip(paths, planned.values, strict=True):
            columns[p].append(v)
        for m, v in zip(task.metrics, values, strict=True):
            columns[m].append(v)
    return columns, time.perf_counter() - start, time.process_time() - cpu


def _batches(
    plan: Plan,
    todo: Sequence[PlannedRun],
    designs: Mapping[str, Design],
    workers: int,
    series: SeriesSpec | None = None,
) -> list[Task]:
    """Cut the runs into tasks of one design and about ``task_seconds`` each."""
    c = plan.campaign
    rates = plan.base["rates"]
    per_run = float(plan.base["duration"]) * float(rates["control"]) / STEPS_PER_SECOND
    size = max(1, round(c.task_seconds / per_run))
    # at least four tasks per worker when there are enough runs, for an even finish
    size = min(size, max(1, math.ceil(len(todo) / (4 * workers))))
    groups: dict[str, list[PlannedRun]] = {}
    for planned in todo:
        groups.setdefault(planned.design, []).append(planned)
    tasks = []
    for key, runs in groups.items():
        for i in range(0, len(runs), size):
            tasks.append(
                Task(
                    designs[key],
                    plan.base,
                    c.factors,
                    tuple(runs[i : i + size]),
                    c.metrics,
                    c.limits,
                    series,
                )
            )
    return tasks


def _serial(tasks: Sequence[Task]) -> Iterator[tuple[dict[str, list[Any]], float, float]]:
    for task in tasks:
        yield run_task(task)


def _joblib(
    tasks: Sequence[Task], jobs: int
) -> Iterator[tuple[dict[str, list[Any]], float, float]]:
    try:
        from joblib import Parallel, delayed
    except ImportError:  # pragma: no cover - the campaign group installs it
        raise MotosimError(
            "backend 'joblib' needs joblib: pip install 'motosim[campaign]'"
        ) from None
    parallel = Parallel(n_jobs=jobs, return_as="generator_unordered")
    yield from parallel(delayed(run_task)(task) for task in tasks)


def _dask(
    tasks: Sequence[Task], jobs: int, scheduler: str | None
) -> Iterator[tuple[dict[str, list[Any]], float, float]]:
    try:
        dd: Any = importlib.import_module("dask.distributed")
    except ImportError:
        raise MotosimError(
            "backend 'dask' needs dask.distributed: pip install 'motosim[campaign]'"
        ) from None
    cluster = None
    if scheduler is None:
        cluster = dd.LocalCluster(
            n_workers=jobs, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = dd.Client(cluster)
    else:
        try:
            client = dd.Client(scheduler, timeout=10)
        except OSError as err:
            raise MotosimError(
                f"--scheduler {scheduler}: no Dask scheduler answered ({err}); expected an "
                "address like tcp://host:8786"
            ) from None
    try:
        futures = client.map(run_task, tasks, pure=False)
        for future in dd.as_completed(futures):
            yield future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _workers(backend: Backend, jobs: int | None, scheduler: str | None) -> int:
    if jobs is not None and jobs < 1:
        raise MotosimError(f"--jobs {jobs}; expected at least 1")
    if backend == "dask" and scheduler is not None:
        return jobs or 1  # the cluster's size; only used to size tasks
    return jobs or os.cpu_count() or 1


def _plain_campaign(campaign: Campaign) -> dict[str, Any]:
    def clean(value: Any) -> Any:
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        return value

    plain: dict[str, Any] = clean(dataclasses.asdict(campaign))
    return plain


def run_campaign(
    campaign: Campaign,
    out: str | Path,
    *,
    backend: Backend | None = None,
    scheduler: str | None = None,
    jobs: int | None = None,
    on_progress: Callable[[int, int, int], None] | None = None,
    runs: int | None = None,
    cache: DesignCache | None = None,
    lock: FolderLock | None = None,
) -> CampaignSummary:
    """Run a campaign into the folder ``out``, skipping the runs it already holds.

    Parameters
    ----------
    campaign : Campaign
        The campaign (:func:`motosim.campaign.load_campaign`).
    out : str or Path
        Result folder: ``parts/part-*.parquet``, ``manifest.json`` and, when the campaign
        keeps ``series``, ``series.zarr`` (on a cluster, a folder every worker can write).
    backend : {"joblib", "dask"}, optional
        joblib's loky processes on this machine (default), or Dask (the default when a
        ``scheduler`` is given).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); without it the Dask
        backend starts a ``LocalCluster`` of ``jobs`` processes.
    jobs : int, optional
        Local worker processes (default: every core); 1 runs in this process.
    on_progress : callable, optional
        Called as ``on_progress(done, total, failed)`` after each task.
    runs : int, optional
        Run only the first ``runs`` of the plan (a shortened campaign: its manifest says
        ``"shortened"`` until the whole plan is written; a call without ``runs`` completes
        it).
    cache : DesignCache, optional
        Where the designs are read from and stored (:mod:`motosim.io.cache`); by default
        designed in this call.
    lock : FolderLock, optional
        The caller's held lock of ``out``, kept after the call (for the report it writes
        there); by default the lock is taken for the call.

    Returns
    -------
    CampaignSummary

    Raises
    ------
    MotosimError
        On an invalid campaign, a folder holding another campaign, an impossible design or a
        backend that is not installed or not reachable.
    """
    start = time.perf_counter()
    chosen: Backend = backend or ("dask" if scheduler else "joblib")
    if chosen == "joblib" and scheduler is not None:
        raise MotosimError("--scheduler is for --backend dask")
    workers = _workers(chosen, jobs, scheduler)
    if runs is not None and not 1 <= runs:
        raise MotosimError(f"--runs {runs}; expected at least 1 run")
    plan = plan_campaign(campaign)
    kinds: list[type] = []
    for f in campaign.factors:
        first = plan.runs[0].values[len(kinds)]
        kinds.append(float if f.path.startswith(f"{TRUE_HANDLEBAR}.") else type(first))
    # a second instance on the folder, or another command writing it (motosim simulate, whose
    # result would replace the folder whole), is refused, not mixed in: the lock is beside the
    # folder (.NAME.lock), the one every command takes
    with nullcontext() if lock is not None else FolderLock(out):
        store = ResultStore(
            out,
            fingerprint=plan.fingerprint,
            factors=[(f.path, k) for f, k in zip(campaign.factors, kinds, strict=True)],
            metrics=campaign.metrics,
        )
        return _fill(
            campaign,
            out,
            plan,
            store,
            chosen,
            workers,
            scheduler,
            start,
            on_progress,
            runs,
            cache,
        )


def _fill(
    campaign: Campaign,
    out: str | Path,
    plan: Plan,
    store: ResultStore,
    chosen: Backend,
    workers: int,
    scheduler: str | None,
    start: float,
    on_progress: Callable[[int, int, int], None] | None,
    limit: int | None = None,
    cache: DesignCache | None = None,
) -> CampaignSummary:
    """Run the campaign's runs that ``store`` does not hold yet (:func:`run_campaign`), of
    the first ``limit`` of the plan when given."""
    if store.previous == "stopped":
        _log.info("%s: its last call stopped while running (killed, or a full disk); resuming", out)
    if limit is not None and limit >= len(plan.runs):
        limit = None  # the whole plan
    planned = plan.runs if limit is None else plan.runs[:limit]
    todo = [r for r in planned if r.run_id not in store.done]
    skipped = len(planned) - len(todo)
    needed = sorted({r.design for r in todo})
    designs = {key: design_for(plan, key, cache=cache) for key in needed}
    series = None
    if campaign.series:
        open_series_store(out, campaign.series, campaign.every)
        series = SeriesSpec(str(Path(out).resolve()), campaign.series, campaign.every)
    tasks = _batches(plan, todo, designs, workers, series)
    design_paths = [f.path for f in campaign.factors if is_design_factor(f.path)]
    manifest: dict[str, Any] = {
        "name": campaign.name,
        "campaign_file": campaign.source,
        "fingerprint": plan.fingerprint,
        "campaign": _plain_campaign(campaign),
        "base_scenario": plan.base,
        "runs": len(plan.runs),
        "designs": {k: dict(zip(design_paths, v, strict=True)) for k, v in plan.designs.items()},
        "backend": chosen,
        "workers": workers,
        "status": "running",
        "written": len(store.done & {r.run_id for r in plan.runs}),
    }
    if limit is not None:
        manifest["shortened_to"] = len(planned)  # --runs: the first runs of the plan
    # "running" holds only while this process holds the folder's lock: a reader that can take
    # the lock reads the campaign as stopped (read_manifest), however this call ends
    store.write_manifest(manifest)
    design_time = time.perf_counter() - start
    done, failed, busy, compute, cpu = skipped, 0, 0.0, 0.0, 0.0
    run_start = time.perf_counter()
    results: Iterator[tuple[dict[str, list[Any]], float, float]] = iter(())
    status = "interrupted"
    try:
        if on_progress is not None:
            on_progress(done, len(planned), failed)
        if tasks and workers == 1 and chosen == "joblib":
            results = _serial(tasks)
        elif tasks and chosen == "joblib":
            results = _joblib(tasks, workers)
        elif tasks:
            results = _dask(tasks, workers, scheduler)
        for columns, seconds, cpu_seconds in results:
            store.write_part(columns)
            busy += seconds
            cpu += cpu_seconds
            compute += float(sum(columns["elapsed"]))
            done += len(columns["run_id"])
            failed += sum(s != "ok" for s in columns["status"])
            if on_progress is not None:
                on_progress(done, len(planned), failed)
        whole = store.done >= {r.run_id for r in plan.runs}
        status = "complete" if whole else "shortened"
    except BaseException as err:
        if not isinstance(err, KeyboardInterrupt | SystemExit):  # a full disk, a worker lost
            status = "failed"
            manifest["error"] = (str(err).strip().splitlines() or [type(err).__name__])[0]
        with warnings.catch_warnings():  # joblib's note that it cancelled the other tasks
            warnings.filterwarnings("ignore", ".*tasks which were still being processed")
            close = getattr(results, "close", None)
            if close is not None:
                close()
        raise
    finally:
        end = time.perf_counter()
        run_wall = end - run_start
        overhead = 1.0 - busy / (workers * run_wall) if tasks and run_wall > 0 else 0.0
        summary = CampaignSummary(
            name=campaign.name,
            folder=str(out),
            runs=len(plan.runs),
            skipped=skipped,
            computed=done - skipped,
            failed=failed,
            designs=len(designs),
            tasks=len(tasks),
            workers=workers,
            wall=end - start,
            design_time=design_time,
            busy=busy,
            cpu=cpu,
            compute=compute,
            overhead=max(overhead, 0.0),
            shortened_to=None if limit is None else len(planned),
        )
        manifest.update(
            status=status,
            written=len(store.done & {r.run_id for r in plan.runs}),
            last_call=dataclasses.asdict(summary),
        )
        try:
            store.write_manifest(manifest)
        except MotosimError:  # one line, naming the file and the system's reason
            if status == "complete":
                raise  # else the error that stopped the campaign (a full disk) is the one said
    return summary


def rerun(plan: Plan, run_id: str) -> dict[str, Any]:
    """Run one run of a campaign again, exactly as the campaign ran it.

    Parameters
    ----------
    plan : Plan
        The campaign's plan.
    run_id : str
        The run.

    Returns
    -------
    dict
        The run's row (the columns of :mod:`motosim.campaign.results` but ``elapsed``).
    """
    planned = plan.run(run_id)
    task = Task(
        design_for(plan, planned.design),
        plan.base,
        plan.campaign.factors,
        (planned,),
        plan.campaign.metrics,
        plan.campaign.limits,
    )
    columns, _, _ = run_task(task)
    return {k: v[0] for k, v in columns.items() if k != "elapsed"}


def rerun_series(plan: Plan, run_id: str) -> tuple[dict[str, Any], dict[str, Any]]:
    """Run one run again; its row (as :func:`rerun`) and its kept series (as stored).

    Parameters
    ----------
    plan : Plan
        The plan of a campaign with ``series``.
    run_id : str
        The run.

    Returns
    -------
    row : dict
        As :func:`rerun`.
    series : dict of str to ndarray
        ``t`` and the campaign's ``series``, decimated by ``every`` (empty when the run
        failed without signals).
    """
    c = plan.campaign
    planned = plan.run(run_id)
    task = Task(
        design_for(plan, planned.design), plan.base, c.factors, (planned,), c.metrics, c.limits
    )
    status, reason, failed_at, values, ts = _run_one(task, planned)
    row: dict[str, Any] = {
        "run_id": planned.run_id,
        "index": planned.index,
        "seed": planned.seed,
        "design": planned.design,
        "status": status,
        "reason": reason,
        "failed_at": failed_at,
    }
    row.update(zip([f.path for f in c.factors], planned.values, strict=True))
    row.update(zip(c.metrics, values, strict=True))
    kept: dict[str, Any] = {}
    if ts is not None:
        step = slice(None, None, c.every)
        kept = {n: np.asarray(ts.t if n == "t" else ts[n])[step] for n in ("t", *c.series)}
    return row, kept
