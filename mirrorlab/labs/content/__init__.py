"""What a student is given for each lab, as package data found through
:mod:`importlib.resources` (the same from a wheel, an editable install and a checkout):
``<folder>/handout.md`` and ``<folder>/starter.py``, templates whose ``{{name}}`` marks
take a variant's numbers (:func:`handout`, :func:`starter`), and ``<folder>/reference/``,
the evidence the lab's reference solution gives for the lab's own numbers, made by the
trusted checker (``tools/make_lab_references.py``). No solution is here.
"""

from __future__ import annotations

import re
from importlib.resources import files
from pathlib import Path

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.variants import Variant, cube_center, lab20_geometry

MARK = re.compile(r"\{\{(\w+)\}\}")
BLOCK = re.compile(r"(# --- variant[^\n]*\n)(.*?)(# --- end of variant)", re.S)


def content_path(*parts: str) -> Path:
    """The packaged file or folder ``mirrorlab/labs/content/<parts...>`` on disk."""
    root = files(__name__)
    if not isinstance(root, Path):
        raise RuntimeError(
            f"mirrorlab's lab content is not on the file system ({root}); "
            f"install mirrorlab as a wheel or from a source folder"
        )
    return root.joinpath(*parts)


def _number(value: float) -> str:
    return f"{value:g}"


def _point(values: tuple[float, ...]) -> str:
    return "(" + ", ".join(_number(v) for v in values) + ")"


def values(variant: Variant) -> dict[str, str]:
    """The text each ``{{name}}`` mark of a lab's templates takes for ``variant``."""
    found = {
        "variant_line": "the lab's own numbers (variant default)"
        if variant.is_default
        else f"{variant.id}, made for {variant.student}"
    }
    if variant.lab == "lab20":
        g = lab20_geometry(variant)
        corners = [_point(c) for c in g["corners"]]
        found.update({key: _number(g[key]) for key in ("x", "y0", "y1", "z0", "z1")})
        found.update(
            width=_number(g["z1"] - g["z0"]),
            height=_number(g["y1"] - g["y0"]),
            corners=", ".join(corners),
            corners_and=", ".join(corners[:3]) + " and " + corners[3],
            corner0=corners[0],
            corner2=corners[2],
            eye=_point(g["eye"]),
            ortho=", ".join(_number(v) for v in g["extents"]),
        )
    elif variant.lab == "spheremap":
        left = variant["shader_side"] == "left"
        shader = "the shader's cone here: lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)"
        texgen = "the texgen cone here: draw_cone_texgen()"
        found.update(
            shader_side=variant["shader_side"],
            texgen_side="right" if left else "left",
            unit=str(variant["unit"]),
            unit_name=f"GL_TEXTURE{variant['unit']}",
            left_cone=shader if left else texgen,
            right_cone=texgen if left else shader,
        )
    else:
        found.update(center=_point(cube_center(variant)))
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
    """The packaged template ``name`` (``handout.md`` or ``starter.py``) of a lab."""
    return content_path(spec.folder, name).read_text()


def handout(spec: LabSpec, variant: Variant) -> str:
    return render(template(spec, "handout.md"), values(variant))


def starter(spec: LabSpec, variant: Variant) -> str:
    return render(template(spec, "starter.py"), values(variant))


def reference_folder(spec: LabSpec) -> Path:
    """The shipped evidence of the lab's reference solution, for its default variant."""
    return content_path(spec.folder, "reference")


def solution_block(variant: Variant) -> str:
    """The lines of a solution's variant block for ``variant``."""
    if variant.lab == "lab20":
        g = lab20_geometry(variant)
        n = _number
        return (
            f"MIRROR_X = {n(g['x'])}\nY0, Y1 = {n(g['y0'])}, {n(g['y1'])}\n"
            f"Z0, Z1 = {n(g['z0'])}, {n(g['z1'])}\n"
        )
    if variant.lab == "spheremap":
        return f'SHADER_SIDE = "{variant["shader_side"]}"\nUNIT = {variant["unit"]}\n'
    return f"CENTER = {_point(cube_center(variant))}\n"


def solution_for(text: str, variant: Variant) -> str:
    """A solution's ``text`` with its variant block holding ``variant``'s numbers;
    ValueError when it has no such block."""
    if not BLOCK.search(text):
        raise ValueError("the solution has no '# --- variant' ... '# --- end of variant' block")
    return BLOCK.sub(lambda m: m.group(1) + solution_block(variant) + m.group(3), text, count=1)
