"""The quad lab's judge: the last frame's clear, then the frame against the reference."""

from __future__ import annotations

import numpy as np

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    Verdicts,
    judge_frame,
    picture,
    results,
    wrong_clear_colour,
)
from tests.labs.fourth_lab.variant import clear_colour

GL_COLOR_BUFFER_BIT = 0x4000


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    clears = [
        e
        for e in student.events("clear", within="clear_background")
        if int(e.get("mask", 0)) & GL_COLOR_BUFFER_BIT
    ]
    colour = clear_colour(context.variant)
    if not clears:
        clear = (False, "clear_background() clears nothing: glClearColor, then glClear")
    elif wrong := wrong_clear_colour(clears[-1], colour, student):
        clear = (
            False,
            f"the frame is cleared to {wrong}; yours is ({', '.join(f'{c:g}' for c in colour)})",
        )
    else:
        clear = (True, "")
    quads = student.events("draw", who="primitive", within="draw_quad")
    quad = (
        (True, "")
        if quads
        else (False, "draw_quad() draws nothing: glBegin(GL_QUADS), four glVertex2f, glEnd")
    )
    verdicts: Verdicts = {"clear": clear, "quad": quad}
    frame = reference.image("frame")
    regions: dict[str, np.ndarray | None] = {"clear": None, "quad": None}
    if frame is not None:
        verdicts = judge_frame(verdicts, student, reference, regions, "quad", {})
    return results(spec, student, verdicts)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (64, 64)
    return picture([(student.image("frame"), ref)], shape)
