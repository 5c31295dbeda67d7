"""What a variant's numbers mean for the cube-map lab: the sphere's centre, the text the
handout's and starter's ``{{name}}`` marks take, and the solution's variant block. Plain
Python: no OpenGL."""

from __future__ import annotations

from mirrorlab.labs.content import point
from mirrorlab.labs.trusted.variants import Variant


def cube_center(variant: Variant) -> tuple[float, float, float]:
    """The chrome sphere's centre, where the six capture cameras sit."""
    v = variant.values
    return (v["center_x"], v["center_y"], v["center_z"])


def template_values(variant: Variant) -> dict[str, str]:
    """The text of the lab's own ``{{name}}`` marks for ``variant``."""
    return {"center": point(cube_center(variant))}


def solution_block(variant: Variant) -> str:
    """The lines of the solution's variant block for ``variant``."""
    return f"CENTER = {point(cube_center(variant))}\n"
