"""Sphinx configuration of motosim's documentation (``make docs``)."""

import os
import re
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE / "_ext"))

import apigen
import commands_ref
import scenario_ref
from gallery_scraper import figure_scraper

import motosim

os.environ.setdefault("MPLBACKEND", "Agg")

project = "motosim"
author = "the motosim developers"
copyright = "the motosim developers, BSD-3-Clause"
release = motosim.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "**.codeobj.json"]

# Markdown pages (the user guide): tables, ``$`` maths and anchors for every heading
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

# API reference: pages written from every public module's __all__ before the build
apigen.write(HERE / "api")
# Pages generated from the code: the scenario file's keys, every command's --help
(HERE / "generated").mkdir(exist_ok=True)
for _name, _text in {
    "scenario": scenario_ref.markdown(),
    "commands": commands_ref.markdown(),
}.items():
    _path = HERE / "generated" / f"{_name}.md"
    if not _path.exists() or _path.read_text(encoding="utf-8") != _text:
        _path.write_text(_text, encoding="utf-8")
autosummary_generate = False
autodoc_typehints = "none"  # the numpydoc sections carry the types with their units
autodoc_member_order = "bysource"
autodoc_class_signature = "mixed"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_attributes_as_param_list = True
numpydoc_xref_param_type = False
# docstrings kept in step with the signatures: no documented parameter that does not exist
# (PR02), none out of order (PR03), a summary (SS01), no public object without a docstring
# (GL08); the build fails on any (warnings are errors)
numpydoc_validation_checks = {"PR02", "PR03", "SS01", "GL08"}
numpydoc_validation_exclude = {re.escape(name) + "$" for name in apigen.data_names()}

# Executed examples: every script of examples/ runs at build time and its figures are kept
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "within_subsection_order": "FileNameSortKey",
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib", figure_scraper),
    "reset_modules": ("matplotlib",),
    "min_reported_time": 1,
}

html_theme = "furo"
html_title = f"motosim {release}"
html_static_path: list[str] = []
pygments_style = "sphinx"
suppress_warnings = ["config.cache"]

_LITERALS = re.compile(r"(``.*?``|`[^`]*`)")


def _escape_bars(
    app: object, what: str, name: str, obj: object, options: object, lines: list[str]
) -> None:
    """Read ``|x|`` in a docstring as the absolute value it means, not a substitution."""
    for i, line in enumerate(lines):
        text = line.strip()
        if "|" not in text or text.startswith("+") or (text[0] == "|" and text[-1] == "|"):
            continue  # a table's border or row
        parts = _LITERALS.split(line)
        lines[i] = "".join(p if k % 2 else p.replace("|", r"\|") for k, p in enumerate(parts))


def setup(app: Any) -> None:
    """Register the docstring hook, after numpydoc's."""
    app.connect("autodoc-process-docstring", _escape_bars, priority=600)
