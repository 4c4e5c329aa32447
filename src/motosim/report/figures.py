"""The figures of a run's report, drawn here or in worker processes started before the run.

matplotlib takes about a second to import and a few tenths of a second per figure, more
than a warm run itself. A command that runs and then reports (``motosim simulate``) opens
:class:`FigureWorkers` before it runs: a fork server (:mod:`multiprocessing.forkserver`)
imports matplotlib and :mod:`motosim.plotting.closed_loop` on another core while the run
goes on, and once the result is written two processes forked from it draw the figures, the
costliest first. Without a fork server (Windows) or a second core nothing is started and the
figures are drawn in the calling process; both ways give the same SVG images.
"""

import contextlib
import multiprocessing
import os
import signal
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from functools import lru_cache
from pathlib import Path
from types import TracebackType
from typing import Any

from motosim.errors import MotosimError
from motosim.io.results import SimResult, load_result

__all__ = ["FIGURES", "FigureWorkers", "draw_figure", "draw_saved_figure"]

FIGURES: tuple[tuple[str, str], ...] = (
    ("Rider torque tau_r and its estimate tau_r_hat (paper Figs. 11 and 14)", "plot_torque"),
    (
        "Handlebar angle theta_h against the virtual steer angle delta (Fig. 13, left)",
        "plot_tracking",
    ),
    ("Handlebar rate and the differentiator's estimate (Fig. 13 right, Fig. 17)", "plot_rate"),
    ("Estimated rider torque and motor torque N k_t i_m (Fig. 18)", "plot_motor_torque"),
    ("Virtual motorcycle: path, roll, speed, path error", "plot_motorcycle"),
    (
        "Spectra of the motor current and of theta_h - delta: a peak above the dotted line is a "
        "buzz the rider feels",
        "plot_spectrum",
    ),
)
"""The report's figures in their order: (caption, name of the function of
:mod:`motosim.plotting.closed_loop` that draws it)."""

# the order the workers take the figures in, the costliest first (log axes, four panels),
# so that the two processes end together
_COSTLIEST_FIRST = (
    "plot_spectrum",
    "plot_motorcycle",
    "plot_rate",
    "plot_torque",
    "plot_tracking",
    "plot_motor_torque",
)
# what the workers import, the buzz metric's cut-off (the spectra's line) included
_PRELOAD = ["motosim.report.figures", "motosim.plotting.closed_loop", "motosim.sim.metrics"]


def draw_figure(result: SimResult, name: str) -> str | None:
    """The figure ``name`` of :data:`FIGURES` drawn from ``result``, as base64 SVG
    (:func:`motosim.plotting.images.svg_base64`).

    Returns None when the result lacks the figure's signals. matplotlib is imported on the
    first figure.
    """
    from motosim.plotting import closed_loop
    from motosim.plotting.images import svg_base64

    try:
        figure = getattr(closed_loop, name)(result)
    except MotosimError:
        return None
    return svg_base64(figure)


@lru_cache(maxsize=1)
def _saved_result(folder: str, stamp: tuple[int, int]) -> SimResult:
    """The result saved in ``folder``, read once per process while its file is unchanged
    (``stamp``: the file's modification time [ns] and size [B], part of the key only)."""
    return load_result(folder)


def draw_saved_figure(folder: str, name: str) -> str | None:
    """:func:`draw_figure` on the result saved in ``folder``: a worker process's task."""
    path = Path(folder)
    stat = (path / "result.h5" if path.is_dir() else path).stat()
    return draw_figure(_saved_result(folder, (stat.st_mtime_ns, stat.st_size)), name)


def _ignore_interrupt() -> None:
    """A worker leaves Ctrl-C to the command, which stops it (:meth:`FigureWorkers.close`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


class FigureWorkers:
    """Processes that draw a report's figures, their imports done ahead of the first figure.

    Use it as a context manager around the run and its report; :meth:`close` stops the
    processes.

    Parameters
    ----------
    processes : int
        How many figures are drawn at once (default 2). With fewer than two cores, or no
        fork server on this platform, nothing is started and :meth:`draw` returns None.
    """

    def __init__(self, processes: int = 2) -> None:
        self._processes = processes
        self._pool: ProcessPoolExecutor | None = None
        self._context: Any = None
        if processes < 2 or (os.cpu_count() or 1) < 2:
            return
        if "forkserver" not in multiprocessing.get_all_start_methods():
            return
        from multiprocessing import forkserver

        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(_PRELOAD)
        try:
            forkserver.ensure_running()  # starts it and returns: it imports in the background
        except OSError:
            return
        self._context = context

    def draw(self, folder: Path, names: Sequence[str]) -> list[str | None] | None:
        """The base64 SVG of each figure of ``names`` drawn from the result in ``folder``
        (None for a figure whose signals the result lacks), in the order of ``names``.

        Returns None when the workers were not started or failed (the caller draws the
        figures itself); an error of a figure's own is raised here.
        """
        return self.start(folder, names)()

    def start(self, folder: Path, names: Sequence[str]) -> Callable[[], list[str | None] | None]:
        """:meth:`draw`, begun: the figures are handed to the workers and the function
        returned waits for them and returns what :meth:`draw` returns, so that the caller
        can do its own work in between."""
        if self._context is None:
            return lambda: None
        rank = {name: i for i, name in enumerate(_COSTLIEST_FIRST)}
        order = sorted(range(len(names)), key=lambda i: rank.get(names[i], len(rank)))
        futures: dict[int, Future[str | None]] = {}
        try:
            if self._pool is None:
                self._pool = ProcessPoolExecutor(
                    self._processes, mp_context=self._context, initializer=_ignore_interrupt
                )
            for i in order:
                futures[i] = self._pool.submit(draw_saved_figure, str(folder), names[i])
        except (OSError, RuntimeError):  # a worker lost (BrokenProcessPool is a RuntimeError)
            self._lost()
            return lambda: None

        def wait() -> list[str | None] | None:
            try:
                return [futures[i].result() for i in range(len(names))]
            except (OSError, RuntimeError):
                self._lost()
                return None

        return wait

    def _lost(self) -> None:
        """A worker was lost: the processes are stopped and the figures drawn in-process."""
        self.close()
        self._context = None

    def close(self) -> None:
        """Stop the worker processes and the fork server, and wait for them (so that their
        CPU time counts in the command's).

        The fork server is terminated rather than asked to stop: it reads the request only
        once its imports are done, which a command that ends before its report (a refused
        design, a failed run, Ctrl-C) would otherwise wait for.
        """
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._context is not None:
            from multiprocessing import forkserver

            server = forkserver._forkserver
            pid = getattr(server, "_forkserver_pid", None)
            stop = getattr(server, "_stop", None)  # else it ends with us
            if stop is not None:
                if pid is not None:
                    with contextlib.suppress(OSError):
                        os.kill(pid, signal.SIGTERM)
                stop()
            self._context = None

    def __enter__(self) -> "FigureWorkers":
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
