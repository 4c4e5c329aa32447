"""A sphinx-gallery image scraper for the figures motosim returns.

motosim's plotting functions build :class:`matplotlib.figure.Figure` objects without pyplot
(they never show anything), so sphinx-gallery's own matplotlib scraper does not see them.
This scraper saves every such Figure bound to a name of the example that it has not saved yet.
"""

from typing import Any

_SEEN = "__motosim_figures_saved__"


def figure_scraper(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any]) -> str:
    """Save the example's new Figure objects and return their reStructuredText."""
    from matplotlib.figure import Figure
    from sphinx_gallery.scrapers import figure_rst

    names = block_vars["example_globals"]
    seen: set[int] = names.setdefault(_SEEN, set())
    paths = []
    for value in list(names.values()):
        if isinstance(value, Figure) and value.canvas.manager is None and id(value) not in seen:
            # (a pyplot figure has a manager: sphinx-gallery's own scraper saves it)
            seen.add(id(value))
            path = next(block_vars["image_path_iterator"])
            value.savefig(path, dpi=90)
            paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])
