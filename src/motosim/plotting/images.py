"""A figure as an image to embed in a page."""

import base64
import io
from typing import Any

__all__ = ["SVG_DATA", "svg_base64"]

SVG_DATA = "data:image/svg+xml;base64,"
"""The start of an ``<img>`` source holding one of :func:`svg_base64`'s images."""


def svg_base64(figure: Any) -> str:
    """``figure`` as SVG, base64-encoded, to embed in a page.

    Vector images: a browser draws them at any zoom, and writing them costs about two
    thirds of rendering and compressing the same figure as PNG. matplotlib is imported on
    the first call.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
        The figure, at its own size [in].

    Returns
    -------
    str
        The SVG's bytes in base64: the source of an ``<img>`` after :data:`SVG_DATA`. The
        texts are kept as text, and a figure drawn twice gives the same string.
    """
    import matplotlib

    buffer = io.BytesIO()
    # the texts kept as text (the browser sets them in DejaVu Sans or the next font of the
    # list it has), the clip paths' ids from a fixed salt and no date: a figure drawn twice
    # gives the same bytes
    with matplotlib.rc_context({"svg.fonttype": "none", "svg.hashsalt": "motosim"}):
        figure.savefig(buffer, format="svg", metadata={"Date": None})
    return base64.b64encode(buffer.getvalue()).decode("ascii")
