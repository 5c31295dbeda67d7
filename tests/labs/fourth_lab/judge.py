"""The quad lab's judge, declared: the frame cleared as the solution clears it before the
quad, and the quad the solution draws; every hint is the shared modules'
(:mod:`mirrorlab.labs.trusted.lab_judge`)."""

from __future__ import annotations

import numpy as np

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted import lab_judge as J
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import Context, TaskResult, picture

QUAD = J.Events("draw", who="primitive", within="draw_quad", at_least=3, last=True)

JUDGE = J.LabJudge(
    lab="quad",
    roles={},
    frame_task="quad",
    tasks=(
        J.TaskRule(
            "clear",
            ("clear_background",),
            checks=(J.Happens(QUAD, "the quad's drawing"), J.SameClears(QUAD, "the frame")),
        ),
        J.TaskRule(
            "quad",
            ("draw_quad",),
            checks=(J.Happens(QUAD, "the quad's drawing"), J.SamePrimitive(QUAD, "quad")),
        ),
    ),
)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    return J.judge(JUDGE, spec, student, reference, context)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (64, 64)
    return picture([(student.image("frame"), ref)], shape)
