"""The labs: each lab's tasks and the functions of the student's file they live in (here),
and three packages whose split is the labs' trust boundary:

- :mod:`mirrorlab.labs.student` runs in the sandbox with the student's file: stand-ins for
  OpenGL, GLU and the lab's kit that send every call to the checker. It imports nothing
  of the rest of mirrorlab, and is all of mirrorlab a sandbox can see.
- :mod:`mirrorlab.labs.trusted` runs outside: the sandbox, the executor that validates and
  runs each call in its own GL context, the judges, the checker, grading, release and the
  reports.
- :mod:`mirrorlab.labs.content` holds what students are given: each lab's handout,
  starter and reference data (package data). The teachers' solutions are not in the
  package; they are in the repository's ``labs/solutions/``.

Importing this package loads no OpenGL.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Task:
    """One task of a lab: its number and id, the function of the student's file it lives
    in, and a title."""

    number: int
    id: str
    function: str
    title: str

    @property
    def name(self) -> str:
        """The task's one name, in hints, reports, CSVs and HTML alike: its number in the
        handout and its id, ``task 1 (capture_camera)``."""
        return f"task {self.number} ({self.id})"


@dataclass(frozen=True)
class LabSpec:
    """A lab: ``name`` (what the command line takes), ``folder`` (its content's and its
    solution's name, also accepted on the command line), the functions the student's file
    defines (``setup`` run once, then ``frame`` every frame), and its tasks in the
    handout's order."""

    name: str
    folder: str
    title: str
    setup: tuple[str, ...]
    frame: str
    functions: tuple[str, ...]
    tasks: tuple[Task, ...]

    def task(self, task_id: str) -> Task:
        return next(t for t in self.tasks if t.id == task_id)

    def task_name(self, task_id: str) -> str:
        """The name of the task ``task_id`` (:attr:`Task.name`), for a hint that points to
        it."""
        return self.task(task_id).name


LABS: dict[str, LabSpec] = {
    "lab20": LabSpec(
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
    ),
    "spheremap": LabSpec(
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
    ),
    "cubemap": LabSpec(
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
    ),
}

ALIASES = {spec.folder: name for name, spec in LABS.items()}


def task_name(lab: str, task_id: str) -> str:
    """The name of ``lab``'s task ``task_id`` (``task 8 (passes)``): how a hint points to
    another task, so that hints, CSVs and reports name a task one way."""
    return LABS[lab].task_name(task_id)


def find_lab(name: str) -> LabSpec:
    """The lab called ``name`` (``lab20``, ``spheremap``, ``cubemap``, or a folder name such
    as ``lab20_mirror``); ValueError naming the choices otherwise."""
    key = ALIASES.get(name.rstrip("/").split("/")[-1], name)
    if key not in LABS:
        choices = ", ".join([*LABS, *ALIASES])
        raise ValueError(f"LAB: unknown lab {name!r}; expected one of {choices}")
    return LABS[key]
