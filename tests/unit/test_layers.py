"""The one-way data flow of the package (docs/organisation.md), checked on the imports.

params -> model -> {identification, estimation, control, cueing} -> sim -> io -> {rt, campaign,
plotting} -> {report, view} -> cli: a module imports only from its own package and from layers
to its left, and siblings in braces do not import each other. Also: no file opts out of the
formatter's layout.
"""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).parents[2] / "src" / "motosim"
LAYERS = [
    {"errors", "__init__", "choices"},  # the exception, the version, light names
    {"signals", "timeseries"},
    {"params"},
    {"model"},
    {"identification", "estimation", "control", "cueing"},
    {"sim"},
    {"io"},
    {"rt", "campaign", "plotting"},
    {"report", "view"},
    {"cli"},
    {"__main__"},  # python -m motosim: the command line
]
RANK = {package: rank for rank, layer in enumerate(LAYERS) for package in layer}


def _package(path: Path) -> str:
    return path.relative_to(SRC).parts[0].removesuffix(".py")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("motosim"):
            parts = node.module.split(".")
            if len(parts) > 1:
                found.add(parts[1])
            else:  # from motosim import __version__, MotosimError
                found.add("__init__")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == "motosim" and len(parts) > 1:
                    found.add(parts[1])
    return found


MODULES = sorted(p for p in SRC.rglob("*.py") if _package(p) != "__init__")


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_imports_flow_one_way(path: Path) -> None:
    own = _package(path)
    assert own in RANK, f"{own} has no layer in LAYERS"
    for target in _imports(path) - {own}:
        assert RANK[target] < RANK[own], f"{path.relative_to(SRC)} imports motosim.{target}"


def test_matplotlib_only_in_plotting() -> None:
    for path in MODULES:
        if _package(path) == "plotting":
            continue
        text = path.read_text(encoding="utf-8")
        assert "import matplotlib" not in text and "from matplotlib" not in text, path


def test_no_file_opts_out_of_the_formatter() -> None:
    # every file in ruff format's layout (docs/contributing.md, "The code's layout")
    root = SRC.parents[1]
    markers = ("# fmt: " + "skip", "# fmt: " + "off")
    found = [
        f"{path.relative_to(root)}:{number}"
        for folder in ("src", "tests", "bench", "scripts", "examples")
        for path in sorted((root / folder).rglob("*.py"))
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if any(marker in line for marker in markers)
    ]
    assert not found, found
