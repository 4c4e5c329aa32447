"""``motosim rt-check``, ``run`` and ``rig`` end to end, the rig in another process.

The cross-process tests run ``motosim rig`` and ``motosim run`` as two processes on
python-can's ``udp_multicast`` interface (multicast on this machine's loopback), as a lab
runs them in two terminals; they check the plumbing (frames both ways, result files,
Ctrl-C), not the timing, which ``bench/bench_rt.py`` measures.
"""

import itertools
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from live_rig import free_udp_port, wait_for_status
from rt_tables import safety_table

from motosim.cli.main import main
from motosim.io.results import load_result
from motosim.rt.config import load_realtime
from motosim.signals import RECORDED

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

SCENARIO = """
[scenario]
name = "rt_cli"
description = "square rider torque, the paper's K(s), 100 Hz status frames"
duration = 2.0

[rates]
measurement = 100.0

[rider]
kind = "torque"
profile = { kind = "square", low = -3.0, high = 3.0, period = 1.0, start = 0.2 }

[controller]
kind = "paper"
""" + safety_table(100)  # 1 s: these tests run on a busy machine without SCHED_FIFO


# a group of our own: the fast link hears only its group, so tests of other checkouts on
# this machine (python-can's default group) do not cross-talk with these
BUS = "udp_multicast:239.74.163.121"


