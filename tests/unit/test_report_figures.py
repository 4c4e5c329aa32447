"""The report's figures drawn in worker processes: the same report as drawn in-process."""

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from motosim.io.results import ResultWriter
from motosim.report import build_report
from motosim.report.figures import FigureWorkers, draw_saved_figure

NAMES = ("t", "tau_r", "tau_r_hat", "theta_h", "delta", "i_m", "theta_h_dot", "theta_h_dot_hat")


def _write(folder: Path, names: tuple[str, ...] = NAMES) -> None:
    t = np.arange(400) * 1e-3
    columns = [t] + [0.1 * (j + 1) * np.sin(7.0 * t + j) for j in range(1, len(names))]
    with ResultWriter(folder, names, {"scenario": {"name": "workers"}, "seed": 1}) as writer:
        writer.append(np.column_stack(columns))
        writer.close({})


def test_the_workers_draw_the_report_the_calling_process_draws(tmp_path: Path) -> None:
    _write(tmp_path)
    here = build_report(tmp_path).read_bytes()
    with FigureWorkers() as workers:
        assert build_report(tmp_path, workers=workers).read_bytes() == here  # byte for byte
        # the figure this result lacks the signals of (the motorcycle's) is None, in order
        drawn = workers.draw(tmp_path, ["plot_motorcycle", "plot_torque"])
    if drawn is None:  # no fork server or one core here: the figures were drawn in-process
        pytest.skip("no worker processes on this machine")
    assert drawn[0] is None
    assert drawn[1] == draw_saved_figure(str(tmp_path), "plot_torque")


def test_without_workers_the_figures_are_drawn_here(tmp_path: Path) -> None:
    _write(tmp_path)
    workers = FigureWorkers(processes=1)  # one process: nothing to gain, nothing started
    assert workers.draw(tmp_path, ["plot_torque"]) is None
    text = build_report(tmp_path, workers=workers).read_text(encoding="utf-8")
    assert text.count('src="data:image/svg+xml;base64,') == 5
    workers.close()


def test_a_report_after_a_rewritten_result_is_drawn_from_the_new_one(tmp_path: Path) -> None:
    # a worker keeps the last result it read while its file is unchanged, not after
    folder = tmp_path / "run"
    _write(folder)
    assert draw_saved_figure(str(folder), "plot_tracking") is not None
    shutil.rmtree(folder)
    _write(folder, NAMES[:3])  # no handlebar angle any more
    assert draw_saved_figure(str(folder), "plot_tracking") is None


def test_closing_does_not_wait_for_the_fork_servers_imports(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # A command that ends before its report (a refused design, a failed run) closes the
    # workers while the fork server may still import matplotlib: close() ends it then, and
    # does not wait for its imports. Here they never end (a module that sleeps for an hour):
    # a close() that waited would hang, and the thread below would still be alive.
    import multiprocessing
    import os
    import sys
    import threading

    from motosim.report import figures

    if (os.cpu_count() or 1) < 2 or "forkserver" not in multiprocessing.get_all_start_methods():
        pytest.skip("no fork server on this machine: nothing is started")
    (tmp_path / "slow_to_import.py").write_text("import time\ntime.sleep(3600)\n")
    # the fork server is a new interpreter: it finds the module on its PYTHONPATH
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(tmp_path), *sys.path]))
    monkeypatch.setattr(figures, "_PRELOAD", ["slow_to_import"])
    workers = FigureWorkers()
    closing = threading.Thread(target=workers.close, daemon=True)
    closing.start()
    closing.join(timeout=60.0)
    assert not closing.is_alive(), "close() waited for the fork server's imports"


def test_the_workers_import_matplotlib_without_the_numerical_stack() -> None:
    # the fork server imports these while the run goes on, on the other core: the compiled
    # models (numba) and SciPy would double the time before the first figure can start
    script = (
        "import sys; from motosim.report.figures import _PRELOAD\n"
        "for name in _PRELOAD: __import__(name)\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & {'numba', 'scipy', 'llvmlite'}))"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-500:]
    assert done.stdout.strip() == "[]"
