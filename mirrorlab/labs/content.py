"""What a student is given for a lab, found from the lab's registry entry (its package's
folder, package data: the same from a wheel, an editable install and a checkout):
``handout.md`` and ``starter.py``, templates whose ``{{name}}`` marks take a variant's
numbers (:func:`handout`, :func:`starter`), and ``reference/``, the evidence the lab's
reference solution gives for the lab's own numbers, made by the trusted checker
(``tools/make_lab_references.py``). What the marks take comes from the lab's
``variant`` module. No solution is shipped.
"""

from __future__ import annotations

import re
from pathlib import Path

from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.variants import Variant, header_line

MARK = re.compile(r"\{\{(\w+)\}\}")
BLOCK = re.compile(r"(# --- variant[^\n]*\n)(.*?)(# --- end of variant)", re.S)


def number(value: float) -> str:
    """A number as the handouts print it (``-7``, ``0.5``)."""
    return f"{value:g}"


def point(values: tuple[float, ...]) -> str:
    """A point as the handouts print it (``(-7, -3, -6)``)."""
    return "(" + ", ".join(number(v) for v in values) + ")"


def values(variant: Variant) -> dict[str, str]:
    """The text each ``{{name}}`` mark of a lab's templates takes for ``variant``."""
    found = {
        "variant_line": "the lab's own numbers (variant default)"
        if variant.is_default
        else f"{variant.id}, made for {variant.student}"
    }
    found.update(find_lab(variant.lab).module("variant").template_values(variant))
    return found


def render(text: str, values: dict[str, str]) -> str:
    """``text`` with each ``{{name}}`` replaced by ``values[name]``; KeyError naming a
    mark ``values`` lacks."""

    def replace(match: re.Match[str]) -> str:
        if match.group(1) not in values:
            raise KeyError(f"template mark {{{{{match.group(1)}}}}} has no value")
        return values[match.group(1)]

    return MARK.sub(replace, text)


def template(spec: LabSpec, name: str) -> str:
    """The template ``name`` (``handout.md`` or ``starter.py``) of a lab."""
    return (spec.home / name).read_text()


def handout(spec: LabSpec, variant: Variant) -> str:
    return render(template(spec, "handout.md"), values(variant))


def starter(spec: LabSpec, variant: Variant) -> str:
    """The starter of ``variant``: its header line (:func:`~.variants.header_line`: the
    variant's numbers, for ``lab check`` away from ``variant.json``), then the template."""
    return header_line(variant) + render(template(spec, "starter.py"), values(variant))


def reference_folder(spec: LabSpec) -> Path:
    """The shipped evidence of the lab's reference solution, for its default variant."""
    return spec.home / "reference"


def solution_block(variant: Variant) -> str:
    """The lines of a solution's variant block for ``variant``."""
    return str(find_lab(variant.lab).module("variant").solution_block(variant))


def solution_for(text: str, variant: Variant) -> str:
    """A solution's ``text`` with its variant block holding ``variant``'s numbers;
    ValueError when it has no such block."""
    if not BLOCK.search(text):
        raise ValueError("the solution has no '# --- variant' ... '# --- end of variant' block")
    return BLOCK.sub(lambda m: m.group(1) + solution_block(variant) + m.group(3), text, count=1)
