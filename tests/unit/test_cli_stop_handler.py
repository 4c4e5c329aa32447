"""The one SIGINT handler of the real-time commands: counted, then a stop, then an E-stop."""

import pytest

from motosim.cli._common import StopHandler


class Target:
    def __init__(self) -> None:
        self.calls: list[str] = []

    def request_stop(self) -> None:
        self.calls.append("stop")

    def emergency_stop(self) -> None:
        self.calls.append("estop")


def test_presses_before_a_target_are_counted_and_checked() -> None:
    handler = StopHandler()
    handler.check()  # nothing pressed
    handler(2, None)
    with pytest.raises(KeyboardInterrupt):
        handler.check()


def test_an_aimed_handler_stops_then_emergency_stops() -> None:
    handler, target = StopHandler(), Target()
    handler.aim(target)
    handler(2, None)
    handler(2, None)
    handler(2, None)
    assert target.calls == ["stop", "estop", "estop"]
    handler.check()  # aimed: presses are the target's, never raised


def test_presses_before_the_aim_are_passed_on_and_release_raises() -> None:
    handler, target = StopHandler(), Target()
    handler(2, None)
    handler.aim(target)
    assert target.calls == ["stop"]
    handler.release()
    with pytest.raises(KeyboardInterrupt):
        handler(2, None)
