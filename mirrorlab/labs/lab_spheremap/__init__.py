"""The sphere-map lab: the textbook's cone in front of the launch picture, drawn by the
student's GLSL (the reflection vector and the sphere map's s and t) beside the same cone
made by fixed-function texgen. A variant picks the side the shader's cone goes, the
texture unit texgen uses and the cone's tilt."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import LabSpec, Task, register

HOME = Path(__file__).resolve().parent

SPEC = register(
    LabSpec(
        name="spheremap",
        folder="lab_spheremap",
        title="Sphere mapping: shader and texgen",
        setup=("load_textures", "setup_texgen"),
        frame="display",
        functions=("load_textures", "setup_texgen", "draw_cone_texgen", "display"),
        tasks=(
            Task(1, "reflection", "reflect_eye", "the reflection vector in the shader"),
            Task(
                2, "sphere_coordinates", "sphere_map_st", "the sphere map's s and t in the shader"
            ),
            Task(3, "texgen_setup", "setup_texgen", "GL_SPHERE_MAP texgen for s and t"),
            Task(
                4,
                "texgen_draw",
                "draw_cone_texgen",
                "the texgen cone: texgen on, the picture bound, texgen off again",
            ),
            Task(5, "side_by_side", "display", "both cones side by side"),
        ),
        package=__name__,
        home=HOME,
        solution=HOME.parents[2] / "labs" / "solutions" / "lab_spheremap.py",
        options={
            "shader_side": ("left", "right"),
            "unit": (0, 2, 3),
            "tilt": (40.0, 50.0, 60.0),
        },
        defaults={"shader_side": "left", "unit": 0, "tilt": 50.0},
        declared=("SPHERE_MAP_GLSL",),
    )
)
