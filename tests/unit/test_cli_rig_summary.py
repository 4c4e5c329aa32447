"""The rig's printed summary says what its platform twin did.

The motion-cueing guide: ``motosim rig ... --platform-udp HOST:PORT`` "reports datagrams,
losses and angles"; the text summary printed only the handlebar's line (the JSON had them).
"""

from motosim.cli.rig import platform_line


def test_the_platform_twin_line_names_datagrams_losses_and_angles() -> None:
    twin = {
        "datagrams": 206,
        "can": False,
        "lost": 3,
        "late": 1,
        "bad": 0,
        "watchdog_timeouts": 1,
        "achieved_deg": [4.25, -0.5, 1.0],
    }
    line = platform_line(twin)
    assert line.startswith("platform: 206 datagrams taken (3 lost, 1 late, 0 bad)")
    assert "roll 4.25, pitch -0.50, yaw 1.00 deg" in line
    assert "PF_COMMAND frames taken" in platform_line(twin | {"can": True})
