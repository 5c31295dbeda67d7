"""The cube-map lab's judge, declared: its tasks, the student functions each judges, the
checks its verdict rests on and the lab's numbers (the sphere's centre). The GLSL tasks
are judged by the value probe, one call each (:func:`.probe.judge`: the face and (s, t) on
the checker's secret inputs, slips named by the formulas' variants); every other task, and
every hint, by :mod:`mirrorlab.labs.trusted.lab_judge`. Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec
from mirrorlab.labs.lab_cubemap.variant import cube_center
from mirrorlab.labs.trusted import lab_judge as J
from mirrorlab.labs.trusted import probe
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    picture,
)
from mirrorlab.labs.trusted.variants import Variant

GLSL_FUNCTIONS = ("cube_face", "cube_face_st")
MIN_FILTER = 0x2801
MIPMAP_FILTERS = {
    0x2700: "GL_NEAREST_MIPMAP_NEAREST",
    0x2701: "GL_LINEAR_MIPMAP_NEAREST",
    0x2702: "GL_NEAREST_MIPMAP_LINEAR",
    0x2703: "GL_LINEAR_MIPMAP_LINEAR",
}
NEAREST_OBJECT = 1.0
"""Every object of the scene is at least this far from the sphere's centre (its surface
is at 1): a near plane beyond it loses what the sphere would reflect."""
FARTHEST_OBJECT = 9.7
"""The picture behind the scene is this far along -z from any centre of the variants."""


def judge_face(student: Evidence) -> tuple[bool, str]:
    """task 1 (face_selection): ``cube_face`` by the value probe (:func:`.probe.judge`)."""
    return probe.judge(student, "cubemap", "cube_face")


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    """task 2 (face_coordinates): ``cube_face_st`` by the value probe
    (:func:`.probe.judge`), given the right face whatever ``cube_face`` picks."""
    return probe.judge(student, "cubemap", "cube_face_st")


FACES = J.Events("draw", who="draw_scene", within="capture_cube")
COPIES = J.Events("copy", within="capture_cube")
VIEWER = J.Events("draw", who="draw_scene", within="display", outside="capture_cube", last=True)
SPHERE = J.Events("draw", who="draw_sphere", within="display", outside="capture_cube", last=True)
KEEP = (NEAREST_OBJECT, FARTHEST_OBJECT)
"""Along each face camera's view: what its near and far planes must keep."""


def numbers(variant: Variant) -> dict[str, Any]:
    """The lab's numbers: the sphere's centre, where the six cameras sit."""
    return {"center": cube_center(variant)}


def _eyes(run: J.Run) -> Any:
    """Where the face cameras sit, when they all sit at one point."""
    eyes = []
    for draw in FACES.find(run.student):
        modelview = np.asarray(draw["modelview"], dtype=np.float64)
        eyes.append(-modelview[:3, :3].T @ modelview[:3, 3])
    if not eyes or not np.allclose(eyes, eyes[0], atol=1e-3):
        return None
    return eyes[0]


def regions(run: J.Run) -> dict[str, np.ndarray | None]:
    """The sphere's pixels (where the reference's check values cover the frame)."""
    mask = run.reference.arrays.get("values_mask")
    frame = run.reference.image("frame")
    if not isinstance(mask, np.ndarray) or frame is None or mask.shape != frame.shape[:2]:
        return {}
    return {"sphere": _grow(mask)}


def mipmapped_frame(run: J.Run) -> tuple[Evidence, Evidence]:
    """The frames as the whole-frame comparison sees them: where the sphere samples
    mipmaps made after the six faces (the handout allows it), both pictures blurred alike
    there, as a trilinear filter sees them."""
    sphere = regions(run).get("sphere")
    mine, theirs = run.student.image("frame"), run.reference.image("frame")
    if sphere is None or mine is None or theirs is None or not _mipmapped(run.student):
        return run.student, run.reference
    mine, theirs = mine.copy(), theirs.copy()
    mine[sphere] = _blurred(run.student.image("frame"))[sphere]  # type: ignore[arg-type]
    theirs[sphere] = _blurred(run.reference.image("frame"))[sphere]  # type: ignore[arg-type]
    return (
        Evidence(
            run.student.lab, run.student.status, arrays={"frame": mine}, state=run.student.state
        ),
        Evidence(run.reference.lab, arrays={"frame": theirs}),
    )


