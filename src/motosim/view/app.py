"""The view's web server: the rider's view, the dashboard, their WebSockets and the controls.

One Starlette application (https://www.starlette.io) per feed, served by uvicorn
(https://www.uvicorn.org), both from the optional group ``view``:

- ``GET /`` the rider's view (three.js, vendored under ``static/``: nothing is fetched from
  the internet), ``GET /dashboard`` the live plots;
- ``GET /api/info`` signal names and units, the road, the status;
- ``WS /ws/pose`` the pose, speed and steer at ``pose_rate`` (60 Hz), JSON;
- ``WS /ws/signals`` new rows of the dashboard's signals at ``signal_rate`` (30 Hz), JSON;
- ``POST /api/control`` arm, stop (and for a replay: seek, rate), only with the run's token
  in the ``X-Motosim-Token`` header (a custom header also keeps other web sites out: a
  browser sends it cross-origin only after a CORS preflight, which this server never grants).

The server binds to 127.0.0.1 unless told otherwise; reading is open to whoever can reach
it, changing the run needs the token.
"""

from __future__ import annotations

import asyncio
import json
import math
import secrets
import threading
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

__all__ = ["DASHBOARD_SIGNALS", "STATIC", "ServerThread", "create_app", "new_token"]

STATIC: Final = Path(__file__).parent / "static"
"""The page files and the vendored three.js build."""

DASHBOARD_SIGNALS: Final = (
    "t", "tau_r", "tau_r_hat", "delta", "theta_h", "phi", "v_x", "e_y", "i_m",
)  # fmt: skip
"""The signals the dashboard plots (those the feed has)."""

_POSE: Final = ("t", "x", "y", "psi", "phi", "delta", "v_x", "theta_h")
_DASHBOARD_RATE: Final = 200.0  # Hz, rows per second kept for the plots


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
    pose_rate: float = 60.0,
    signal_rate: float = 30.0,
    title: str = "motosim",
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
        Messages per second on ``/ws/pose`` and ``/ws/signals`` [Hz].
    title : str
        Shown in the pages.

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
    from starlette.responses import FileResponse, JSONResponse
    from starlette.routing import Mount, Route, WebSocketRoute
    from starlette.staticfiles import StaticFiles
    from starlette.websockets import WebSocketDisconnect

    if len(token) < 8:
        raise MotosimError(f"a view token of {len(token)} characters; expected at least 8")
    for name, rate in (("pose_rate", pose_rate), ("signal_rate", signal_rate)):
        if not (math.isfinite(rate) and 0.0 < rate <= 240.0):
            raise MotosimError(f"{name} = {rate!r} Hz; expected a number in (0, 240]")

    names = feed.names
    pose_cols = [names.index(n) for n in _POSE if n in names]
    pose_names = [n for n in _POSE if n in names]
    dash_names = [n for n in DASHBOARD_SIGNALS if n in names]
    dash_cols = np.array([names.index(n) for n in dash_names])
    road_json = road.to_json()

    def info(request: Request) -> Response:
        return JSONResponse(
            {
                "title": title,
                "names": list(names),
                "dashboard": dash_names,
                "units": {n: SIGNALS[n].unit for n in names if n in SIGNALS},
                "road": road_json,
                "status": feed.status(),
                "replay": isinstance(feed, ReplayFeed),
            }
        )

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
        next_time = loop.time()
        try:
            while True:
                row = feed.latest()
                message: dict[str, Any] = {"status": feed.status()}
                if row is not None:
                    message["pose"] = dict(zip(pose_names, _finite(row[pose_cols]), strict=True))
                await websocket.send_text(json.dumps(message))
                next_time = max(next_time + period, loop.time())
                await asyncio.sleep(next_time - loop.time())
        except (WebSocketDisconnect, RuntimeError, OSError):
            return

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
                if rows.shape[0] > 1:
                    dt = float(np.median(np.diff(rows[:, 0])))
                    stride = max(1, round(1.0 / (_DASHBOARD_RATE * dt))) if dt > 0 else 1
                    index = np.arange(new_cursor - rows.shape[0], new_cursor)
                    rows = rows[index % stride == 0]
                cursor = new_cursor
                message = {
                    "names": dash_names,
                    "rows": [_finite(r) for r in rows[:, dash_cols]] if rows.size else [],
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
            WebSocketRoute("/ws/pose", pose),
            WebSocketRoute("/ws/signals", signals),
            Mount("/static", StaticFiles(directory=STATIC), name="static"),
        ]
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
