"""The sphere-map lab's judge: the student's GLSL by the values it writes (the reflection
vector and (s, t) at every pixel of the cone, against the formulas and the usual slips),
texgen by the state at the fixed-function draw and the calls that set it (which unit was
active), and the frame against the reference's, half by half and as a whole. Numpy only."""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from mirrorlab.envmap import sphere_map
from mirrorlab.labs import LabSpec, task_name
from mirrorlab.labs.lab_spheremap.trusted import SphereMapLab
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    INTEGER_HALF,
    Context,
    TaskResult,
    Verdicts,
    differing,
    glsl_body,
    judge_frame,
    picture,
    results,
    same_picture,
    stopped_hint,
    viewer_camera,
    where,
)
from mirrorlab.labs.trusted.probe import INPUTS, slip

GL_SPHERE_MAP = 0x2402
MODE_NAMES = {
    0x2400: "GL_EYE_LINEAR",
    0x2401: "GL_OBJECT_LINEAR",
    0x2402: "GL_SPHERE_MAP",
    0x8511: "GL_NORMAL_MAP",
    0x8512: "GL_REFLECTION_MAP",
}
GLSL_FUNCTIONS = ("reflect_eye", "sphere_map_st")


def _task(task_id: str) -> str:
    """How a hint names another task of this lab (``task 8 (passes)``)."""
    return task_name("spheremap", task_id)


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


def _texgen_draw(student: Evidence) -> dict[str, Any] | None:
    draws = student.events("draw", who="draw_cone_fixed_function")
    return draws[-1] if draws else None


def _units(event: dict[str, Any]) -> dict[int, dict[str, Any]]:
    units = (event.get("state") or {}).get("units") or {}
    return {int(k): v for k, v in units.items() if isinstance(v, dict)}


def judge_texgen_setup(student: Evidence, unit: int) -> tuple[bool, str]:
    draw = _texgen_draw(student)
    if draw is None:
        return False, (f"not judged: the texgen cone was never drawn, see {_task('texgen_draw')}")
    seen, units = draw.get("seen") or {}, _units(draw)
    hints = []
    for coordinate in ("s", "t"):
        mode = int(seen.get(f"mode_{coordinate}") or 0)
        if mode == GL_SPHERE_MAP:
            continue
        name, upper = MODE_NAMES.get(mode, str(mode)), coordinate.upper()
        call = f"glTexGeni(GL_{upper}, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)"
        elsewhere = [
            (u, e[f"texgen_{coordinate}"])
            for u, e in units.items()
            if u != unit and (e.get(f"texgen_{coordinate}") or {}).get("value") == GL_SPHERE_MAP
        ]
        own = units.get(unit, {}).get(f"texgen_{coordinate}")
        if elsewhere:
            other, setting = elsewhere[0]
            hints.append(
                f"{call} at {student.at(setting.get('line', 0))} set texgen for unit "
                f"{other} (GL_TEXTURE{other} was active then); the cone's texture "
                f"coordinates come from unit {unit}: call glActiveTexture("
                f"GL_TEXTURE{unit}) before it"
            )
        elif own is not None:
            hints.append(
                f"texgen for {coordinate} is {name} ({student.at(own.get('line', 0))}): {call}"
            )
        else:
            active = f", with GL_TEXTURE{unit} active," if unit else ""
            hints.append(
                f"texgen for {coordinate} is {name} (GL's default): {call}{active} in "
                f"setup_texgen()"
            )
    return (not hints), "; ".join(hints)


