"""Lab 20, the multipass mirror: the robot on its base in front of a mirror whose picture
the student captures into a texture (an orthographic camera at the mirror) and draws on
the mirror quad. A variant moves and sizes the mirror and poses the robot."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import LabSpec, Task, register

HOME = Path(__file__).resolve().parent

SPEC = register(
    LabSpec(
        name="lab20",
        folder="lab20_mirror",
        title="Lab 20: the multipass mirror",
        setup=("load_textures", "build_scene_graph"),
        frame="display",
        functions=(
            "load_textures",
            "build_scene_graph",
            "create_mirror",
            "render_mirror",
            "display",
        ),
        tasks=(
            Task(
                1,
                "capture_camera",
                "create_mirror",
                "the capture's orthographic projection and camera",
            ),
            Task(2, "capture_scene", "create_mirror", "the scene drawn without the mirror"),
            Task(3, "capture_copy", "create_mirror", "the framebuffer copied into ENVIRONMENT"),
            Task(
                4,
                "environment_texture",
                "load_textures",
                "ENVIRONMENT's filters and wrapping, no mipmaps",
            ),
            Task(5, "base_texture", "build_scene_graph", "the base wears METAL"),
            Task(
                6,
                "mirror_texture",
                "render_mirror",
                "the mirror's shader, sampler uniform and texture",
            ),
            Task(7, "mirror_quad", "render_mirror", "the mirror's corners and texture coordinates"),
            Task(8, "passes", "display", "both passes, in order, every frame"),
        ),
        package=__name__,
        home=HOME,
        solution=HOME.parents[2] / "labs" / "solutions" / "lab20_mirror.py",
        options={
            "mirror_x": (-7.5, -7.0, -6.5),
            "y0": (-3.5, -3.0, -2.5),
            "height": (7.0, 7.5, 8.0, 8.5),
            "z0": (-6.5, -6.0, -5.5),
            "width": (7.0, 7.5, 8.0, 8.5),
            "base_angle": (-50.0, -45.0, -40.0, -35.0, -30.0, -25.0, -20.0),
            "lower_angle": (20.0, 25.0, 30.0, 35.0, 40.0),
            "upper_angle": (-85.0, -80.0, -75.0, -70.0, -65.0),
        },
        defaults={
            "mirror_x": -7.0,
            "y0": -3.0,
            "height": 8.0,
            "z0": -6.0,
            "width": 8.0,
            "base_angle": -35.0,
            "lower_angle": 30.0,
            "upper_angle": -75.0,
        },
        declared=(),
    )
)
