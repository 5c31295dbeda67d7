"""The documentation's own promises that a build cannot see: the README stays a front door,
every page is in the site's navigation, and the command-line reference is made from the
parser, every command and option of it, and the built site works opened from disk: every
link in it lands on a file, not a folder. (./dev test builds the site with --strict,
which fails on a broken link, anchor or API reference.)"""

from __future__ import annotations

import argparse
import importlib.util
import os
import re
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

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


class _PageLinks(HTMLParser):
    """The ``href`` and ``src`` values and the element ids of one HTML page."""

    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []
        self.ids: set[str] = set()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for key, value in attrs:
            if key in ("href", "src") and value:
                self.links.append(value)
            elif key == "id" and value:
                self.ids.add(value)


def read_page(path: Path) -> _PageLinks:
    page = _PageLinks()
    page.feed(path.read_text(encoding="utf-8"))
    return page


def test_the_built_site_works_opened_from_disk(tmp_path):
    """Built as a reader gets it, every link of every page (the generated ones too) goes to
    a file that exists, and to an id on that page when it names one: opened from file://,
    a link to a folder would show a folder listing. (404.html is for a web server only:
    its links start at the server's root.)"""
    config = (REPO / "mkdocs.yml").read_text()
    assert re.search(r"^use_directory_urls: false$", config, flags=re.M)
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1", "DISABLE_MKDOCS_2_WARNING": "true"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--quiet", "--site-dir", str(site)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    pages = {path: read_page(path) for path in site.rglob("*.html") if path.name != "404.html"}
    assert len(pages) >= 20
    broken, checked = [], 0
    for path, page in pages.items():
        for link in page.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or (not parts.path and not parts.fragment):
                continue
            target = (path.parent / unquote(parts.path)).resolve() if parts.path else path
            checked += 1
            if not target.is_file():
                broken.append(f"{path.relative_to(site)}: {link} (no such file)")
            elif parts.fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else read_page(target).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{path.relative_to(site)}: {link} (no such id)")
    assert checked > 500
    assert not broken, "\n".join(broken[:40])
