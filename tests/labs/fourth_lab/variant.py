"""What the quad lab's variant means: the clear colour (its red varies)."""

from __future__ import annotations

from mirrorlab.labs.content import point
from mirrorlab.labs.trusted.variants import Variant


def clear_colour(variant: Variant) -> tuple[float, float, float]:
    """The frame's colour, RGB in 0..1."""
    return (float(variant["red"]), 0.2, 0.4)


def template_values(variant: Variant) -> dict[str, str]:
    return {"colour": point(clear_colour(variant))}


def solution_block(variant: Variant) -> str:
    return f"COLOUR = {point(clear_colour(variant))}\n"
