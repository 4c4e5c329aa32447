"""The rider's view and the dashboard of ``motosim run --view``, served by the recorder.

:class:`ViewSink` is the :class:`~motosim.rt.recorder.LiveSink` the recorder process feeds:
it is built in the command's process (picklable: the road, the token, the port) and starts
its server in the recorder's, where the rows are drained, so that serving the view cannot
delay the loop.
"""

import argparse
import threading
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from motosim.errors import MotosimError
from motosim.params.checks import short_repr
from motosim.rt.recorder import Control

if TYPE_CHECKING:
    from motosim.rt.safety import SafetyLimits
    from motosim.sim import RunInputs

__all__ = ["ViewSink", "view_sink"]

Array = NDArray[np.float64]


class _LoopControl:
    """The view's arm/stop, sent to the loop's process; the state read from the loop's rows."""

    def __init__(self, conn: Any) -> None:
        self._conn = conn
        self._lock = threading.Lock()
        self.current = "waiting"

    def _send(self, control: Control) -> None:
        with self._lock:
            try:
                self._conn.send(control)
            except OSError:  # the loop has ended
                pass

    def arm(self) -> None:
        """Arm: the loop enables the safety stage (a fade-in)."""
        self._send(Control.ARM)

    def stop(self) -> None:
        """Stop as Ctrl-C does: the torque fades out and the run ends."""
        self._send(Control.STOP)

    def state(self) -> str:
        """The safety stage's state in the last row drained: ``waiting`` before the first,
        then ``idle``, ``fade_in``, ``running``, ``stopping`` or ``fault``."""
        return self.current


class ViewSink:
    """The live view of a run: its road, title, duration [s], port and access token."""

    def __init__(
        self,
        token: str,
        port: int,
        road: tuple[Array, Array],
        duration: float,
        title: str,
        watchdog_periods: int,
    ) -> None:
        self.token = token
        self.port = port
        self.road = road
        self.duration = duration
        self.title = title
        self.watchdog_periods = watchdog_periods
        self._server: Any = None
        self._control: _LoopControl | None = None
        self._ring: Any = None
        self._rows: Any = None
        self._state_col = -1

    def start(self, names: tuple[str, ...], controls: Any) -> str:
        """Serve the view of the loop's columns ``names``; its URL (in the recorder)."""
        from motosim.io.telemetry import TelemetryRing
        from motosim.rt.stack import RESULT_SIGNALS
        from motosim.view.app import ServerThread, create_app
        from motosim.view.feeds import LiveFeed, Road
        from motosim.view.live import LoopRows

        self._state_col = names.index("state")
        self._rows = LoopRows(names, RESULT_SIGNALS)
        self._ring = TelemetryRing(self._rows.names, capacity=1 << 15)  # 32 s at 1 kHz
        self._control = _LoopControl(controls)
        feed = LiveFeed(self._ring, self._control, self.duration, self.watchdog_periods)
        app = create_app(feed, Road(*self.road), token=self.token, title=self.title)
        self._server = ServerThread(app, "127.0.0.1", self.port).start()
        url: str = self._server.url
        return url

    def push(self, rows: Array, block: Array) -> None:
        """The loop's rows drained and their result rows, into the view's ring."""
        from motosim.rt.safety import State

        assert self._control is not None
        self._ring.push_block(self._rows.rows(rows, block))
        self._control.current = State(int(rows[-1, self._state_col])).name.lower()

    def stop(self) -> None:
        """Stop serving."""
        if self._server is not None:
            self._server.stop()
            self._server = None


def view_sink(
    args: argparse.Namespace, inputs: "RunInputs", duration: float, limits: "SafetyLimits"
) -> ViewSink:
    """Check ``--view-port`` and the optional group; the view along the scenario's path."""
    from motosim.view.app import _need_starlette, new_token
    from motosim.view.feeds import road_from_xy

    if not 0 <= args.view_port < 65536:
        raise MotosimError(f"--view-port {short_repr(args.view_port)}; expected 0..65535")
    _need_starlette()
    sc = inputs.scenario
    length = max(duration * sc.motorcycle.speed, 10.0)
    if sc.rider.path is not None:
        built = sc.rider.path.build(length)
        road = road_from_xy(built.x, built.y)
    else:
        road = road_from_xy(np.array([0.0, length]), np.zeros(2))
    return ViewSink(
        new_token(), args.view_port, (road.x, road.y), duration, sc.name, limits.watchdog_periods
    )
