"""The command reference: the ``--help`` of every ``motosim`` subcommand, from its parser."""

import argparse
import os

from motosim.cli.main import COMMANDS, build_parser


def markdown() -> str:
    """The reference page, in MyST Markdown."""
    os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal's width
    parser = build_parser("all")
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = [
        "# Command reference",
        "",
        "Generated from the parser of each command (`motosim COMMAND --help` prints the same).",
        "The user guide shows when to use each; exit codes are in",
        "[troubleshooting](../guide/troubleshooting.md).",
        "",
        "```text",
        parser.format_help().rstrip(),
        "```",
        "",
    ]
    for name in COMMANDS:
        out += [f"## `motosim {name}`", "", "```text", sub.choices[name].format_help().rstrip()]
        out += ["```", ""]
    return "\n".join(out)
