"""The sphere-map lab's judge: the student's GLSL by the values it writes (the reflection
vector and (s, t) at every pixel of the cone, against the formulas and the usual slips),
texgen by the state at the fixed-function draw and the calls that set it (which unit was
active), and the frame against the reference's, half by half and as a whole. Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec, task_name
from mirrorlab.labs.lab_spheremap.trusted import SphereMapLab
from mirrorlab.labs.trusted import probe
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    Verdicts,
    differing,
    judge_frame,
    picture,
    results,
    same_picture,
    stopped_hint,
    viewer_camera,
    where,
)

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


def judge_reflection(student: Evidence) -> tuple[bool, str]:
    """task 1 (reflection): ``reflect_eye`` by the value probe (:func:`.probe.judge`)."""
    return probe.judge(student, "spheremap", "reflect_eye")


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    """task 2 (sphere_coordinates): ``sphere_map_st`` by the value probe (:func:`.probe.judge`)."""
    return probe.judge(student, "spheremap", "sphere_map_st")


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
