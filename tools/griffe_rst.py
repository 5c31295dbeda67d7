"""A griffe extension for the site's API reference: mirrorlab's docstrings are written for
``help()`` and Sphinx-style readers (``:func:`render```, ``Example::``); in the Markdown
the site renders they would show their markup. This turns a role into inline code (its
last name with ``~``, as Sphinx does) and a paragraph's closing ``::`` into ``:``."""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|meth|mod|attr|data|exc|obj|const):`(~?)([^`]+)`")
LITERAL = re.compile(r"(\S)::[ \t]*$", flags=re.M)


def markdown_of(text: str) -> str:
    text = ROLE.sub(lambda m: f"`{m.group(2).split('.')[-1] if m.group(1) else m.group(2)}`", text)
    return LITERAL.sub(r"\1:", text)


class SphinxRolesToMarkdown(griffe.Extension):
    def on_instance(self, *, node: Any, obj: griffe.Object, agent: Any, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown_of(obj.docstring.value)
