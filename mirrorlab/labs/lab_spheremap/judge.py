"""The sphere-map lab's judge, declared: its tasks, the student functions each judges, the
checks its verdict rests on and the lab's numbers (the shader cone's side, texgen's unit).
The GLSL tasks are judged by the values the student's functions write (the reflection
vector and (s, t) at every pixel of the cone and on the value probe's inputs, against the
formulas and the usual slips: :func:`judge_reflection`, :func:`judge_coordinates`); every
other task, and every hint, by :mod:`mirrorlab.labs.trusted.lab_judge`. Numpy only."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from mirrorlab.envmap import sphere_map
from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted import lab_judge as J
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    INTEGER_HALF,
    Context,
    TaskResult,
    glsl_body,
    picture,
)
from mirrorlab.labs.trusted.probe import INPUTS, slip
from mirrorlab.labs.trusted.variants import Variant

GL_SPHERE_MAP = 0x2402
GLSL_FUNCTIONS = ("reflect_eye", "sphere_map_st")


def _best(values: np.ndarray, candidates: dict[str, np.ndarray], tolerance: float) -> str:
    """The candidate that ``values`` ``(n, k)`` match on at least 98% of rows, or ''."""
    for name, predicted in candidates.items():
        if np.mean(np.abs(values - predicted).max(-1) <= tolerance) >= 0.98:
            return name
    return ""


def _cone_values(
    student: Evidence, key: str, function: str, width: int = 3
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | str:
    """The values ``key`` the student's ``function`` gave on the cone's pixels
    ``(pixels, width)``, with the view direction u and normal n there ``(pixels, 3)``; or
    the hint when there are none, or when they are not all finite."""
    problem = student.state.get("values_error")
    if isinstance(problem, dict):
        return str(problem.get("message", ""))
    if (
        "SPHERE_MAP_GLSL" not in (student.state.get("declared") or [])
        and "values_mask" not in student.arrays
    ):
        return "SPHERE_MAP_GLSL is missing: keep the string of GLSL the starter has"
    mask = student.arrays.get("values_mask")
    if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.ndim != 2 or mask.sum() < 50:
        return "the cone could not be drawn with SPHERE_MAP_GLSL"
    shape = (*mask.shape, 3)
    values, u, n = (student.floats(f"values_{name}", shape) for name in (key, "u", "n"))
    if values is None or u is None or n is None:
        return "the cone could not be drawn with SPHERE_MAP_GLSL"
    values, u, n = values[mask][:, :width], u[mask], n[mask]
    if not np.all(np.isfinite(values)):
        return f"{function} gives NaN or infinity on the cone"
    return values, u, n


def _probed(student: Evidence, function: str) -> str:
    """The slip the value probe finds in the student's ``function`` (:func:`.probe.slip`):
    'right', a slip's name, or '' (none known, or no probe values)."""
    return slip(function, student.floats(f"probe_{function}", (INPUTS[function][0].shape[0], 4)))


def judge_reflection(student: Evidence) -> tuple[bool, str]:
    cone = _cone_values(student, "r", "reflect_eye")
    if isinstance(cone, str):
        return False, cone
    r, u, n = cone
    right = u - 2 * (u * n).sum(-1, keepdims=True) * n
    if _best(
        r,
        {
            "right": right,
            "normalised": right / np.maximum(np.linalg.norm(right, axis=-1, keepdims=True), 1e-9),
        },
        2e-3,
    ):
        return True, ""
    # the slip is named by the probe's values, on inputs with n.u of both signs: a
    # clamped dot product is r = u on the cone only, as is r = u itself
    hints = {
        "sign": "r points the wrong way (it is -r): the reflection is u - 2 (n.u) n, with u "
        "the direction from the eye to the point",
        "no_two": "the factor 2 is missing: r = u - 2 (n.u) n",
        "plus": "the sign of the 2 (n.u) n term: r = u - 2 (n.u) n",
        "unreflected": "reflect_eye returns u unchanged: reflect it about n, u - 2 (n.u) n",
        "normal": "reflect_eye returns the normal: r = u - 2 (n.u) n",
        "clamped": "dot(n, u) is clamped (clamp or max): on the cone u points at the "
        "surface, so n.u is negative, the clamp makes it 0 and r = u; use "
        "dot(n, u) as it is: r = u - 2 (n.u) n",
        "abs_dot": "abs(dot(n, u)): on the cone n.u is negative and its sign matters; use "
        "dot(n, u) as it is: r = u - 2 (n.u) n",
    }
    found = _probed(student, "reflect_eye")
    if found in hints:
        return False, hints[found]
    return False, "reflect_eye's r differs from u - 2 (n.u) n on the cone"


PLUS_ONE = re.compile(
    r"\bz\s*\+\s*1\b|\b1(\.0*)?\s*\+\s*\w+\.z\b|"
    r"vec3\(\s*0(\.0*)?\s*,\s*0(\.0*)?\s*,\s*1(\.0*)?\s*\)"
)
"""The + 1 on r.z (or r + (0, 0, 1), the viewer's direction), written."""


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    cone = _cone_values(student, "st", "sphere_map_st", width=2)
    if isinstance(cone, str):
        return False, cone
    st, u, n = cone
    r = u - 2 * (u * n).sum(-1, keepdims=True) * n
    if _best(st, {"right": np.stack(sphere_map(r), -1)}, 2e-3):
        return True, ""
    hints = {
        "swap": "s and t swapped: s comes from r.x and t from r.y",
        "flip_t": "t upside down: t = r.y / m + 1/2",
        "flip_s": "s mirrored: s = r.x / m + 1/2",
        "no_plus_one": "m must use (r.z + 1): m = 2 sqrt(r.x^2 + r.y^2 + (r.z + 1)^2), the "
        "normal of the mirror ball halfway between r and the viewer",
        "unnormalised": "the halfway vector (r.x, r.y, r.z + 1) is not normalised: s and t "
        "are its x and y over its length, m = 2 sqrt(r.x^2 + r.y^2 + "
        "(r.z + 1)^2)",
        "minus_one": "the sign of the 1 in m: m = 2 sqrt(r.x^2 + r.y^2 + (r.z + 1)^2), the "
        "halfway vector between r and the viewer at +z",
        "no_two": "the factor 2 in m is missing: m = 2 sqrt(r.x^2 + r.y^2 + (r.z + 1)^2), or "
        "s and t leave [0, 1]",
        "no_half": "the + 1/2 is missing: s and t must lie in [0, 1], centre (1/2, 1/2)",
    }
    # the slip is named by the probe's values, on reflection vectors of several lengths:
    # on the cone's unit vectors a halfway vector left unnormalised and a missing + 1 give
    # the same (s, t)
    found = _probed(student, "sphere_map_st")
    body = glsl_body(student.source, "sphere_map_st")
    # Read from the source only where values cannot tell two forms apart:
    # - 1/2 in GLSL is 0, so "+ 1/2" gives exactly the numbers of a missing + 1/2;
    # - r normalised first, then its halfway vector left unnormalised, is the very function
    #   of r that m without the + 1 is (rx / 2|r| + 1/2 for any r).
    if found == "no_half" and INTEGER_HALF.search(body):
        return False, (
            "1/2 in GLSL is integer division, 0, so the + 1/2 adds nothing: write "
            "0.5 (s = r.x / m + 0.5, t = r.y / m + 0.5)"
        )
    if found == "no_plus_one" and PLUS_ONE.search(body):
        found = "unnormalised"
    if found in hints:
        return False, hints[found]
    return False, "sphere_map_st differs from Hoff's s = r.x/m + 1/2, t = r.y/m + 1/2 on the cone"


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
