"""Every command stops on SIGTERM and SIGHUP as on Ctrl-C, and never leaves a file half written.

A lab's process manager, ``timeout`` or a closed terminal stops a command with SIGTERM or
SIGHUP. Before, only a result writer's ``with`` block turned them into Ctrl-C: any other
command, or one still starting, was killed at once (exit -15), and a file being written by
``excite``, ``estimate``, ``report`` or ``telemetry`` was left truncated under its own name.
Each child here is ``python -m motosim``, the command line as a lab starts it.
"""

import os
import signal
import subprocess
import sys
import threading
import time
import unittest.mock
from pathlib import Path
from typing import Any

import pytest

from motosim.cli.main import main
from motosim.io.files import FolderLock, lock_file


def _motosim(*argv: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "motosim", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


@pytest.mark.parametrize("stop", [signal.SIGTERM, signal.SIGHUP])
def test_a_stop_signal_while_a_command_computes_is_exit_130_as_ctrl_c(
    tmp_path: Path, stop: signal.Signals
) -> None:
    out = tmp_path / "design.toml"
    child = _motosim("design", "--out", str(out))  # several seconds of optimisation
    assert child.stderr is not None and child.stderr.readline().startswith("designing for")
    child.send_signal(stop)
    _, err = child.communicate(timeout=60)
    assert child.returncode == 130, err  # was -15 (-1 for SIGHUP): killed, nothing said
    assert err == "motosim: interrupted\n"
    assert list(tmp_path.iterdir()) == []


def test_sigterm_while_excite_replaces_a_log_keeps_the_previous_one(tmp_path: Path) -> None:
    out = tmp_path / "excite.csv"
    out.write_text("t,i_cmd\n0.0,0.0\n", encoding="utf-8")
    child = _motosim(
        "excite", "--duration", "300", "--rate", "1000", "--out", str(out), "--overwrite"
    )
    deadline = time.monotonic() + 60.0
    while not any(p.name.endswith(".tmp") for p in tmp_path.iterdir()):  # writing
        assert child.poll() is None and time.monotonic() < deadline, child.communicate()
        time.sleep(0.01)
    child.send_signal(signal.SIGTERM)
    _, err = child.communicate(timeout=60)
    if child.returncode == 0:  # it finished writing first: the new log, whole
        pytest.skip("the log was written before the signal arrived")
    assert child.returncode == 130 and err.endswith("motosim: interrupted\n"), err
    # the old log whole, no new one cut mid-row under the log's own name
    assert out.read_text(encoding="utf-8") == "t,i_cmd\n0.0,0.0\n"
    assert [p.name for p in tmp_path.iterdir()] == ["excite.csv"]


def test_a_stop_signal_after_the_command_ends_the_process_with_its_code() -> None:
    """The interpreter's exit after the command must neither turn a finished run into exit
    -15 nor hang on a stop signal: it leaves at once with the command's code, its output
    flushed."""
    code = (
        "import os, signal, sys, time\n"
        "from motosim.cli.main import main\n"
        "sys.argv = ['motosim', '--version']\n"
        "code = main()\n"
        "print('done', code, end='')\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(30)\n"
        "print('not reached')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and done.stdout.splitlines()[-1] == "done 0", done
    # called with its words (a test, a script) main leaves the handlers as they were
    assert main(["--version"]) == 0
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL


@pytest.mark.parametrize("ignored", [True, False])
def test_a_hangup_stops_a_command_unless_started_with_nohup(ignored: bool) -> None:
    """SIGHUP (a closed terminal) stops a command as Ctrl-C does; started under ``nohup`` (SIGHUP
    ignored) the command keeps running, as before motosim handled the signal."""
    code = (
        "import os, signal, time\n"
        f"if {ignored}: signal.signal(signal.SIGHUP, signal.SIG_IGN)\n"
        "from motosim.cli.main import _stop_signals_as_ctrl_c\n"
        "with _stop_signals_as_ctrl_c():\n"
        "    os.kill(os.getpid(), signal.SIGHUP)\n"
        "    time.sleep(0.5)\n"
        "    print('kept running')\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    if ignored:
        assert done.returncode == 0 and done.stdout.strip() == "kept running", done
    else:
        assert done.returncode != 0 and "KeyboardInterrupt" in done.stderr, done


def _small_campaign(folder: Path) -> Path:
    (folder / "base.toml").write_text(
        '[scenario]\nname = "base"\nduration = 0.2\n[rider]\nkind = "torque"\n'
        'profile = { kind = "constant", value = 1.0 }\n[controller]\nkind = "paper"\n',
        encoding="utf-8",
    )
    campaign = folder / "c.toml"
    campaign.write_text(
        '[campaign]\nname = "c"\nscenario = "base.toml"\nsampling = "grid"\nseed = 1\n'
        '[factors]\n"handlebar.inertia_factor" = [0.9, 1.1]\n',
        encoding="utf-8",
    )
    return campaign


def test_a_campaign_holds_its_folder_until_its_report_is_written(tmp_path: Path) -> None:
    # as simulate's: the lock was released before the report was built from the folder
    import fcntl

    import motosim.report.campaign

    campaign = _small_campaign(tmp_path)
    out = tmp_path / "out"
    locked: list[bool] = []
    real = motosim.report.campaign.build_campaign_report

    def build_campaign_report(folder: Any) -> Any:
        fd = os.open(lock_file(out), os.O_RDWR)  # as another instance tries it
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            locked.append(False)
        except BlockingIOError:
            locked.append(True)
        finally:
            os.close(fd)
        return real(folder)

    with unittest.mock.patch.object(
        motosim.report.campaign, "build_campaign_report", build_campaign_report
    ):
        assert main(["campaign", str(campaign), "--out", str(out), "--jobs", "1"]) == 0
    assert locked == [True] and (out / "report.html").is_file()
    assert not lock_file(out).exists()


def test_a_campaign_under_a_read_only_parent_is_refused_in_one_line(tmp_path: Path) -> None:
    # its lock is beside --out (.out.lock), as every command's, so that a campaign and a
    # simulate of the same folder exclude each other: a read-only parent is refused
    campaign = _small_campaign(tmp_path)
    parent = tmp_path / "shared"
    out = parent / "out"
    out.mkdir(parents=True)
    parent.chmod(0o555)
    try:
        if os.access(parent, os.W_OK):
            pytest.skip("running as a user who writes anywhere (root)")
        argv = ["campaign", str(campaign), "--out", str(out), "--no-report", "--jobs", "1"]
        done = subprocess.run(
            [sys.executable, "-m", "motosim", *argv], capture_output=True, text=True, check=False
        )
        assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
        assert "cannot create the lock" in done.stderr and "nothing was written" in done.stderr
        assert list(out.iterdir()) == []
    finally:
        parent.chmod(0o755)


def test_a_campaign_on_a_folder_another_instance_writes_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    campaign = _small_campaign(tmp_path)
    out = tmp_path / "out"
    argv = ["campaign", str(campaign), "--out", str(out), "--no-report", "--jobs", "1"]
    with FolderLock(out):  # another instance, running or resuming the campaign
        code = main(argv)
    err = capsys.readouterr().err
    # was: both ran every run into the same parts and manifest (same temporary names)
    assert code == 2 and err.count("\n") == 1, err
    assert f"another run (pid {os.getpid()}) is writing this result" in err
    assert not out.exists()
    assert main(argv) == 0  # once it has ended


def test_a_campaign_and_a_simulate_of_one_folder_exclude_each_other(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # both take the one lock of the folder: were a simulate to lock beside --out, its
    # publishing rename would replace the whole folder, the campaign's manifest and parts
    # with it, while the campaign said it had succeeded
    import numpy as np

    import motosim.campaign.execute
    from motosim.io.results import ResultWriter

    campaign = _small_campaign(tmp_path)
    out = tmp_path / "out"
    argv = ["campaign", str(campaign), "--out", str(out), "--no-report", "--jobs", "1"]
    with ResultWriter(out, ("t", "phi"), {}) as writer:  # a simulate writing --out
        writer.append(np.array([[0.0, 0.1]]))
        assert main(argv) == 2
        writer.close()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"another run (pid {os.getpid()}) is writing" in err, err
    assert sorted(p.name for p in out.iterdir()) == ["result.csv", "result.h5"]

    # the reverse: a simulate while the campaign writes --out (before it has a file there)
    other = tmp_path / "other"
    scenario = tmp_path / "base.toml"
    codes: list[int] = []
    real = motosim.campaign.execute.ResultStore

    def simulate() -> None:
        codes.append(main(["simulate", str(scenario), "--out", str(other), "--no-report"]))

    def store(*args: Any, **kwargs: Any) -> Any:
        # another thread, as another process: the campaign's thread would share its lock
        thread = threading.Thread(target=simulate)
        thread.start()
        thread.join()
        return real(*args, **kwargs)

    with unittest.mock.patch.object(motosim.campaign.execute, "ResultStore", store):
        assert main([*argv[:3], str(other), *argv[4:]]) == 0
    err = capsys.readouterr().err
    assert codes == [2] and f"another run (pid {os.getpid()}) is writing" in err, err
    assert (other / "manifest.json").is_file() and (other / "parts").is_dir()