def _mipmapped(student: Evidence) -> bool:
    spheres = SPHERE.find(student)
    if not spheres:
        return False
    params = spheres[-1].get("sampling") or {}
    return (params.get(str(MIN_FILTER)) or {}).get("value") in MIPMAP_FILTERS and bool(
        spheres[-1].get("mipmaps_fresh")
    )


def _blurred(image: np.ndarray, radius: int = 2) -> np.ndarray:
    """A box blur of ``image`` ``(h, w, 3)`` uint8 over (2 radius + 1)^2 pixels."""
    padded = np.pad(
        image.astype(np.float64), ((radius, radius), (radius, radius), (0, 0)), mode="edge"
    )
    total = np.zeros(image.shape, dtype=np.float64)
    height, width = image.shape[:2]
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            total += padded[dy : dy + height, dx : dx + width]
    return np.clip(total / (2 * radius + 1) ** 2 + 0.5, 0, 255).astype(np.uint8)


def _grow(mask: np.ndarray, by: int = 2) -> np.ndarray:
    grown = mask.copy()
    for _ in range(by):
        shifted = grown.copy()
        shifted[1:] |= grown[:-1]
        shifted[:-1] |= grown[1:]
        shifted[:, 1:] |= grown[:, :-1]
        shifted[:, :-1] |= grown[:, 1:]
        grown = shifted
    return grown


JUDGE = J.LabJudge(
    lab="cubemap",
    roles={"cube_texture": "cube_texture"},
    numbers=numbers,
    regions=regions,
    frame=mipmapped_frame,
    frame_task="live_frame",
    owner={"sphere": ("live_frame", "the sphere's picture")},
    glsl_functions=GLSL_FUNCTIONS,
    tasks=(
        J.TaskRule("face_selection", (), checks=(J.Glsl(judge_face),), region="sphere"),
        J.TaskRule("face_coordinates", (), checks=(J.Glsl(judge_coordinates),), region="sphere"),
        J.TaskRule(
            "capture_cameras",
            ("capture_cube",),
            checks=(
                J.Happens(FACES, "the faces' drawing", count=True),
                J.CopyOf(
                    _eyes,
                    "center",
                    "the cameras sit at the sphere's centre {whose}, not yours: your sphere's "
                    "centre is {mine}",
                ),
                J.SameView(FACES, "the face cameras", KEEP),
                J.SameViewport(FACES, "the face"),
            ),
            region="sphere",
        ),
        J.TaskRule(
            "capture_copy",
            ("capture_cube",),
            checks=(
                J.Happens(COPIES, "the copies into the faces"),
                J.CopiesAfterDraws(COPIES, FACES),
                J.SameCopies(COPIES),
                J.SamePicture("the faces", array="cube_faces"),
            ),
            explain=(J.SameClears(FACES, "face"),),
            region="sphere",
            after=("capture_cameras",),
            after_first=True,
        ),
        J.TaskRule(
            "live_frame",
            ("display", "capture_cube"),
            checks=(
                J.Stopped("display"),
                J.Happens(SPHERE, "the sphere's drawing"),
                J.SameOrder("display"),
                J.SameClears(VIEWER, "the frame"),
                J.SameViewport(VIEWER, "the scene"),
                J.SameMipmaps(SPHERE, "cube_texture"),
                J.SameView(VIEWER, "the viewer's view"),
            ),
        ),
    ),
)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    return J.judge(JUDGE, spec, student, reference, context)


def faces_grid(faces: np.ndarray | None, height: int) -> np.ndarray | None:
    """The six faces in GL order as a 3 x 2 grid (+X -X +Y over -Y +Z -Z), in a square
    picture ``height`` on a side."""
    if not isinstance(faces, np.ndarray) or faces.ndim != 4 or faces.shape[0] != 6:
        return None
    side = height // 3
    index = np.linspace(0, faces.shape[1] - 1, side).astype(int)
    out = np.full((height, height, 3), 255, dtype=np.uint8)
    top = (height - 2 * side) // 2
    for face in range(6):
        row, col = divmod(face, 3)
        out[top + row * side : top + (row + 1) * side, col * side : (col + 1) * side] = faces[face][
            index
        ][:, index]
    return out


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture(
        [
            (student.image("frame"), ref),
            (
                faces_grid(student.arrays.get("cube_faces"), shape[0]),
                faces_grid(reference.arrays.get("cube_faces"), shape[0]),
            ),
        ],
        shape,
    )
