"""``mirrorlab techniques``: the reflection techniques of :mod:`mirrorlab.techniques`
listed."""

from __future__ import annotations

import argparse

NAME = "techniques"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``techniques`` command (no arguments), as a subcommand of ``commands``."""
    commands.add_parser(NAME, help="list the reflection techniques")


def run(args: argparse.Namespace) -> int:
    """``mirrorlab techniques``: one line a technique, its name, kind and summary."""
    from mirrorlab.techniques import techniques

    for entry in techniques():
        print(f"{entry.name:<14} {entry.kind:<7} {entry.summary}")
    return 0
