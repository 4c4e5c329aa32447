"""The view's web server: the rider's view, the dashboard, their WebSockets and the controls.

One Starlette application (https://www.starlette.io) per feed, served by uvicorn
(https://www.uvicorn.org), both from the optional group ``view``:

- ``GET /`` the rider's view (three.js, vendored under ``static/``: nothing is fetched from
  the internet), ``GET /dashboard`` the live plots;
- ``GET /api/info`` signal names and units, the road, the status;
- ``WS /ws/pose`` the newest pose, speed and steer as soon as the feed has a new row (at most
  ``pose_rate``, 120 Hz), JSON; when the feed has the loop's clock (``t_clock``), the time
  the loop wrote the row (``clock``: the deadline plus the wake-up latency and compute time)
  and its deadline (``deadline``) on that clock [s]. The page sends ``{"ping": ms}``
  (answered ``{"pong": ms, "server": s}``, the server's monotonic clock) and
  ``{"frames": [[sample, drawn], ...]}``: for each animation frame, the loop-clock time of
  the sample it drew and when it drew it, on the same clock [s];
- ``GET /api/replay`` a replay's whole run, its dashboard signals (at most 4000 rows), which
  the dashboard of a replay plots at once, a cursor at the replay time;
- ``GET /api/lag`` those frames summarised: the view's lag behind the loop and its frame rate;
- ``WS /ws/signals`` new rows of the dashboard's signals at ``signal_rate`` (30 Hz), JSON;
- ``POST /api/control`` arm, stop (and for a replay: seek, rate), only with the run's token
  in the ``X-Motosim-Token`` header (a custom header also keeps other web sites out: a
  browser sends it cross-origin only after a CORS preflight, which this server never grants).

The server binds to 127.0.0.1 unless told otherwise; reading is open to whoever can reach
it, changing the run needs the token. Every response says ``Cross-Origin-Opener-Policy:
same-origin`` and ``Cross-Origin-Embedder-Policy: require-corp``: the pages are then
cross-origin isolated, which lets the rider's view read the newest pose from a worker's
shared memory (https://web.dev/articles/coop-coep).
"""

from __future__ import annotations

import asyncio
import json
import math
import secrets
import threading
import time
from collections import deque
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from motosim.errors import MotosimError
from motosim.signals import SIGNALS
from motosim.view.feeds import Feed, ReplayFeed, Road

if TYPE_CHECKING:
    from starlette.applications import Starlette
    from starlette.requests import Request
    from starlette.responses import Response
    from starlette.websockets import WebSocket

__all__ = ["DASHBOARD_SIGNALS", "STATIC", "LagLog", "ServerThread", "create_app", "new_token"]

STATIC: Final = Path(__file__).parent / "static"
"""The page files and the vendored three.js build."""

DASHBOARD_SIGNALS: Final = (
    "t",
    "tau_r",
    "tau_r_hat",
    "delta",
    "theta_h",
    "phi",
    "v_x",
    "e_y",
    "i_m",
    "period",
    "compute",
    "wake",
    "missed",
    "state",
    "fault",
    "phi_s",
    "theta_s",
    "psi_s",
    "phi_vis",
)
"""The signals the dashboard plots (those the feed has): the rider's torque and its estimate,
steer and handlebar, roll, speed, the real-time loop's timing and safety codes
(:data:`motosim.view.live.LOOP_VIEW_SIGNALS`), the platform commands of :mod:`motosim.cueing`."""

_POSE: Final = ("t", "x", "y", "psi", "phi", "delta", "v_x", "theta_h", "theta")
_DASHBOARD_RATE: Final = 200.0  # Hz, rows per second kept for the plots
_REPLAY_POINTS: Final = 4000  # rows of a whole replayed run sent to the dashboard
_PEAKS: Final = ("period", "compute", "wake")  # decimated by their maximum, not a sample
_UNITS: Final = {
    "t_clock": "s",
    "wake": "s",
    "compute": "s",
    "period": "s",
    "missed": "1",
    "state": "1",
    "fault": "1",
}
_POLL: Final = 0.002  # s, how often /ws/pose looks for a new row
_HEARTBEAT: Final = 0.25  # s, the longest /ws/pose stays silent (the status still changes)


