"""The cube-map lab: a chrome sphere among coloured objects, drawn through the
student's GLSL face selection from a cube map the student captures live, six cameras
at the sphere's centre. A variant moves the sphere's centre."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import LabSpec, Task, register

HOME = Path(__file__).resolve().parent

SPEC = register(
    LabSpec(
        name="cubemap",
        folder="lab_cubemap",
        title="Cube mapping: face selection and a live cube map",
        setup=("create_cube_texture",),
        frame="display",
        functions=("create_cube_texture", "capture_cube", "display"),
        tasks=(
            Task(1, "face_selection", "cube_face", "the face by the major axis in the shader"),
            Task(2, "face_coordinates", "cube_face_st", "s and t on the face in the shader"),
            Task(3, "capture_cameras", "capture_cube", "six 90-degree cameras, one a face"),
            Task(4, "capture_copy", "capture_cube", "each picture copied into its face"),
            Task(5, "live_frame", "display", "the capture before the sphere, every frame"),
        ),
        package=__name__,
        home=HOME,
        solution=HOME.parents[2] / "labs" / "solutions" / "lab_cubemap.py",
        options={
            "center_x": (-0.4, -0.2, 0.0, 0.2, 0.4),
            "center_y": (0.0, 0.15, 0.3),
            "center_z": (-0.4, -0.2, 0.0, 0.2, 0.4),
        },
        defaults={"center_x": 0.0, "center_y": 0.0, "center_z": 0.0},
        declared=("CUBE_MAP_GLSL",),
    )
)