def _main(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_rt_check_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = _main(capsys, "rt-check", "--rate", "1000", "--duration", "0.05", "--json")
    payload = json.loads(out)
    # the verdict against the targets sets the exit code (0 pass, 1 fail): a busy machine
    # may fail them in 50 periods
    assert code == (0 if payload["verdict"]["pass"] else 1)
    assert payload["units"] == "s" and payload["privileges"] == []
    timing = payload["timing"]
    assert timing["periods"] == 50 and timing["served"] + timing["missed"] == 50
    assert {"wake_p50", "wake_p99", "wake_p999", "wake_max"} <= set(timing)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "[realtime.safety] is missing"),
        ("[realtime.safety]\nmax_current = 1.0\n", "missing max_slew"),
        ("[realtime]\nbus = 1\n", "unknown key 'bus' in [realtime]"),
        (
            "[realtime]\nstatus_latency = -0.001\n" + safety_table(100),
            "[realtime] status_latency = -0.001 s; expected 0 to 1 s",
        ),
        (
            "[realtime]\nstatus_latency = '2 ms'\n" + safety_table(100),
            "status_latency = '2 ms': expected a number of seconds",
        ),
        (  # 9.8 ms and half of the 1 kHz loop's period: older than a 100 Hz frame period
            "[realtime]\nstatus_latency = 0.0098\n" + safety_table(100),
            "the stack accounts for up to one frame period (10 ms at 100 Hz)",
        ),
    ],
)
def test_run_refuses_bad_realtime_tables(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, text: str, message: str
) -> None:
    base = SCENARIO.split("[realtime.safety]")[0]
    path = tmp_path / "s.toml"
    path.write_text(base + text, encoding="utf-8")
    code = main(["run", str(path), "--bus", "virtual", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


EQUAL_RATES = "[rates]\nmeasurement = 100.0\ncontrol = 100.0"


def _with_latency(latency: str, rates: str = "") -> str:
    """SCENARIO with ``status_latency = latency`` and, given, ``rates`` for its [rates]."""
    text = SCENARIO.replace("[rates]\nmeasurement = 100.0", rates) if rates else SCENARIO
    base = text.split("[realtime.safety]")[0]
    return f"{base}[realtime]\nstatus_latency = {latency}\n" + safety_table(100)


@pytest.mark.parametrize(
    ("rates", "latency", "pace"),
    [
        ("", "-0.001", "clock"),
        # 9.8 ms and half of the 1 kHz loop's period: older than a 100 Hz frame period, and
        # at these rates run takes no other pace
        ("", "0.0098", "clock"),
        # one period per frame: run --pace bus reads the frame as it arrives, 10.1 ms old
        (EQUAL_RATES, "0.0101", "bus"),
    ],
)
def test_rig_refuses_the_status_latency_that_every_run_refuses(
    capsys: pytest.CaptureFixture[str], tmp_path: Path, rates: str, latency: str, pace: str
) -> None:
    # the rig reads the same scenario as run: it refuses a status_latency before it starts,
    # in run's line (for the pace that accepts the oldest frame at the scenario's rates)
    path = tmp_path / "s.toml"
    path.write_text(_with_latency(latency, rates), encoding="utf-8")
    out = str(tmp_path / "o")
    refused = []
    for argv in (
        ["run", str(path), "--bus", "virtual", "--out", out, "--pace", pace],
        ["rig", str(path), "--bus", "virtual", "--duration", "0.05"],
    ):
        code = main(argv)
        err = capsys.readouterr().err
        assert code == 2 and len(err.strip().splitlines()) == 1, (argv[0], err)
        refused.append(err)
    assert refused[0] == refused[1] and "status_latency" in refused[0]


def test_rig_keeps_a_status_latency_that_run_takes_paced_by_the_bus(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # 6 ms at 100 Hz control and frames: paced by its clock, run refuses the frame (6 ms and
    # half a 10 ms period: 11 ms old); paced by the frames (--pace bus) it takes it (6 ms),
    # so the rig, which serves either, starts
    path = tmp_path / "s.toml"
    path.write_text(_with_latency("0.006", EQUAL_RATES), encoding="utf-8")
    code = main(["run", str(path), "--bus", "virtual", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "and half a control period waiting for the clock, makes the status frame 11 ms" in err
    code = main(["rig", str(path), "--bus", "virtual", "--duration", "0.05", "--json"])
    out, err = capsys.readouterr()
    assert code == 0 and json.loads(out)["commands"] == 0, err


@pytest.mark.parametrize("command", ["run", "rig"])
def test_the_platform_file_and_address_are_parsed_once(
    command: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    # check_rt_options read the platform file and the address, then run and rig read them
    # again: the values it checked are the ones used
    import unittest.mock

    import motosim.cueing
    import motosim.rt.telemetry

    path = tmp_path / "s.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    address = f"127.0.0.1:{free_udp_port()}"
    argv = {
        "run": [
            "run",
            str(path),
            "--out",
            str(tmp_path / "o"),
            "--no-report",
            "--telemetry",
            "off",
        ],
        "rig": ["rig", str(path)],
    }[command] + ["--bus", "virtual", "--duration", "0.05", "--platform-udp", address]
    loads = unittest.mock.Mock(wraps=motosim.cueing.load_platform)
    parses = unittest.mock.Mock(wraps=motosim.rt.telemetry.parse_address)
    with (
        unittest.mock.patch.object(motosim.cueing, "load_platform", loads),
        unittest.mock.patch.object(motosim.rt.telemetry, "parse_address", parses),
    ):
        code = main(argv)
    err = capsys.readouterr().err
    assert code in (0, 3), err  # run: no drive on the bus, the watchdog's fault (exit 3)
    parsed = [call.args[0] for call in parses.call_args_list]  # and the rig's --telemetry
    assert loads.call_count == 1 and address in parsed and len(set(parsed)) == len(parsed)


def test_run_refuses_a_view_port_out_of_range(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    argv = ["run", str(path), "--bus", "virtual", "--out", str(tmp_path / "o"), "--view"]
    code = main([*argv, "--view-port", "70000"])
    err = capsys.readouterr().err
    assert code == 2 and "--view-port 70000; expected 0..65535" in err
    assert len(err.strip().splitlines()) == 1


def _udp_multicast() -> None:
    from motosim.errors import MotosimError
    from motosim.io.can import open_link

    try:
        open_link(BUS).close()
    except MotosimError as err:
        pytest.skip(f"udp_multicast is not available here: {err}")


def _run(path: Path, out: Path, *options: str) -> subprocess.Popen[str]:
    """``motosim run PATH --bus BUS --out OUT --no-report OPTIONS`` started."""
    return _motosim("run", str(path), "--bus", BUS, "--out", str(out), "--no-report", *options)


def _motosim(*argv: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "motosim.cli.main", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


@pytest.fixture
def rig(tmp_path: Path, request: pytest.FixtureRequest) -> object:
    _udp_multicast()
    path = tmp_path / "rt.toml"
    text = getattr(request, "param", SCENARIO)
    path.write_text(text, encoding="utf-8")
    telemetry = f"127.0.0.1:{free_udp_port()}"
    proc = _motosim(
        "rig",
        str(path),
        "--bus",
        BUS,
        "--duration",
        "120",
        "--json",
        "--telemetry",
        telemetry,
    )
    try:
        wait_for_status(BUS, 60.0)
        yield path, telemetry
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()


def test_run_against_the_rig_in_another_process(rig: tuple[Path, object], tmp_path: Path) -> None:
    path, telemetry = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--json", "--telemetry", str(telemetry))
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    payload = json.loads(stdout)
    assert payload["fault"] == "NONE" and payload["counters"]["status_frames"] >= 150
    # on the clock over the fast link: the wait's end and the bus read in compiled code
    assert payload["wait"] == "compiled" and payload["counters"]["bus_errors"] == 0
    assert payload["warm"] is True  # the stack warmed before each deadline (--warm on)
    result = load_result(out)
    # the link in use (--link fast, the default), in the summary and in the result
    assert payload["link"] == result.metadata["realtime"]["link"] == "fast"
    # one row schema: the columns of an offline run's result that a real-time run knows, in
    # their order (the stack's estimate and measurement, the current sent, the motorcycle)
    columns = ("t", *result.names)
    assert columns == tuple(name for name in RECORDED if name in columns)
    assert {"tau_r_hat", "theta_h_meas", "i_m", "tau_m", "delta", "phi", "x", "y"} <= set(columns)
    report = json.loads((out / "timing.json").read_text())
    timing = report["timing"]
    # one row per 1 kHz control period served (a missed deadline is skipped and counted)
    assert result.complete and result.t.size == timing["served"]
    # where the compute time went: four stages whose medians add up to about the compute,
    # and the stack's own time (timed inside the compiled period) within the control stage
    profile = report["profile"]
    assert list(profile) == ["read", "control", "send", "rest", "stack"]
    assert all(0.0 <= stage["p50"] <= stage["p99"] <= stage["max"] for stage in profile.values())
    stack = profile.pop("stack")
    assert sum(stage["max"] for stage in profile.values()) >= timing["compute_p50"]
    assert 0.0 < stack["p50"] < profile["control"]["p50"]
    # 2 s at 1 kHz, then the torque fades out over the 0.5 s fade_in (never a step to zero)
    assert timing["periods"] > 2000 and 2.4 < result.t[-1]
    assert result["i_m"][-1] == 0.0 and payload["state"] == "IDLE"
    # the buzz judged while the stack's command ran unfaded, not over the fade-out
    assert result.summary["buzz_current_p2p"] < 0.3 and result.summary["flag_oscillation"] == 0.0
    # offline, this scenario commands up to 12.7 mA and moves the handlebar by 0.045 rad,
    # and the estimate reaches 2.67 N*m of the rider's 3 N*m (motosim simulate, seed 0)
    assert np.max(np.abs(result["i_m"])) > 0.005
    assert np.ptp(result["theta_h_meas"]) > 0.02
    assert np.max(np.abs(result["tau_r_hat"])) > 2.0


def test_ctrl_c_fades_the_torque_out_and_closes_the_files(
    rig: tuple[Path, object], tmp_path: Path
) -> None:
    path, _ = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--duration", "60")
    staging = out.with_name(out.name + ".partial")  # made by the writer just before the loop
    end = time.monotonic() + 120
    while time.monotonic() < end and not staging.exists():
        time.sleep(0.1)
    time.sleep(3.0)  # about 3 s of the 60 s run
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "torque faded out" in stderr
    result = load_result(out)
    assert not result.complete and result.t.size > 500
    i = np.abs(result["i_m"])
    assert i[-1] == 0.0
    # the last half second fades: each current below the envelope times the clamp
    tail = i[-500:]
    envelope = np.linspace(1.0, 0.0, 501)[1:]
    assert np.all(tail <= envelope * 10.0 + 1e-9)


FALLING = SCENARIO.replace(
    'profile = { kind = "square", low = -3.0, high = 3.0, period = 1.0, start = 0.2 }',
    # a pure torque push: the arms' spring of the default grip would hold the steer against it
    'profile = { kind = "constant", value = 10.0 }\nhands = "off"',
).replace("duration = 2.0", "duration = 8.0")


@pytest.mark.parametrize("rig", [FALLING], indirect=True)
def test_a_fall_fades_the_torque_out_and_ends_the_run_with_exit_3(
    rig: tuple[Path, object], tmp_path: Path
) -> None:
    # A constant 10 N*m at the handlebar: offline, the motorcycle passes 45 deg of roll at
    # 3.45 s (motosim simulate, seed 0) and the run stops there, exit 3, its files closed
    # and flagged; the real-time run does the same, the torque faded out.
    path, _ = rig
    out = tmp_path / "run"
    proc = _motosim("run", str(path), "--bus", BUS, "--out", str(out), "--no-report")
    _, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 3, stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith("motosim: run failed: rt_cli: the motorcycle fell at t = "), stderr
    assert "deg, beyond 45 deg" in last and f"the result is in {out}, flagged" in last
    fell = float(last.split("fell at t = ")[1].split(" s")[0])
    result = load_result(out)  # closed whole, not partial
    assert 2.0 < fell < 6.0 and result.t[-1] < 8.0
    assert result.summary["complete"] == 0.0 and result.summary["flag_fall"] == 1.0
    assert "fell at t" in result.summary["failure"]
    after = result.t >= fell
    assert after.sum() == pytest.approx(500, abs=5)  # the 0.5 s fade-out, then the end
    assert result["i_m"][-1] == 0.0
    envelope = np.linspace(1.0, 0.0, after.sum() + 1)[1:]
    assert np.all(np.abs(result["i_m"][after]) <= envelope * 10.0 + 0.02)


SENSED = SCENARIO.replace(
    "[controller]",
    '[estimator]\nname = "torque_sensor"\n\n[sensor.torque]\nnoise = 0.05\n\n[controller]',
)


@pytest.mark.parametrize("rig", [SENSED], indirect=True)
def test_a_run_reads_the_rigs_torque_sensor(rig: tuple[Path, object], tmp_path: Path) -> None:
    # the rig in its own process fits the scenario's torque sensor and sends HB_TORQUE after
    # each 100 Hz status frame; the run's stack takes the rider's torque from it: the
    # estimate follows the square +/-3 N*m (the arms of the default relaxed grip add their
    # passive torque, the sensor 0.05 N*m of noise)
    path, _ = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--json")
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    counters = json.loads(stdout)["counters"]
    assert counters["torque_frames"] >= 150 and counters["status_frames"] >= 150
    result = load_result(out)
    inputs, _ = load_realtime(str(path))
    t, tau_hat = result.t, result["tau_r_hat"]
    profile = inputs.scenario.rider.profile.sample(t, inputs.tables)
    steps = t[np.flatnonzero(np.diff(profile)) + 1]
    settled = np.min(np.abs(t[:, None] - steps[None, :]), axis=1) > 0.05  # 50 ms from a step
    assert steps.size >= 2 and np.max(np.abs(profile)) == 3.0
    assert np.median(np.abs(tau_hat[settled] - profile[settled])) < 0.5


LANE_CHANGE = (
    SCENARIO.replace(
        'kind = "torque"\nprofile = { kind = "square", low = -3.0, high = 3.0, period = 1.0,'
        " start = 0.2 }",
        'kind = "virtual"\n'
        'path = { kind = "lane_change", offset = 3.5, length = 60.0, start = 20.0 }',
    )
    .replace("duration = 2.0", "duration = 4.0")
    .replace("[rates]\nmeasurement = 100.0", "")
)


@pytest.mark.parametrize("rig", [LANE_CHANGE], indirect=True)
def test_the_rigs_virtual_rider_steers_by_the_runs_state_stream(
    rig: tuple[Path, str], tmp_path: Path
) -> None:
    # the lane change of lane_change_20 moved to 20 m: at 20 m/s it spans 1 s to 4 s, and
    # offline the motorcycle is 3.46 m aside at 4 s (motosim simulate of this file, seed 0)
    path, telemetry = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--json", "--telemetry", telemetry)
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    stream = json.loads(stdout)["state_stream"]  # sent by the writer process, not the loop
    assert stream["sent"] > 100 and stream["lag_p50"] < 0.05
    # without the stream the rider holds 0 N*m and the motorcycle stays on y = 0; missed
    # deadlines on a busy machine slow the virtual motorcycle (each period advances it by
    # one period), so only the lane change under way is asserted here: the lock-step test in
    # test_rt_offline.py checks the trajectory
    assert load_result(out)["y"][-1] > 1.0


def _post(url: str, token: str, action: str) -> dict[str, object]:
    import urllib.request

    request = urllib.request.Request(
        f"{url}/api/control",
        data=json.dumps({"action": action}).encode(),
        headers={"Content-Type": "application/json", "X-Motosim-Token": token},
        method="POST",
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        answer: dict[str, object] = json.loads(response.read())
    return answer


def test_run_with_the_view_serves_live_rows_and_its_buttons_go_through_the_safety_stage(
    rig: tuple[Path, object], tmp_path: Path
) -> None:
    pytest.importorskip("uvicorn", reason="the view server is in the optional group view")
    pytest.importorskip("websockets", reason="the WebSocket client is in the optional group view")
    import re
    import urllib.request

    from websockets.sync.client import connect

    path, _ = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--duration", "60", "--view", "--view-port", "0")
    assert proc.stderr is not None
    match = None
    lines: list[str] = []
    while match is None:
        line = proc.stderr.readline()
        assert line, "".join(lines)
        lines.append(line)
        match = re.search(r"rider's view (http://127\.0\.0\.1:\d+)/\?token=(\S+)", line)
    url, token = match.group(1), match.group(2)
    with urllib.request.urlopen(f"{url}/api/info", timeout=10) as response:
        info = json.loads(response.read())
    assert info["replay"] is False and info["status"]["mode"] == "live"
    assert {"t", "x", "y", "psi", "phi", "delta", "v_x", "i_m"} <= set(info["names"])

    def rows_until(states: set[str], seconds: float, after: float = 0.0) -> list[list[float]]:
        got: list[list[float]] = []
        with connect(f"{url.replace('http', 'ws')}/ws/signals") as ws:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                message = json.loads(ws.recv(timeout=10))
                got += message["rows"]
                if got and got[-1][0] >= after and message["status"]["state"] in states:
                    return got
        pytest.fail(f"no rows in state {states} within {seconds} s")

    # the torque is off until Arm is pressed: the loop runs, records and feeds the view
    idle = rows_until({"idle"}, 60.0, after=0.5)
    assert len(idle) > 50 and all(b[0] > a[0] for a, b in itertools.pairwise(idle))
    assert _post(url, token, "arm")["ok"] is True
    rows_until({"running"}, 30.0)
    time.sleep(1.0)
    with pytest.raises(urllib.error.HTTPError):
        _post(url, "wrong-token", "stop")
    assert _post(url, token, "stop")["ok"] is True  # the path of Ctrl-C
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, "".join(lines) + stderr
    assert "torque faded out" in stderr
    result = load_result(out)
    i = np.abs(result["i_m"])
    armed = np.flatnonzero(i > 0.0)
    assert armed.size > 100 and armed[0] > 10  # no current before Arm, some after
    assert i[-1] == 0.0


PACED = SCENARIO.replace("[rates]\nmeasurement = 100.0", EQUAL_RATES)


def test_pace_bus_needs_the_control_rate_of_the_status_frames(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    path = tmp_path / "s.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    argv = ["run", str(path), "--bus", "virtual", "--out", str(tmp_path / "o"), "--pace", "bus"]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "--pace bus with control = 1000 Hz and measurement = 100 Hz; expected equal" in err


@pytest.mark.parametrize("rig", [PACED], indirect=True)
def test_run_paced_by_the_rigs_status_frames(rig: tuple[Path, str], tmp_path: Path) -> None:
    path, telemetry = rig
    out = tmp_path / "run"
    proc = _run(path, out, "--json", "--telemetry", telemetry, "--pace", "bus")
    stdout, stderr = proc.communicate(timeout=180)
    assert proc.returncode == 0, stderr
    payload = json.loads(stdout)
    timing = payload["timing"]
    assert payload["pace"] == "bus" and payload["fault"] == "NONE"
    # one period per status frame: 2 s of frames at 100 Hz, then the 0.5 s fade-out
    assert timing["served"] <= payload["counters"]["status_frames"]  # each on a frame
    assert timing["periods"] > 200 and load_result(out).complete
