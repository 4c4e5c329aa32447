"""Every option's default is stated in ``--help``, and what the README and the guide say of a
default is what the parser does.

The documents state a default in three forms, each checked against the command's parser:

- ```--option VALUE`, the default`` or ```--option VALUE` (the default``, in prose;
- ``[--option VALUE]`` in a synopsis block (a ```text`` block starting ``motosim COMMAND``),
  where a literal value (not an upper-case placeholder) of an option that has a default is
  that default (of an option without one, such as ``--scheduler``, it is an example);
- ``[--option a|b]`` in a synopsis, where the first of the choices is the default.
"""

import argparse
import re
from pathlib import Path

import pytest

from motosim.cli.main import COMMANDS, build_parser, has_default, render_default

ROOT = Path(__file__).parents[2]
DOCUMENTS = [ROOT / "README.md", *sorted((ROOT / "docs" / "guide").glob("*.md"))]


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser("all")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise AssertionError("motosim has no subcommands")


PARSERS = _subparsers()


def _options(name: str) -> dict[str, argparse.Action]:
    return {
        option: action
        for action in PARSERS[name]._actions
        for option in action.option_strings
        if option.startswith("--")
    }


def _help_of(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    formatter = parser._get_formatter()
    return " ".join(formatter._format_action(action).split())


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_option_states_its_default(command: str) -> None:
    parser = PARSERS[command]
    silent = []
    for action in parser._actions:
        if not action.option_strings or action.nargs == 0 or action.required:
            continue  # flags say what they do; required options have no default
        text = _help_of(parser, action).lower()
        if "default" not in text:
            silent.append(action.option_strings[0])
        elif has_default(action) and "%(default)" not in (action.help or ""):
            shown = render_default(action.default).lower()
            assert shown in text, f"{command} {action.option_strings[0]}: {text!r}"
    assert not silent, f"motosim {command} --help: no default stated for {silent}"


def test_the_help_shows_a_default_as_typed() -> None:
    text = " ".join(PARSERS["excite"].format_help().split())
    assert "length [s] (default: 60)" in text
    assert "--signal {chirp,square} default: chirp" in text


_PROSE = re.compile(r"`(--[a-z-]+) ([^`\s]+)`(?:,|\s\()\s*(?:the|by)\s+default")
_SYNOPSIS = re.compile(r"\[(--[a-z-]+) ([^\]\s]+)\]")
_SHOWN_COMMAND = re.compile(r"motosim ([a-z-]+)")


def _statements() -> list[tuple[str, str, str, str]]:
    """(where, command, option, value) for each default the documents state."""
    found = []
    for page in DOCUMENTS:
        text = page.read_text(encoding="utf-8")
        name = page.relative_to(ROOT)
        for block in re.findall(r"^```text\n(motosim [a-z-]+.*?)^```", text, re.M | re.S):
            command = ""
            for line in block.splitlines():
                if line.startswith("motosim "):
                    command = line.split()[1]
                for option, value in _SYNOPSIS.findall(line):
                    first = value.split("|")[0]
                    if first.isupper() or not has_default(_options(command)[option]):
                        continue  # a placeholder (N, FILE), or an example of a value
                    found.append((f"{name}: [{option} {value}]", command, option, first))
        for paragraph in re.split(r"\n\s*\n", text):
            for match in _PROSE.finditer(paragraph):
                before = paragraph[: match.start()]
                commands = _SHOWN_COMMAND.findall(before) or _SHOWN_COMMAND.findall(paragraph)
                option, value = match.groups()
                owners = [c for c in dict.fromkeys(commands[::-1]) if option in _options(c)]
                if not owners:  # the paragraph names no command: any command with the option
                    owners = [c for c in PARSERS if option in _options(c)]
                said = " ".join(match.group(0).split())
                found.append((f"{name}: {said}", owners[0], option, value))
    return found


STATEMENTS = _statements()


def test_the_documents_state_defaults() -> None:
    # the README's cueing default and the guide's synopses at least
    assert any(s[1:3] == ("cueing", "--algorithm") for s in STATEMENTS if "README" in s[0])
    assert len(STATEMENTS) > 15


@pytest.mark.parametrize(
    ("where", "command", "option", "value"), STATEMENTS, ids=[s[0] for s in STATEMENTS]
)
def test_a_stated_default_is_the_parsers(where: str, command: str, option: str, value: str) -> None:
    action = _options(command)[option]
    if action.choices is not None and "|" in where:
        assert value in action.choices, f"{where}: {value} is not a choice of {option}"
    assert render_default(action.default) == value, (
        f"{where}: motosim {command} {option} defaults to {render_default(action.default)}"
    )
