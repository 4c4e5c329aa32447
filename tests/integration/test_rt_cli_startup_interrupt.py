"""Ctrl-C while ``motosim run`` starts (the stack loaded and compiled, 10-15 s): the run does
not start.

numba and llvmlite call back into Python from C while they load and link compiled code
(``ExecutionEngine._raw_object_cache_notify`` among others); a KeyboardInterrupt raised in
such a callback is printed as "Exception ignored" and lost, and the run went on to drive the
handlebar for its whole duration. The test presses Ctrl-C from inside a ctypes callback, as
the signal lands there, while the stack is built.
"""

import ctypes
import os
import signal
from collections.abc import Iterator
from multiprocessing import shared_memory
from pathlib import Path

import pytest

import motosim.sim
from motosim.cli.main import main

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"

pytest.importorskip("can", reason="motosim run needs the rt group (python-can)")


@pytest.fixture
def python_sigint() -> Iterator[None]:
    """Python's own Ctrl-C handler for the test (a test runner started in the background
    inherits SIGINT ignored)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _press_ctrl_c_inside_a_c_callback() -> None:
    def callback() -> None:
        os.kill(os.getpid(), signal.SIGINT)
        for _ in range(1000):  # Python runs the signal's handler here, inside the callback
            pass

    prototype = ctypes.CFUNCTYPE(None)
    ctypes.CFUNCTYPE(None, prototype)(lambda f: f())(prototype(callback))


def test_ctrl_c_while_the_stack_is_built_stops_the_run(
    python_sigint: None,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    build_stack = motosim.sim.build_stack

    def interrupted_build(*args: object, **kwargs: object) -> object:
        _press_ctrl_c_inside_a_c_callback()
        return build_stack(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(motosim.sim, "build_stack", interrupted_build)
    out = tmp_path / "run"
    code = main(
        [
            "run",
            str(SCENARIOS / "realtime_square.toml"),
            "--bus",
            "virtual",
            "--out",
            str(out),
            "--duration",
            "2",
            "--no-report",
            "--telemetry",
            "off",
            "--no-cache",  # the stack built here, not read from the design cache
        ]
    )
    err = capsys.readouterr().err
    assert code == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert not out.exists()  # stopped before the loop: no run, no torque


def test_ctrl_c_once_the_runner_is_built_releases_its_shared_ring(
    python_sigint: None,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    import motosim.rt.run

    runner_class = motosim.rt.run.RealtimeRunner
    names: list[str] = []

    def interrupted_runner(*args: object, **kwargs: object) -> object:
        runner = runner_class(*args, **kwargs)  # type: ignore[arg-type]
        names.append(runner.ring.handle.name)
        _press_ctrl_c_inside_a_c_callback()
        return runner

    monkeypatch.setattr(motosim.rt.run, "RealtimeRunner", interrupted_runner)
    code = main(
        [
            "run",
            str(SCENARIOS / "realtime_square.toml"),
            "--bus",
            "virtual",
            "--out",
            str(tmp_path / "run"),
            "--duration",
            "2",
            "--no-report",
            "--telemetry",
            "off",
        ]
    )
    assert code == 130, capsys.readouterr().err
    with pytest.raises(FileNotFoundError):  # unlinked, not left to the resource tracker
        shared_memory.SharedMemory(name=names[0])


def test_ctrl_c_while_the_rig_is_built_stops_it(
    python_sigint: None, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import motosim.rt.rig

    rig_class = motosim.rt.rig.VirtualRig

    def interrupted_rig(*args: object, **kwargs: object) -> object:
        _press_ctrl_c_inside_a_c_callback()
        return rig_class(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(motosim.rt.rig, "VirtualRig", interrupted_rig)
    code = main(
        [
            "rig",
            str(SCENARIOS / "realtime_square.toml"),
            "--bus",
            "virtual",
            "--duration",
            "5",
            "--json",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 130, err
    assert out == "" and "interrupted" in err  # stopped before its first tick
