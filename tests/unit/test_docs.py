"""The documentation's own promises that a build cannot see: the README stays a front door,
every page is in the site's navigation, and the command-line reference is made from the
parser, every command and option of it. (./dev test builds the site with --strict, which
fails on a broken link, anchor or API reference.)"""

from __future__ import annotations

import argparse
import importlib.util
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def docs_pages_module():
    spec = importlib.util.spec_from_file_location("docs_pages", REPO / "tools" / "docs_pages.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_is_short_and_links_into_the_site():
    text = (REPO / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    assert text.startswith("# mirrorlab\n\n```sh\n./dev render")
    linked = set(re.findall(r"\]\(docs/([a-z-]+\.md)\)", text))
    pages = {p.name for p in (REPO / "docs").glob("*.md")}
    assert pages - {"index.md", "api-reference.md"} <= linked, pages - linked


def test_every_page_is_in_the_navigation():
    nav = (REPO / "mkdocs.yml").read_text().split("\nnav:\n", 1)[1]
    listed = set(re.findall(r":\s*([a-z-]+\.md)\s*$", nav, flags=re.M))
    pages = {p.name for p in (REPO / "docs").glob("*.md")}
    generated = {"cli-reference.md", "changelog.md"}
    assert listed == pages | generated, listed ^ (pages | generated)


def all_parsers(parser: argparse.ArgumentParser, prog: str = ""):
    yield prog or parser.prog, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from all_parsers(sub, f"{prog or parser.prog} {name}")


def test_the_cli_reference_has_every_command_and_option():
    from mirrorlab.cli import build_parser

    page = docs_pages_module().reference_markdown(build_parser())
    count = 0
    for title, parser in all_parsers(build_parser()):
        assert f"`{title}`" in page, title
        section = page.split(f"`{title}`", 1)[1]
        for action in parser._actions:
            for flag in action.option_strings:
                assert flag in section, (title, flag)
                count += 1
    assert count > 80  # every command's options, not a few


def test_the_cli_reference_follows_the_parser():
    """A new option appears with its help, a new command with its heading: the page is
    the parser's, not a copy."""
    parser = argparse.ArgumentParser(prog="tool", description="A tool.")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND")
    paint = commands.add_parser("paint", help="paint a wall")
    paint.add_argument("--colour", default="red", help="the colour (default %(default)s)")
    page = docs_pages_module().reference_markdown(parser)
    assert "### `tool paint`" in page and "Paint a wall." in page
    assert "| `--colour COLOUR` | the colour (default red) |" in page


def test_docstring_roles_become_markdown_code():
    spec = importlib.util.spec_from_file_location("griffe_rst", REPO / "tools" / "griffe_rst.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    text = (
        "Returns a :class:`~mirrorlab.frame.Frame`; see :func:`mirrorlab.render` and "
        ":mod:`mirrorlab.options`. Make one::\n\n    r = Renderer()\n"
    )
    assert module.markdown_of(text) == (
        "Returns a `Frame`; see `mirrorlab.render` and `mirrorlab.options`. Make one:\n\n"
        "    r = Renderer()\n"
    )
