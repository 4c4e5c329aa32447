"""See the ride: the rider's view and a live dashboard in the browser.

:mod:`motosim.view.feeds` defines what is shown (a feed of rows of named signals, a run
control, the road), :mod:`motosim.view.app` serves it (Starlette, uvicorn, three.js vendored
under ``static/``), :mod:`motosim.view.live` is a simulated run paced to the wall clock that
stands in for the real-time loop. The server needs the optional group ``view``.
"""

from motosim.view.feeds import Feed, LiveFeed, ReplayFeed, Road, RunControl, road_from_xy

__all__ = ["Feed", "LiveFeed", "ReplayFeed", "Road", "RunControl", "road_from_xy"]
