"""The fast udp_multicast link against python-can's own, and the loop over socketcan vcan.

:class:`motosim.io.can.UdpMulticastLink` must put on the wire exactly what python-can's
``udp_multicast`` bus puts there (``can.interfaces.udp_multicast.utils.pack_message``) and
read what it sends, so that a ``motosim rig`` or any python-can tool on the same group sees
the same frames. The socketcan test runs ``motosim rig`` and ``motosim run`` as two processes
on a virtual CAN device (``vcan0``) where the kernel has one.
"""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("can", reason="python-can is in the rt and dev dependency groups")
pytest.importorskip("cantools", reason="cantools is in the rt and dev dependency groups")

import can
from can.interfaces.udp_multicast.utils import pack_message
from rt_tables import safety_table

from motosim.errors import MotosimError
from motosim.io.can import CanLink, UdpMulticastLink, open_link
from motosim.io.results import load_result


@pytest.mark.parametrize("frame_id", [0x010, 0x07F, 0x080, 0x0FF, 0x100, 0x101, 0x7FF])
@pytest.mark.parametrize("length", [1, 2, 8])
def test_the_bytes_sent_are_python_cans_own_packing(frame_id: int, length: int) -> None:
    data = bytes(range(0xA0, 0xA0 + length))
    before, after = UdpMulticastLink._template(frame_id, length)
    expected = pack_message(can.Message(arbitration_id=frame_id, data=data, is_extended_id=False))
    assert before + data + after == expected


def _links() -> tuple[UdpMulticastLink, CanLink]:
    try:
        fast, slow = open_link("udp_multicast"), open_link("udp_multicast", fast=False)
    except MotosimError as err:
        pytest.skip(f"udp_multicast is not available here: {err}")
    assert isinstance(fast, UdpMulticastLink) and isinstance(slow, CanLink)
    return fast, slow


def _frames(
    link: UdpMulticastLink | CanLink, wanted: set[int], count: int = 3
) -> list[tuple[int, bytes]]:
    got = []
    end = time.monotonic() + 5.0
    while time.monotonic() < end and len(got) < count:
        frame = link.receive(0.1)
        if frame is not None and frame[0] in wanted:  # other users of the group are ignored
            got.append(frame)
    return got


def test_the_fast_link_and_python_can_read_each_others_frames() -> None:
    fast, slow = _links()
    try:
        sent = [(0x101, bytes([1, 2, 3, 4, 5, 6, 7, k])) for k in range(3)]
        for frame in sent:
            fast.send(*frame)
        assert _frames(slow, {0x101}) == sent
        back = [(0x100, bytes([9, k])) for k in range(3)]
        for frame in back:
            slow.send(*frame)
        assert _frames(fast, {0x100}) == back
    finally:
        fast.close()
        slow.close()


def test_the_fast_link_drops_its_own_frames_in_the_kernel() -> None:
    # multicast loops back to every socket of the group on this machine, the sender's too:
    # python-can reads its own frames back; the fast link sends from a port of its own and
    # its BPF filter drops that port's datagrams before they are queued (Linux)
    fast, slow = _links()
    try:
        slow.send(0x7FE, b"\x01")
        fast.send(0x7FF, b"\x00")
        assert _frames(slow, {0x7FE, 0x7FF}, 2) == [(0x7FE, b"\x01"), (0x7FF, b"\x00")]
        if not fast.own_filtered:
            pytest.skip("no SO_ATTACH_FILTER here: the fast link reads its frames back")
        assert _frames(fast, {0x7FE, 0x7FF}, 2) == [(0x7FE, b"\x01")]
    finally:
        fast.close()
        slow.close()


SCENARIO = (Path(__file__).parent / "test_rt_cli.py").read_text(encoding="utf-8")
SCENARIO = SCENARIO.split('SCENARIO = """', 1)[1].split('"""', 1)[0] + safety_table(100)


def _vcan() -> str:
    """The name of an up virtual CAN device, or skip with the reason."""
    if not hasattr(socket, "AF_CAN"):
        pytest.skip("this platform's Python has no AF_CAN sockets (socketcan is Linux only)")
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
    except OSError as err:
        pytest.skip(f"this kernel has no CAN sockets ({err.strerror}): no vcan test here")
    name = os.environ.get("MOTOSIM_VCAN", "vcan0")
    if not Path(f"/sys/class/net/{name}").exists():
        pytest.skip(
            f"no {name}: create it with 'ip link add dev {name} type vcan; ip link set {name} up'"
            " (root; modprobe vcan first if the module is not loaded)"
        )
    return name


def test_run_against_the_rig_over_socketcan_vcan(tmp_path: Path) -> None:
    name = _vcan()
    path = tmp_path / "rt.toml"
    path.write_text(SCENARIO, encoding="utf-8")
    bus = f"socketcan:{name}"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    motosim = [sys.executable, "-m", "motosim.cli.main"]
    rig = subprocess.Popen(
        [*motosim, "rig", str(path), "--bus", bus, "--duration", "120", "--telemetry", "off"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    try:
        with open_link(bus) as link:  # the rig is up when its status frames come
            end = time.monotonic() + 60.0
            while time.monotonic() < end and (link.receive(0.1) or (0,))[0] != 0x101:
                pass
        out = tmp_path / "run"
        run = subprocess.run(
            [
                *motosim,
                "run",
                str(path),
                "--bus",
                bus,
                "--out",
                str(out),
                "--json",
                "--no-report",
                "--telemetry",
                "off",
            ],
            capture_output=True,
            text=True,
            env=env,
            timeout=180,
        )
    finally:
        rig.send_signal(signal.SIGINT)
        try:
            rig.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            rig.kill()
    assert run.returncode == 0, run.stderr
    payload = json.loads(run.stdout)
    assert payload["fault"] == "NONE" and payload["counters"]["status_frames"] >= 150
    assert load_result(out).complete


def test_the_fast_link_hears_only_its_own_group() -> None:
    # a socket bound to the port gets every group joined on the machine unless
    # IP(V6)_MULTICAST_ALL is off (Linux ip(7), ipv6(7)); the fast link turns it off
    fast, slow = _links()
    fast.close()
    try:
        other = open_link("udp_multicast:ff15:7079:7468:6f6e:6465:6d6f:6d63:7777", fast=False)
        ours = open_link("udp_multicast")
    except MotosimError as err:
        pytest.skip(f"a second multicast group is not available here: {err}")
    try:
        other.send(0x7FE, b"\x01")
        slow.send(0x7FD, b"\x02")
        assert _frames(ours, {0x7FD, 0x7FE}, 2) == [(0x7FD, b"\x02")]
    finally:
        for link in (other, ours, slow):
            link.close()