def judge_texgen_draw(student: Evidence, unit: int) -> tuple[bool, str]:
    draw = _texgen_draw(student)
    if draw is None:
        return False, (
            "draw_cone_texgen() never draws the cone: call lab.draw_cone_fixed_function() there"
        )
    seen, units = draw.get("seen") or {}, _units(draw)
    hints = []
    moved: list[tuple[str, int, int]] = []
    for coordinate in ("s", "t"):
        if seen.get(f"gen_{coordinate}"):
            continue
        cap = f"GL_TEXTURE_GEN_{coordinate.upper()}"
        elsewhere = [(u, e[cap]) for u, e in units.items() if u != unit and cap in e]
        if elsewhere:
            moved.append((coordinate, elsewhere[0][0], elsewhere[0][1].get("line", 0)))
        else:
            hints.append(
                f"texgen for {coordinate} is off while the cone is drawn: glEnable({cap}) first"
            )
    if moved:
        other, line = moved[0][1], moved[0][2]
        which = " and ".join(c for c, _, _ in moved)
        hints.insert(
            0,
            f"texgen for {which} is switched on for unit {other} (glEnable at "
            f"{student.at(line)}, with GL_TEXTURE{other} active), but the cone is "
            f"textured from unit {unit}: glActiveTexture(GL_TEXTURE{unit}) before "
            f"glEnable(GL_TEXTURE_GEN_S) and (GL_TEXTURE_GEN_T)",
        )
    pictures = {student.state.get("launch"), student.state.get("backdrop_texture")} - {None, 0}
    if seen.get("texture") not in pictures:
        launch = student.state.get("launch")
        bound = [
            (u, e["2d"])
            for u, e in units.items()
            if (e.get("2d") or {}).get("value") == launch and launch
        ]
        if bound:
            other, setting = bound[0]
            hints.append(
                f"the launch picture is bound on unit {other} ("
                f"{student.at(setting.get('line', 0))}), but the cone is textured "
                f"from unit {unit}: glActiveTexture(GL_TEXTURE{unit}) before "
                f"glBindTexture"
            )
        else:
            hints.append(
                f"the launch picture is not bound on texture unit {unit} when the cone "
                f"is drawn (glActiveTexture(GL_TEXTURE{unit}); glBindTexture("
                f"GL_TEXTURE_2D, launch))"
            )
    leaves = [
        e
        for e in student.last_frame
        if e.get("kind") == "leave" and e.get("function") == "draw_cone_texgen"
    ]
    if leaves:
        left_on = [
            (u, cap, e[cap])
            for u, e in _units(leaves[-1]).items()
            for cap in ("GL_TEXTURE_GEN_S", "GL_TEXTURE_GEN_T")
            if cap in e
        ]
        if left_on:
            hints.append(
                "texgen left on after the cone: glDisable(GL_TEXTURE_GEN_S) and "
                "(GL_TEXTURE_GEN_T) once it is drawn, or everything drawn later in "
                "the fixed-function pipeline gets sphere-map coordinates too"
            )
    return (not hints), "; ".join(hints)


def _halves(width: int, shader_side: str) -> tuple[slice, slice]:
    half = width // 2
    left, right = slice(0, half), slice(half, width)
    return (left, right) if shader_side == "left" else (right, left)


