"""Pages of the documentation site made when it is built (mkdocs-gen-files runs this file;
mkdocs.yml names it): the command-line reference, from mirrorlab's own argument parser
(``mirrorlab.cli.build_parser``): every command, its usage line, and every option with
its help, as ``--help`` prints them. Nothing of it is written by hand, so the page cannot
drift from the parser. ``python tools/docs_pages.py`` prints the page."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

PAGE = "cli-reference.md"
REPO = Path(__file__).resolve().parent.parent
WIDTH = 76
"""Columns argparse formats the usage lines for (its help follows the terminal otherwise)."""


def _formatter(parser: argparse.ArgumentParser) -> argparse.HelpFormatter:
    os.environ["COLUMNS"] = str(WIDTH)
    return parser._get_formatter()


def _subcommands(parser: argparse.ArgumentParser):
    """``(name, help, parser)`` for each subcommand, in the parser's order."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            for name, sub in action.choices.items():
                yield name, helps.get(name), sub


def _escape(text: str) -> str:
    return text.replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;")


def _options(parser: argparse.ArgumentParser) -> list[str]:
    formatter = _formatter(parser)
    lines: list[str] = []
    for group in parser._action_groups:
        actions = [
            a
            for a in group._group_actions
            if a.help != argparse.SUPPRESS and not isinstance(a, argparse._SubParsersAction)
        ]
        if not actions:
            continue
        lines += ["", f"**{group.title}**", "", "| option | what it does |", "|---|---|"]
        for action in actions:
            invocation = formatter._format_action_invocation(action)
            text = formatter._expand_help(action) if action.help else ""
            lines.append(f"| `{invocation}` | {_escape(' '.join(text.split()))} |")
    return lines


def _command(
    parser: argparse.ArgumentParser, title: str, summary: str | None, level: int
) -> list[str]:
    lines = [f"{'#' * level} `{title}`", ""]
    if summary:
        lines += [summary[0].upper() + summary[1:] + ".", ""]
    if parser.description and parser.description != summary:
        lines += [parser.description, ""]
    usage = _formatter(parser)
    usage.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    lines += ["```text", usage.format_help().strip(), "```"]
    lines += _options(parser)
    if parser.epilog:
        lines += ["", "```text", parser.epilog.strip(), "```"]
    lines.append("")
    for name, helped, sub in _subcommands(parser):
        lines += _command(sub, f"{title} {name}", helped, level + 1)
    return lines


def reference_markdown(parser: argparse.ArgumentParser) -> str:
    """The whole reference page for ``parser`` (Markdown)."""
    head = [
        "# Command-line reference",
        "",
        "Made from the argument parser of the installed mirrorlab when this site was "
        "built, so it says what `mirrorlab COMMAND --help` says. The "
        "[command line](cli.md) page explains the commands with examples.",
        "",
    ]
    return "\n".join(head + _command(parser, parser.prog, None, 2)) + "\n"


def write_pages() -> None:
    """Write the generated pages into the site being built."""
    import mkdocs_gen_files

    from mirrorlab.cli import build_parser

    with mkdocs_gen_files.open(PAGE, "w") as page:
        page.write(reference_markdown(build_parser()))
    # The changelog lives at the top of the repository, where packagers look for it.
    with mkdocs_gen_files.open("changelog.md", "w") as page:
        page.write((REPO / "CHANGELOG.md").read_text(encoding="utf-8"))


if __name__ == "<run_path>":  # run by mkdocs-gen-files (runpy.run_path)
    write_pages()
elif __name__ == "__main__":
    from mirrorlab.cli import build_parser

    print(reference_markdown(build_parser()))
