"""The documentation site's promises, checked without Sphinx (``make docs`` builds the site).

- every public name (each module's ``__all__``) is on a page of the API reference;
- every key of the scenario file has its meaning written in the scenario reference;
- every ``motosim ...`` line of a shell block of the guide parses with the command's own
  parser (options and commands that exist), and the scenario and campaign files it names
  exist;
- every TOML block parses, and every Python block of the guide runs as written.
"""

import importlib
import re
import shlex
import sys
import tomllib
from pathlib import Path

import pytest

from motosim.cli.main import build_parser
from motosim.sim.scenario import parse_scenario

ROOT = Path(__file__).parents[2]
DOCS = ROOT / "docs"
sys.path.insert(0, str(DOCS / "_ext"))

import apigen  # noqa: E402
import scenario_ref  # noqa: E402

PAGES = sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```", re.M | re.S)


def _blocks(language: str) -> list[tuple[str, str]]:
    found = []
    for page in PAGES:
        for lang, body in FENCE.findall(page.read_text(encoding="utf-8")):
            if lang == language:
                found.append((str(page.relative_to(DOCS)), body))
    return found


def test_every_public_name_is_in_the_api_reference() -> None:
    documented = apigen.documented(apigen.pages())
    for name in apigen.public_modules():
        module = importlib.import_module(name)
        for item in getattr(module, "__all__", []):
            home = apigen.homes()[(name, item)]
            assert f"{home}.{item}" in documented, f"{name}.{item} is on no API page"


def test_every_scenario_key_has_a_meaning() -> None:
    keys = scenario_ref.all_keys()
    missing = [key for key in keys if not scenario_ref.DESCRIPTIONS.get(key)]
    stale = [key for key in scenario_ref.DESCRIPTIONS if key not in keys]
    assert not missing, f"describe these scenario keys in docs/_ext/scenario_ref.py: {missing}"
    assert not stale, f"these keys no longer exist: {stale}"


def _commands() -> list[tuple[str, list[str]]]:
    out = []
    for page, body in _blocks("sh"):
        for line in body.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words and words[-1] == "&":
                words = words[:-1]
            if words and words[0] == "motosim":
                out.append((f"{page}: {line.strip()}", words[1:]))
    return out


COMMANDS = _commands()


def test_the_guide_has_commands() -> None:
    assert len(COMMANDS) > 30


@pytest.mark.parametrize(("where", "words"), COMMANDS, ids=[c[0] for c in COMMANDS])
def test_shell_commands_of_the_guide_parse(where: str, words: list[str]) -> None:
    parser = build_parser("all")
    try:
        parser.parse_args(words)
    except SystemExit as stop:  # argparse's usage error (printed) or --help
        code = stop.code
    else:
        code = 0
    assert code == 0, where
    for word in words:  # the files of the repository a command names
        if word.startswith(("scenarios/", "campaigns/")):
            assert (ROOT / word).exists(), f"{where}: {word} does not exist"


@pytest.mark.parametrize(("where", "body"), _blocks("toml"), ids=lambda v: str(v)[:40])
def test_toml_blocks_parse(where: str, body: str) -> None:
    data = tomllib.loads(body)
    if "name" in data.get("scenario", {}):  # a whole scenario: valid as one
        parse_scenario(data, origin=where)


PYTHON = [(page, body) for page, body in _blocks("python") if "ServerThread" not in body]


@pytest.mark.parametrize(
    ("where", "body"), PYTHON, ids=[f"{p}:{i}" for i, (p, _) in enumerate(PYTHON)]
)
def test_python_blocks_run(where: str, body: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)  # the guide runs from the repository's root
    exec(compile(body, where, "exec"), {"__name__": "__docs__"})
