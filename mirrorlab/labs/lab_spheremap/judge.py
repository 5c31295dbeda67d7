"""The sphere-map lab's judge, declared: its tasks, the student functions each judges, the
checks its verdict rests on and the lab's numbers (the shader cone's side, texgen's unit).
The GLSL tasks are judged by the value probe, one call each (:func:`.probe.judge`: the
reflection vector and (s, t) on the checker's secret inputs, slips named by the formulas'
variants); every other task, and every hint, by :mod:`mirrorlab.labs.trusted.lab_judge`.
Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted import lab_judge as J
from mirrorlab.labs.trusted import probe
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    picture,
)
from mirrorlab.labs.trusted.variants import Variant

GL_SPHERE_MAP = 0x2402
GLSL_FUNCTIONS = ("reflect_eye", "sphere_map_st")


def judge_reflection(student: Evidence) -> tuple[bool, str]:
    """task 1 (reflection): ``reflect_eye`` by the value probe (:func:`.probe.judge`)."""
    return probe.judge(student, "spheremap", "reflect_eye")


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    """task 2 (sphere_coordinates): ``sphere_map_st`` by the value probe (:func:`.probe.judge`)."""
    return probe.judge(student, "spheremap", "sphere_map_st")


TEXGEN_DRAW = J.Events("draw", who="draw_cone_fixed_function", last=True)
SHADER_DRAW = J.Events("draw", who="draw_cone_shader", within="display", last=True)
TEXGEN_LEAVES = J.Events("leave", function="draw_cone_texgen", last=True)
COORDINATES = ("s", "t")
SWITCHES = ("GL_TEXTURE_GEN_S", "GL_TEXTURE_GEN_T")


def numbers(variant: Variant) -> dict[str, Any]:
    """The lab's numbers: which side the shader's cone takes, texgen's unit, and both."""
    side, unit = str(variant["shader_side"]), int(variant["unit"])
    return {"side": side, "unit": unit, "variant": (side, unit)}


def _columns(run: J.Run, shader: bool) -> slice:
    width, half = run.size[0], run.size[0] // 2
    left = (run.numbers["side"] == "left") == shader
    return slice(0, half) if left else slice(half, width)


def _units(run: J.Run, key: str, value: Any = None) -> set[int]:
    """The texture units where ``key`` (a switch, or ``texgen_s``) is on (or holds
    ``value``) when the texgen cone is drawn."""
    draws = TEXGEN_DRAW.find(run.student)
    units = ((draws[-1].get("state") or {}).get("units") or {}) if draws else {}
    return {
        int(u)
        for u, entry in units.items()
        if key in entry and (value is None or (entry[key] or {}).get("value") == value)
    }


def _observed(run: J.Run) -> tuple[str, int] | None:
    """(the shader cone's side, texgen's one unit), when the calls show both."""
    shader, units = SHADER_DRAW.find(run.student), _units(run, "GL_TEXTURE_GEN_S")
    if not shader or len(units) != 1:
        return None
    left = (shader[-1].get("viewport") or [0])[0] < run.size[0] // 2
    return ("left" if left else "right", units.pop())


def regions(run: J.Run) -> dict[str, np.ndarray | None]:
    """The shader cone's half of the frame and the texgen cone's."""
    width, height = run.size
    found: dict[str, np.ndarray | None] = {}
    for name, shader in (("shader", True), ("texgen", False)):
        mask = np.zeros((height, width), dtype=bool)
        mask[:, _columns(run, shader)] = True
        found[name] = mask
    return found


SHARED = (
    "this file sets up texgen for units {extra} as well as your unit {mine}: a file made for "
    "several variants at once; set up yours alone"
)

JUDGE = J.LabJudge(
    lab="spheremap",
    roles={"launch": "launch", "backdrop_texture": "the backdrop's picture"},
    numbers=numbers,
    regions=regions,
    frame_task="side_by_side",
    glsl_functions=GLSL_FUNCTIONS,
    tasks=(
        J.TaskRule("reflection", (), checks=(J.Glsl(judge_reflection),), region="shader"),
        J.TaskRule("sphere_coordinates", (), checks=(J.Glsl(judge_coordinates),), region="shader"),
        J.TaskRule(
            "texgen_setup",
            ("setup_texgen",),
            checks=(
                J.Happens(TEXGEN_DRAW, "the texgen cone's drawing"),
                J.OneVariant(lambda run: _units(run, "texgen_s", GL_SPHERE_MAP), "unit", SHARED),
                J.SameSeen(TEXGEN_DRAW, {"mode_s": "texgen for s", "mode_t": "texgen for t"}),
                J.SameUnits(TEXGEN_DRAW, "when the texgen cone is drawn", texgen=COORDINATES),
            ),
            region="texgen",
            after=("texgen_draw",),
        ),
        J.TaskRule(
            "texgen_draw",
            ("draw_cone_texgen",),
            checks=(
                J.Happens(TEXGEN_DRAW, "the texgen cone's drawing"),
                J.OneVariant(lambda run: _units(run, "GL_TEXTURE_GEN_S"), "unit", SHARED),
                J.SameSeen(
                    TEXGEN_DRAW,
                    {
                        "gen_s": "texgen for s",
                        "gen_t": "texgen for t",
                        "texture": "the texture bound",
                    },
                ),
                J.SameUnits(TEXGEN_DRAW, "when the texgen cone is drawn", switches=SWITCHES),
                J.SameUnits(TEXGEN_LEAVES, "when draw_cone_texgen() returns", switches=SWITCHES),
            ),
            region="texgen",
        ),
        J.TaskRule(
            "side_by_side",
            ("display", "draw_cone_texgen"),
            checks=(
                J.Stopped("display"),
                J.CopyOf(
                    _observed,
                    "variant",
                    "this file is made {whose}: your variant draws the shader's cone on the "
                    "side and sets up texgen on the unit your handout names {mine}",
                ),
                J.SameDraws(
                    "display", ("draw_cone_shader", "draw_cone_fixed_function", "draw_backdrop")
                ),
                J.SameView(SHADER_DRAW, "the shader's cone's view"),
                J.SameView(TEXGEN_DRAW, "the texgen cone's view"),
                J.SamePicture(
                    "the shader's cone's half",
                    array="frame",
                    columns=lambda run: _columns(run, True),
                    after=("reflection", "sphere_coordinates"),
                ),
                J.SamePicture(
                    "the texgen cone's half",
                    array="frame",
                    columns=lambda run: _columns(run, False),
                    after=("texgen_setup", "texgen_draw"),
                ),
            ),
        ),
    ),
)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    return J.judge(JUDGE, spec, student, reference, context)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture([(student.image("frame"), ref)], shape)
