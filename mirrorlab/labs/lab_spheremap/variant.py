"""What a variant's numbers mean for the sphere-map lab: the text the handout's and
starter's ``{{name}}`` marks take, and the solution's variant block. Plain Python: no
OpenGL."""

from __future__ import annotations

from mirrorlab.labs.trusted.variants import Variant


def template_values(variant: Variant) -> dict[str, str]:
    """The text of the lab's own ``{{name}}`` marks for ``variant``."""
    left = variant["shader_side"] == "left"
    shader = "the shader's cone here: lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)"
    texgen = "the texgen cone here: draw_cone_texgen()"
    return {
        "shader_side": variant["shader_side"],
        "texgen_side": "right" if left else "left",
        "unit": str(variant["unit"]),
        "unit_name": f"GL_TEXTURE{variant['unit']}",
        "left_cone": shader if left else texgen,
        "right_cone": texgen if left else shader,
    }


def solution_block(variant: Variant) -> str:
    """The lines of the solution's variant block for ``variant``."""
    return f'SHADER_SIDE = "{variant["shader_side"]}"\nUNIT = {variant["unit"]}\n'