def judge_side_by_side(
    student: Evidence, reference: Evidence, verdicts: Verdicts, shader_side: str
) -> tuple[bool, str]:
    if hint := stopped_hint(student, "display"):
        return False, hint
    frame, ref = student.image("frame"), reference.image("frame")
    if frame is None or ref is None or frame.shape != ref.shape:
        return False, "display() drew no frame"
    width = ref.shape[1]
    texgen_side = "right" if shader_side == "left" else "left"
    shader_cols, texgen_cols = _halves(width, shader_side)
    shader_ok = same_picture(frame[:, shader_cols], ref[:, shader_cols])
    texgen_ok = same_picture(frame[:, texgen_cols], ref[:, texgen_cols])
    if shader_ok and texgen_ok:
        return True, ""
    half = width // 2
    if same_picture(frame[:, :half], ref[:, half : 2 * half]) and same_picture(
        frame[:, half : 2 * half], ref[:, :half]
    ):
        return False, (
            f"the halves are swapped: your variant puts the shader's cone on the "
            f"{shader_side}, texgen's on the {texgen_side}"
        )
    drawn = {e.get("who"): e for e in student.events("draw", within="display")}
    hints = []
    for who, side, what in (
        ("draw_cone_shader", shader_side, "the shader's cone"),
        ("draw_cone_fixed_function", texgen_side, "the texgen cone"),
    ):
        event = drawn.get(who)
        if event is None:
            call = (
                "lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)"
                if who == "draw_cone_shader"
                else "draw_cone_texgen()"
            )
            hints.append(f"{what} is not drawn: {call} in the {side} viewport")
            continue
        viewport = event.get("viewport") or [0, 0, 0, 0]
        in_left = viewport[0] < half
        if (side == "left") != in_left:
            hints.append(
                f"{what} is drawn in the {'left' if in_left else 'right'} half; your "
                f"variant puts it on the {side}"
            )
    if hints:
        return False, "; ".join(hints)
    halves = {"left": half / ref.shape[0], "right": (width - half) / ref.shape[0]}
    for who, side, ok, what in (
        ("draw_cone_shader", shader_side, shader_ok, "the shader's cone"),
        ("draw_cone_fixed_function", texgen_side, texgen_ok, "the texgen cone"),
    ):
        if not ok:
            good, hint = viewer_camera(student, drawn[who], SphereMapLab, halves[side], what)
            if not good:
                hints.append(hint)
    if hints:
        return False, "; ".join(hints)
    if not shader_ok:
        if not (verdicts["reflection"][0] and verdicts["sphere_coordinates"][0]):
            hints.append(f"the {shader_side} half is judged once tasks 1 and 2 pass")
        else:
            mask = differing(frame[:, shader_cols], ref[:, shader_cols])
            hints.append(
                f"the {shader_side} half (the shader's cone) differs from the "
                f"reference in {int(mask.sum())} pixels"
            )
    if not texgen_ok:
        if not (verdicts["texgen_setup"][0] and verdicts["texgen_draw"][0]):
            hints.append(f"the {texgen_side} half is judged once tasks 3 and 4 pass")
        else:
            mask = differing(frame[:, texgen_cols], ref[:, texgen_cols])
            hints.append(
                f"the {texgen_side} half (the texgen cone) differs from the "
                f"reference in {int(mask.sum())} pixels, {where(mask)}"
            )
    return False, "; ".join(hints)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    variant = context.variant
    unit, side = int(variant["unit"]), str(variant["shader_side"])
    verdicts: Verdicts = {
        "reflection": judge_reflection(student),
        "sphere_coordinates": judge_coordinates(student),
        "texgen_setup": judge_texgen_setup(student, unit),
        "texgen_draw": judge_texgen_draw(student, unit),
    }
    verdicts["side_by_side"] = judge_side_by_side(student, reference, verdicts, side)
    observed = _observed(student)
    for name, other in context.differing_others().items():
        if (
            observed is not None
            and observed != (side, unit)
            and observed == (other["shader_side"], int(other["unit"]))
        ):
            context.matched = name
            verdicts["side_by_side"] = (
                False,
                (
                    f"this file is made for {'the lab' if name == 'default' else 'another'}'s "
                    f"variant (the shader's cone on the {other['shader_side']}, texgen on unit "
                    f"{other['unit']}), not yours: shader's cone on the {side}, texgen on unit "
                    f"{unit}"
                ),
            )
            break
    frame = reference.image("frame")
    regions: dict[str, np.ndarray | None] = {}
    if frame is not None:
        height, width = frame.shape[:2]
        shader_cols, texgen_cols = _halves(width, side)
        shader, texgen = np.zeros((height, width), bool), np.zeros((height, width), bool)
        shader[:, shader_cols] = True
        texgen[:, texgen_cols] = True
        regions = {
            "reflection": shader,
            "sphere_coordinates": shader,
            "texgen_setup": texgen,
            "texgen_draw": texgen,
            "side_by_side": None,
        }
    verdicts = judge_frame(verdicts, student, reference, regions, "side_by_side", {})
    return results(spec, student, verdicts, GLSL_FUNCTIONS)


def _observed(student: Evidence) -> tuple[str, int] | None:
    """The (shader's side, texgen unit) the student's calls follow, when they show both:
    the viewport the shader's cone was drawn in and the one unit texgen was on for at the
    texgen cone."""
    draw = _texgen_draw(student)
    shader = student.events("draw", who="draw_cone_shader", within="display")
    if draw is None or not shader:
        return None
    on = [u for u, e in _units(draw).items() if "GL_TEXTURE_GEN_S" in e]
    if len(on) != 1:
        return None
    frame = student.image("frame")
    width = frame.shape[1] if frame is not None else 256
    in_left = (shader[-1].get("viewport") or [0])[0] < width // 2
    return ("left" if in_left else "right", on[0])


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture([(student.image("frame"), ref)], shape)