class LagLog:
    """The frames the rider's view reports: which sample each one drew, and when.

    Both times are on the loop's clock (the machine's monotonic clock) [s]; the page maps its
    own clock onto it with the ping of ``/ws/pose``. The lag of a frame is the time it was
    drawn minus the loop's time of the sample it drew.

    Parameters
    ----------
    capacity : int
        Frames kept (the newest).

    Examples
    --------
    >>> log = LagLog()
    >>> log.add([[10.0, 10.02], [10.016, 10.036], [10.033, 10.053]])
    3
    >>> s = log.summary(); round(s["p50_ms"], 3), round(s["fps"], 1)
    (20.0, 60.6)
    """

    def __init__(self, capacity: int = 1 << 15) -> None:
        self._frames: deque[tuple[float, float]] = deque(maxlen=capacity)
        self._lock = threading.Lock()

    def add(self, frames: object) -> int:
        """Keep the ``[sample, drawn]`` pairs of finite numbers in ``frames``; how many."""
        if not isinstance(frames, list):
            return 0
        kept = 0
        with self._lock:
            for pair in frames[:10_000]:
                if (
                    isinstance(pair, list)
                    and len(pair) == 2
                    and all(isinstance(v, int | float) and math.isfinite(v) for v in pair)
                ):
                    self._frames.append((float(pair[0]), float(pair[1])))
                    kept += 1
        return kept

    def summary(self, window: float = 10.0) -> dict[str, Any]:
        """Frames drawn in the last ``window`` seconds: count, frame rate [1/s], lag [ms]."""
        with self._lock:
            frames = np.array(self._frames, dtype=np.float64).reshape(-1, 2)
        if frames.shape[0]:
            frames = frames[frames[:, 1] >= frames[-1, 1] - window]
        n = frames.shape[0]
        out: dict[str, Any] = {"frames": n, "window_s": window}
        if n < 2:
            return out | {"fps": None, "p50_ms": None, "p99_ms": None, "max_ms": None}
        lag = 1e3 * (frames[:, 1] - frames[:, 0])
        span = frames[-1, 1] - frames[0, 1]
        return out | {
            "fps": float((n - 1) / span) if span > 0 else None,
            "p50_ms": float(np.percentile(lag, 50)),
            "p99_ms": float(np.percentile(lag, 99)),
            "max_ms": float(lag.max()),
        }


_ISOLATION: Final = [
    (b"cross-origin-opener-policy", b"same-origin"),
    (b"cross-origin-embedder-policy", b"require-corp"),
]


class _Isolated:
    """ASGI middleware: the cross-origin isolation headers on every HTTP response."""

    def __init__(self, app: Any) -> None:
        self.app = app

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return

        async def send_isolated(message: Any) -> None:
            if message["type"] == "http.response.start":
                message["headers"] = [*message.get("headers", []), *_ISOLATION]
            await send(message)

        await self.app(scope, receive, send_isolated)


def _decimate(rows: Any, first: int, stride: int, peaks: list[int]) -> Any:
    """Every ``stride``-th row of the feed (row ``first`` of ``rows`` is the feed's row
    ``first``); the ``peaks`` columns keep the maximum of the rows each one stands for."""
    index = np.arange(first, first + rows.shape[0])
    starts = np.flatnonzero(index % stride == 0)
    out = rows[starts]
    if peaks and starts.size:
        groups = starts.copy()
        groups[0] = 0  # the rows before the first kept one count with it
        out[:, peaks] = np.fmax.reduceat(rows[:, peaks], groups, axis=0)
    return out


def new_token() -> str:
    """A random token for the controls (URL-safe, 128 bits)."""
    return secrets.token_urlsafe(16)


def _need_starlette() -> None:
    try:
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError:
        raise MotosimError(
            "the view needs starlette and uvicorn: pip install 'motosim[view]'"
        ) from None


def _finite(values: Any) -> Any:
    """Floats with NaN and infinities as None (JSON has neither)."""
    return [None if not math.isfinite(v) else round(float(v), 6) for v in values]


