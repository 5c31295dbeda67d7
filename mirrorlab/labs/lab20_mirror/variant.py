"""What a variant's numbers mean for lab 20: the mirror's geometry, the text the
handout's and starter's ``{{name}}`` marks take, and the solution's variant block.
Plain Python: no OpenGL."""

from __future__ import annotations

from typing import Any

from mirrorlab.labs.content import number, point
from mirrorlab.labs.trusted.variants import Variant


def lab20_geometry(variant: Variant) -> dict[str, Any]:
    """Lab 20's mirror: plane ``x``, ``y0``..``y1``, ``z0``..``z1``, the four ``corners``
    (as the handout lists them), the capture's ``extents`` (glOrtho's six numbers), its
    ``eye`` and ``angles`` of the robot's joints."""
    v = variant.values
    x, y0, z0 = v["mirror_x"], v["y0"], v["z0"]
    y1, z1 = y0 + v["height"], z0 + v["width"]
    return {
        "x": x,
        "y0": y0,
        "y1": y1,
        "z0": z0,
        "z1": z1,
        "corners": ((x, y0, z0), (x, y1, z0), (x, y1, z1), (x, y0, z1)),
        "extents": (z0, z1, y0, y1, 0.0, 15.0),
        "eye": (x, 0.0, 0.0),
        "angles": (v["base_angle"], v["lower_angle"], v["upper_angle"]),
    }


def template_values(variant: Variant) -> dict[str, str]:
    """The text of the lab's own ``{{name}}`` marks for ``variant``."""
    g = lab20_geometry(variant)
    corners = [point(c) for c in g["corners"]]
    found = {key: number(g[key]) for key in ("x", "y0", "y1", "z0", "z1")}
    found.update(
        width=number(g["z1"] - g["z0"]),
        height=number(g["y1"] - g["y0"]),
        corners=", ".join(corners),
        corners_and=", ".join(corners[:3]) + " and " + corners[3],
        corner0=corners[0],
        corner2=corners[2],
        eye=point(g["eye"]),
        ortho=", ".join(number(v) for v in g["extents"]),
    )
    return found


def solution_block(variant: Variant) -> str:
    """The lines of the solution's variant block for ``variant``."""
    g = lab20_geometry(variant)
    n = number
    return (
        f"MIRROR_X = {n(g['x'])}\nY0, Y1 = {n(g['y0'])}, {n(g['y1'])}\n"
        f"Z0, Z1 = {n(g['z0'])}, {n(g['z1'])}\n"
    )
