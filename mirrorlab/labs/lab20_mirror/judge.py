"""Lab 20's judge, declared: its tasks, the student functions each judges, the checks its
verdict rests on, and the lab's numbers (the variant's mirror). The reasoning, and every
hint, is :mod:`mirrorlab.labs.trusted.lab_judge`'s. Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs import LabSpec
from mirrorlab.labs.lab20_mirror.trusted import Lab20
from mirrorlab.labs.lab20_mirror.variant import lab20_geometry
from mirrorlab.labs.trusted import lab_judge as J
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import Context, TaskResult, picture
from mirrorlab.labs.trusted.variants import Variant

CAPTURE = J.Events("draw", who="draw_scene", within="create_mirror")
COPY = J.Events("copy", within="create_mirror")
VIEWER = J.Events("draw", who="draw_scene", within="display", outside="create_mirror")
MIRROR = J.Events("draw", who="primitive", within="render_mirror", at_least=3, last=True)
MATRICES = frozenset(
    {"glMatrixMode", "glLoadIdentity", "glOrtho", "glFrustum", "gluPerspective", "gluLookAt"}
    | {"glTranslate", "glRotate", "glScale", "glLoadMatrix", "glMultMatrix", "gluOrtho2D"}
    | {"glPushMatrix", "glPopMatrix", "lab.set_viewer"}
)
COPYING = frozenset({"glActiveTexture", "glBindTexture", "glCopyTexImage2D"})
COPYING |= {"glCopyTexSubImage2D", "lab.draw_scene"}
SHADING = frozenset({"glUseProgram", "glUniform", "glActiveTexture", "glBindTexture"})
QUAD = frozenset({"glBegin", "glEnd", "glVertex", "glTexCoord"}) | MATRICES
ROBOT_DEPTHS, BEHIND_GLASS = (4.5, 9.5), (-0.2,)
"""Along the capture camera's view (from the glass): where the robot lies, and the frame
behind the glass, which the near and far planes must keep and leave out."""


def numbers(variant: Variant) -> dict[str, Any]:
    """The lab's numbers for ``variant``: the mirror's corners and the capture's x, y and w
    rows of projection @ view (what a copy of another variant's file carries)."""
    g = lab20_geometry(variant)
    clip = math3d.ortho(*g["extents"]) @ math3d.look_at(g["eye"], (0, 0, 0), (0, 1, 0))
    return {"corners": g["corners"], "capture": clip[[0, 1, 3]]}


def _capture_rows(run: J.Run) -> Any:
    draws = CAPTURE.find(run.student)
    if not draws:
        return None
    projection, modelview = (np.asarray(draws[0][k]) for k in ("projection", "modelview"))
    return (projection @ modelview)[[0, 1, 3]]


def regions(run: J.Run) -> dict[str, np.ndarray | None]:
    """The mirror's pixels (the variant's, and wherever the file drew its quad)."""
    projection, view = Lab20.viewer_for(run.size)
    mirror = J.polygon_region(np.array(run.numbers["corners"]), projection @ view, run.size)
    for draw in MIRROR.find(run.student):
        mirror = mirror | J.drawn_region(draw, run.size)
    return {"mirror": mirror}


def clamp_rim(run: J.Run) -> np.ndarray | None:
    """The mirror's outline, 3 pixels either side, when ENVIRONMENT wraps with GL_CLAMP
    (which the handout accepts): its linear filter darkens a thin rim there with the border
    colour, not a mark of the file's; else None."""
    params = run.student.state.get("environment_parameters") or {}
    if J.GL_CLAMP not in (params.get("GL_TEXTURE_WRAP_S"), params.get("GL_TEXTURE_WRAP_T")):
        return None
    projection, view = Lab20.viewer_for(run.size)
    return J.convex_rim(np.array(run.numbers["corners"]), projection @ view, run.size, 3)


JUDGE = J.LabJudge(
    lab="lab20",
    roles={"environment": "tex_ids[ENVIRONMENT]", "metal": "tex_ids[METAL]"},
    programs={"texture_shader": "lab.textureShader"},
    uniforms={"texture_sampler": "lab.texSampler"},
    numbers=numbers,
    regions=regions,
    frame_task="passes",
    owner={"mirror": ("mirror_quad", "the mirror's picture")},
    allowed=clamp_rim,
    tasks=(
        J.TaskRule(
            "capture_camera",
            ("create_mirror",),
            checks=(
                J.Happens(CAPTURE, "the capture's drawing"),
                J.CopyOf(
                    _capture_rows,
                    "capture",
                    "this capture is {whose}, not yours: glOrtho and gluLookAt for your "
                    "mirror (see the handout's corners)",
                ),
                J.SameView(CAPTURE, "the capture's view", ROBOT_DEPTHS, BEHIND_GLASS),
            ),
            families=MATRICES,
            region="mirror",
        ),
        J.TaskRule(
            "capture_scene",
            ("create_mirror",),
            checks=(
                J.Happens(CAPTURE, "the capture's drawing"),
                J.SamePicture("the capture's picture", events=COPY),
            ),
            explain=(
                J.SameClears(CAPTURE, "the capture"),
                J.SameViewport(CAPTURE, "the capture"),
            ),
            region="mirror",
            after=("capture_camera", "base_texture", "capture_copy"),
        ),
        J.TaskRule(
            "capture_copy",
            ("create_mirror",),
            checks=(
                J.Happens(COPY, "the copy into ENVIRONMENT"),
                J.CopiesAfterDraws(COPY, CAPTURE),
                J.SameCopies(COPY),
            ),
            families=COPYING,
        ),
        J.TaskRule(
            "environment_texture",
            ("load_textures",),
            checks=(J.SameTexture("environment"),),
        ),
        J.TaskRule(
            "base_texture",
            ("build_scene_graph",),
            checks=(
                J.SameArgument(
                    J.Events("draw", who="draw_scene"),
                    ("textures", "base"),
                    'robot["base"].texture',
                ),
            ),
        ),
        J.TaskRule(
            "mirror_texture",
            ("render_mirror",),
            checks=(
                J.Stopped("render_mirror"),
                J.Happens(MIRROR, "the mirror's quad"),
                J.SameSampling(MIRROR, "texture_shader", "lab.texSampler"),
            ),
            families=SHADING,
            region="mirror",
            after=("environment_texture",),
        ),
        J.TaskRule(
            "mirror_quad",
            ("render_mirror",),
            checks=(
                J.Stopped("render_mirror"),
                J.Happens(MIRROR, "the mirror's quad"),
                J.SamePrimitive(MIRROR, "mirror quad", corners="corners"),
            ),
            families=QUAD,
            region="mirror",
            after=("passes",),
        ),
        J.TaskRule(
            "passes",
            ("display", "create_mirror", "render_mirror"),
            checks=(
                J.Stopped("display"),
                J.Happens(VIEWER, "the camera pass"),
                J.SameOrder("display"),
                J.SameClears(VIEWER, "the frame"),
                J.SameViewport(VIEWER, "the scene"),
                J.SameView(VIEWER, "the viewer's view"),
            ),
            families=None,
        ),
    ),
)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    return J.judge(JUDGE, spec, student, reference, context)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    """Frame and capture: student | reference | difference."""
    ref_frame = reference.image("frame")
    shape = ref_frame.shape[:2] if ref_frame is not None else (256, 256)
    return picture(
        [
            (student.image("frame"), ref_frame),
            (student.image("capture"), reference.image("capture")),
        ],
        shape,
    )