def create_app(
    feed: Feed,
    road: Road,
    *,
    token: str,
    pose_rate: float = 120.0,
    signal_rate: float = 30.0,
    title: str = "motosim",
    recorded: Mapping[str, Any] | None = None,
    lags: LagLog | None = None,
) -> Starlette:
    """The web application of one feed.

    Parameters
    ----------
    feed : Feed
        A :class:`~motosim.view.feeds.ReplayFeed` or a live feed.
    road : Road
        The road to draw.
    token : str
        Required in ``X-Motosim-Token`` by ``POST /api/control`` (:func:`new_token`).
    pose_rate, signal_rate : float
        Largest messages per second on ``/ws/pose``, messages per second on ``/ws/signals``
        [Hz].
    title : str
        Shown in the pages.
    recorded : mapping, optional
        What a replayed run recorded about its loop and safety stage (``timing.json`` of
        ``motosim run``), shown by the dashboard.
    lags : LagLog, optional
        Where the frames reported by the pages go (a new one by default; ``GET /api/lag``).

    Returns
    -------
    starlette.applications.Starlette

    Raises
    ------
    MotosimError
        If starlette is missing, the token is shorter than 8 characters or a rate is not in
        (0, 240] Hz.
    """
    _need_starlette()
    from starlette.applications import Starlette
    from starlette.middleware import Middleware
    from starlette.responses import FileResponse, JSONResponse
    from starlette.routing import Mount, Route, WebSocketRoute
    from starlette.staticfiles import StaticFiles
    from starlette.websockets import WebSocketDisconnect

    if len(token) < 8:
        raise MotosimError(f"a view token of {len(token)} characters; expected at least 8")
    for name, rate in (("pose_rate", pose_rate), ("signal_rate", signal_rate)):
        if not (math.isfinite(rate) and 0.0 < rate <= 240.0):
            raise MotosimError(f"{name} = {rate!r} Hz; expected a number in (0, 240]")

    lag_log = LagLog() if lags is None else lags
    names = feed.names
    clock_col = names.index("t_clock") if "t_clock" in names else -1
    # the time the loop wrote the row: its deadline plus its wake-up latency and compute time
    late_cols = [names.index(n) for n in ("wake", "compute") if n in names]
    pose_cols = [names.index(n) for n in _POSE if n in names]
    pose_names = [n for n in _POSE if n in names]
    dash_names = [n for n in DASHBOARD_SIGNALS if n in names]
    dash_cols = np.array([names.index(n) for n in dash_names])
    peak_cols = [j for j, n in enumerate(dash_names) if n in _PEAKS]
    road_json = road.to_json()
    units = {n: SIGNALS[n].unit if n in SIGNALS else _UNITS.get(n, "") for n in names}

    def info(request: Request) -> Response:
        return JSONResponse(
            {
                "title": title,
                "names": list(names),
                "dashboard": dash_names,
                "units": units,
                "road": road_json,
                "status": feed.status(),
                "replay": isinstance(feed, ReplayFeed),
                "recorded": dict(recorded) if recorded is not None else None,
            }
        )

    def replay_rows(request: Request) -> Response:
        """The whole run's dashboard signals, at most ``_REPLAY_POINTS`` rows (a replay)."""
        if not isinstance(feed, ReplayFeed):
            return JSONResponse(
                {"error": "not a replay: the rows come over /ws/signals"}, status_code=404
            )
        rows = feed.rows()[:, dash_cols]
        stride = max(1, -(-rows.shape[0] // _REPLAY_POINTS))
        rows = _decimate(rows, 0, stride, peak_cols)
        return JSONResponse({"names": dash_names, "rows": [_finite(r) for r in rows]})

    def lag(request: Request) -> Response:
        try:
            window = float(request.query_params.get("window", "10"))
        except ValueError:
            window = math.nan
        if not (math.isfinite(window) and window > 0.0):
            return JSONResponse({"error": "window: expected seconds > 0"}, status_code=400)
        return JSONResponse(lag_log.summary(window))

    def page(file: str) -> Any:
        def endpoint(request: Request) -> Response:
            return FileResponse(STATIC / file, headers={"Cache-Control": "no-store"})

        return endpoint

    async def control(request: Request) -> Response:
        given = request.headers.get("x-motosim-token", "")
        if not secrets.compare_digest(given.encode(), token.encode()):
            return JSONResponse({"error": "missing or wrong X-Motosim-Token"}, status_code=403)
        try:
            body = await request.json()
        except ValueError:
            return JSONResponse({"error": "expected a JSON body"}, status_code=400)
        action = body.get("action") if isinstance(body, dict) else None
        try:
            if action == "arm":
                feed.control.arm()
            elif action == "stop":
                feed.control.stop()
            elif action in ("seek", "rate") and isinstance(feed, ReplayFeed):
                value = body.get("t" if action == "seek" else "rate")
                if not isinstance(value, int | float) or isinstance(value, bool):
                    raise MotosimError(f"{action} = {value!r}; expected a number")
                if action == "seek":
                    feed.seek(float(value))
                else:
                    feed.set_rate(float(value))
            else:
                allowed = "arm, stop, seek, rate" if isinstance(feed, ReplayFeed) else "arm, stop"
                raise MotosimError(f"action = {action!r}; expected one of {allowed}")
        except MotosimError as err:
            return JSONResponse({"error": str(err)}, status_code=400)
        return JSONResponse({"ok": True, "status": feed.status()})

    async def pose(websocket: WebSocket) -> None:
        await websocket.accept()
        period = 1.0 / pose_rate
        loop = asyncio.get_running_loop()
        lock = asyncio.Lock()

        async def send(message: dict[str, Any]) -> None:
            async with lock:
                await websocket.send_text(json.dumps(message))

        async def receive() -> None:  # pings and frame reports from the page
            while True:
                try:
                    message = json.loads(await websocket.receive_text())
                except ValueError:
                    continue
                if not isinstance(message, dict):
                    continue
                ping = message.get("ping")
                if isinstance(ping, int | float) and math.isfinite(ping):
                    await send({"pong": ping, "server": time.monotonic()})
                if "frames" in message:
                    lag_log.add(message["frames"])

        listener = asyncio.create_task(receive())
        last_t: float | None = None
        last_sent = -math.inf
        try:
            while not listener.done():
                now = loop.time()
                row = feed.latest()
                t = float(row[0]) if row is not None else None
                fresh = t != last_t and now - last_sent >= 0.9 * period
                if fresh or now - last_sent >= _HEARTBEAT:
                    message: dict[str, Any] = {"status": feed.status()}
                    if row is not None:
                        message["pose"] = dict(
                            zip(pose_names, _finite(row[pose_cols]), strict=True)
                        )
                        if clock_col >= 0 and math.isfinite(row[clock_col]):
                            deadline = float(row[clock_col])
                            late = float(np.sum(row[late_cols])) if late_cols else 0.0
                            written = deadline + late if math.isfinite(late) else deadline
                            message["clock"], message["deadline"] = written, deadline
                    message["sent"] = time.monotonic()
                    await send(message)
                    last_t, last_sent = t, now
                await asyncio.sleep(_POLL)
        except (WebSocketDisconnect, RuntimeError, OSError):
            return
        finally:
            listener.cancel()

    async def signals(websocket: WebSocket) -> None:
        await websocket.accept()
        period = 1.0 / signal_rate
        cursor, epoch = 0, None
        try:
            while True:
                status = feed.status()
                if status.get("epoch") != epoch:
                    epoch, cursor = status.get("epoch"), 0
                    start_over = True
                else:
                    start_over = False
                rows, new_cursor = feed.read_since(cursor)
                if new_cursor < cursor:
                    start_over = True
                rows = rows[:, dash_cols]
                if rows.shape[0] > 1:
                    dt = float(np.median(np.diff(rows[:, 0])))
                    stride = max(1, round(1.0 / (_DASHBOARD_RATE * dt))) if dt > 0 else 1
                    rows = _decimate(rows, new_cursor - rows.shape[0], stride, peak_cols)
                cursor = new_cursor
                message = {
                    "names": dash_names,
                    "rows": [_finite(r) for r in rows] if rows.size else [],
                    "start_over": start_over,
                    "status": status,
                }
                await websocket.send_text(json.dumps(message))
                await asyncio.sleep(period)
        except (WebSocketDisconnect, RuntimeError, OSError):
            return

    return Starlette(
        routes=[
            Route("/", page("view.html")),
            Route("/dashboard", page("dashboard.html")),
            Route("/api/info", info),
            Route("/api/control", control, methods=["POST"]),
            Route("/api/lag", lag),
            Route("/api/replay", replay_rows),
            WebSocketRoute("/ws/pose", pose),
            WebSocketRoute("/ws/signals", signals),
            Mount("/static", StaticFiles(directory=STATIC), name="static"),
        ],
        middleware=[Middleware(_Isolated)],
    )


class ServerThread:
    """Serve an application with uvicorn in a background thread (for a loop or a test).

    Parameters
    ----------
    app : Starlette
        From :func:`create_app`.
    host : str
        Address to bind (127.0.0.1 unless the user asks otherwise).
    port : int
        TCP port; 0 picks a free one (see :attr:`port` once started).

    Examples
    --------
    ``with ServerThread(app) as server: print(server.url)`` serves until the block ends.
    """

    def __init__(self, app: Starlette, host: str = "127.0.0.1", port: int = 0) -> None:
        _need_starlette()
        import uvicorn

        self.host = host
        self._asked = port
        self._server = uvicorn.Server(
            uvicorn.Config(app, host=host, port=port, log_level="warning", ws_ping_interval=None)
        )
        self._thread = threading.Thread(target=self._server.run, name="motosim-view", daemon=True)

    @property
    def port(self) -> int:
        """The port listened on."""
        return int(self._server.servers[0].sockets[0].getsockname()[1])

    @property
    def url(self) -> str:
        """``http://host:port``."""
        return f"http://{self.host}:{self.port}"

    def start(self, timeout: float = 10.0) -> ServerThread:
        """Start serving; returns once the socket listens."""
        self._thread.start()
        waited = 0.0
        while not self._server.started:
            if not self._thread.is_alive() or waited > timeout:
                raise MotosimError(
                    f"the view server on {self.host}:{self._asked} did not start; "
                    "expected a free port (0: any)"
                )
            threading.Event().wait(0.02)
            waited += 0.02
        return self

    def stop(self) -> None:
        """Stop serving and wait for the thread."""
        self._server.should_exit = True
        self._thread.join(5.0)

    def __enter__(self) -> ServerThread:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
