"""Copies of registered techniques under new names ("twins"), and how the tests find what
they measured for a technique whatever it is called.

No test keeps its own list of the techniques (DESIGN.md, stage 5): the lists and counts
come from the registry (:mod:`mirrorlab.techniques`), so a technique is covered by
registering it. To check that, the whole suite can run with a twin of any registered
technique, named ``<name>-twin``, registered in every test process:

    MIRRORLAB_TEST_TWINS=reflected,cube-live .venv/bin/python -m pytest tests/unit tests/gl

(``tests/__init__.py`` reads the variable, so a child process that imports the tests has
the twins too; one that runs ``mirrorlab`` alone does not.) A twin is its original under
another name: it must draw, plan, parse and measure as its original does, and nothing may
break. ``tests/unit/test_twins.py`` runs the registry's own checks that way.

Figures measured for one technique (a tolerance against the ray tracer) stay keyed by the
technique's name; :func:`measured` finds a twin's under its original's name.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import replace
from typing import TypeVar

from mirrorlab.techniques import Technique, register, technique, techniques

VARIABLE = "MIRRORLAB_TEST_TWINS"
"""The environment variable naming the techniques to register a twin of, comma-separated."""
SUFFIX = "-twin"

T = TypeVar("T")


def twin_of(entry: Technique) -> Technique:
    """``entry`` under the name ``<name>-twin``: nothing else differs but its summary."""
    return replace(entry, name=f"{entry.name}{SUFFIX}", summary=f"{entry.summary} (a twin)")


def register_twins(names: Iterable[str]) -> tuple[Technique, ...]:
    """Register a twin of each technique of ``names`` (ValueError for a name the registry
    does not hold); returns them."""
    return tuple(register(twin_of(technique(name))) for name in names)


def register_from_environment() -> tuple[Technique, ...]:
    """The twins :data:`VARIABLE` asks for, registered (none when it is unset or empty)."""
    names = [n.strip() for n in os.environ.get(VARIABLE, "").split(",") if n.strip()]
    return register_twins(names)


def original(name: str) -> str:
    """The name of the technique ``name`` is a copy of: the first registered technique
    whose entry is ``name``'s but for its name and summary (``name`` itself when no other
    is)."""
    entry = technique(name)
    for other in techniques():
        if replace(entry, name=other.name, summary=other.summary) == other:
            return other.name
    return name


def measured(table: Mapping[str, T], name: str, what: str = "a measured figure") -> T:
    """``table[name]``, or for a copy of another technique its original's entry
    (:func:`original`); KeyError saying what to measure when there is neither."""
    for key in (name, original(name)):
        if key in table:
            return table[key]
    raise KeyError(
        f"no {what} for technique {name!r}: measure it (the failing check prints its "
        f"figures) and add it beside those of {', '.join(table)}"
    )


def techniques_named(test: Callable[[Technique], bool]) -> str:
    """How a message names the registered techniques ``test`` is true of: ``technique
    'a'``, or ``techniques 'a', 'b'`` (a twin's original and the twin, say)."""
    names = [t.name for t in techniques() if test(t)]
    listed = ", ".join(repr(n) for n in names)
    return f"technique {listed}" if len(names) == 1 else f"techniques {listed}"


def reflector_choices() -> str:
    """How a message lists the techniques a reflector may take: every one of either kind
    (one serving both once), in the registry's order."""
    from mirrorlab.techniques import reflector_technique_names

    return ", ".join(reflector_technique_names())
