"""The sphere-map lab's judge: the student's GLSL judged by the values it writes (the
reflection vector and (s, t) at every pixel of the cone, against the formulas and the
usual slips), texgen by the GL state the cone is drawn with, and the frame against the
reference's. Numpy only."""

from __future__ import annotations

import numpy as np

from mirrorlab.envmap import sphere_map
from mirrorlab.labs import LabSpec
from mirrorlab.labs.judging import Evidence, TaskResult, picture, results_with_errors, share_within

GL_SPHERE_MAP = 0x2402
MODE_NAMES = {0x2400: "GL_EYE_LINEAR", 0x2401: "GL_OBJECT_LINEAR", 0x2402: "GL_SPHERE_MAP",
              0x8511: "GL_NORMAL_MAP", 0x8512: "GL_REFLECTION_MAP"}
GLSL_FUNCTIONS = ("reflect_eye", "sphere_map_st")


def _best(values: np.ndarray, candidates: dict[str, np.ndarray], tolerance: float) -> str:
    """The candidate that ``values`` ``(n, k)`` match on at least 98% of rows, or ''."""
    for name, predicted in candidates.items():
        if np.mean(np.abs(values - predicted).max(-1) <= tolerance) >= 0.98:
            return name
    return ""


def _cone_values(student: Evidence, key: str, function: str,
                 width: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray] | str:
    """The values ``key`` the student's ``function`` gave on the cone's pixels
    ``(pixels, width)`` (its first ``width`` components), with the view direction u and
    normal n there ``(pixels, 3)``; or the hint when there are none, or when the values
    are not all finite."""
    mask = student.arrays.get("values_mask")
    if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.ndim != 2 or \
            mask.sum() < 50:
        return "the cone could not be drawn with SPHERE_MAP_GLSL"
    shape = (*mask.shape, 3)
    values, u, n = (student.floats(f"values_{name}", shape) for name in (key, "u", "n"))
    if values is None or u is None or n is None:
        return "the cone could not be drawn with SPHERE_MAP_GLSL"
    values, u, n = values[mask][:, :width], u[mask], n[mask]
    if not np.all(np.isfinite(values)):
        return f"{function} gives NaN or infinity on the cone"
    return values, u, n


def judge_reflection(student: Evidence) -> tuple[bool, str]:
    cone = _cone_values(student, "r", "reflect_eye")
    if isinstance(cone, str):
        return False, cone
    r, u, n = cone
    un = (u * n).sum(-1, keepdims=True)
    right = u - 2 * un * n
    found = _best(r, {
        "right": right, "sign": -right, "no_two": u - un * n, "plus": u + 2 * un * n,
        "unreflected": u, "normal": n, "normalised_sum": right / np.maximum(
            np.linalg.norm(right, axis=-1, keepdims=True), 1e-9)}, 2e-3)
    hints = {
        "sign": "r points the wrong way (it is -r): the reflection is u - 2 (n.u) n, with u "
                "the direction from the eye to the point",
        "no_two": "the factor 2 is missing: r = u - 2 (n.u) n",
        "plus": "the sign of the 2 (n.u) n term: r = u - 2 (n.u) n",
        "unreflected": "reflect_eye returns u unchanged: reflect it about n, u - 2 (n.u) n",
        "normal": "reflect_eye returns the normal: r = u - 2 (n.u) n",
    }
    if found in ("right", "normalised_sum"):
        return True, ""
    if found in hints:
        return False, hints[found]
    return False, "reflect_eye's r differs from u - 2 (n.u) n on the cone"


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    cone = _cone_values(student, "st", "sphere_map_st", width=2)
    if isinstance(cone, str):
        return False, cone
    st, u, n = cone
    r = u - 2 * (u * n).sum(-1, keepdims=True) * n
    s, t = sphere_map(r)
    right = np.stack([s, t], -1)
    rx, ry, rz = r[:, 0], r[:, 1], r[:, 2]
    length = np.linalg.norm(r, axis=-1)
    no_plus = np.stack([rx / (2 * length) + 0.5, ry / (2 * length) + 0.5], -1)
    m_half = np.sqrt(rx**2 + ry**2 + (rz + 1) ** 2)
    no_two = np.stack([rx / m_half + 0.5, ry / m_half + 0.5], -1)
    found = _best(st, {
        "right": right, "swap": right[:, ::-1], "flip_t": np.stack([s, 1 - t], -1),
        "flip_s": np.stack([1 - s, t], -1), "no_plus_one": no_plus, "no_two": no_two,
        "no_half": right - 0.5}, 2e-3)
    hints = {
        "swap": "s and t swapped: s comes from r.x and t from r.y",
        "flip_t": "t upside down: t = r.y / m + 1/2",
        "flip_s": "s mirrored: s = r.x / m + 1/2",
        "no_plus_one": "m must use (r.z + 1): m = 2 sqrt(r.x^2 + r.y^2 + (r.z + 1)^2), the "
                       "normal of the mirror ball halfway between r and the viewer",
        "no_two": "the factor 2 in m is missing: m = 2 sqrt(r.x^2 + r.y^2 + (r.z + 1)^2), or "
                  "s and t leave [0, 1]",
        "no_half": "the + 1/2 is missing: s and t must lie in [0, 1], centre (1/2, 1/2)",
    }
    if found == "right":
        return True, ""
    if found in hints:
        return False, hints[found]
    return False, "sphere_map_st differs from Hoff's s = r.x/m + 1/2, t = r.y/m + 1/2 on the cone"


def _texgen_draw(student: Evidence) -> dict | None:
    draws = student.state.get("texgen_draws")
    if not isinstance(draws, list) or not draws or not isinstance(draws[-1], dict):
        return None
    return draws[-1]


def judge_texgen_setup(student: Evidence) -> tuple[bool, str]:
    draw = _texgen_draw(student)
    if draw is None:
        return False, "not judged: the texgen cone was never drawn (task 4)"
    hints = []
    for coordinate in ("s", "t"):
        mode = draw.get(f"mode_{coordinate}")
        if mode != GL_SPHERE_MAP:
            name = MODE_NAMES.get(mode, str(mode))
            hints.append(f"texgen for {coordinate} is {name}: glTexGeni(GL_{coordinate.upper()}, "
                         f"GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)")
    return (not hints), "; ".join(hints)


def judge_texgen_draw(student: Evidence) -> tuple[bool, str]:
    draw = _texgen_draw(student)
    if draw is None:
        return False, ("draw_cone_texgen() never draws the cone: call "
                       "lab.draw_cone_fixed_function() there")
    hints = []
    for coordinate in ("s", "t"):
        if not draw.get(f"gen_{coordinate}"):
            hints.append(f"texgen for {coordinate} is off while the cone is drawn: "
                         f"glEnable(GL_TEXTURE_GEN_{coordinate.upper()}) first")
    launch = {student.state.get("launch_texture"), student.state.get("student_launch")}
    if draw.get("active_unit") != 0 or draw.get("texture") not in launch - {None, -1, 0}:
        hints.append("the launch picture is not bound on texture unit 0 when the cone is drawn "
                     "(glActiveTexture(GL_TEXTURE0); glBindTexture(GL_TEXTURE_2D, launch))")
    after = student.state.get("texgen_after")
    if isinstance(after, dict) and (after.get("gen_s") or after.get("gen_t")):
        hints.append("texgen left on after the cone: glDisable(GL_TEXTURE_GEN_S) and "
                     "(GL_TEXTURE_GEN_T) when it is drawn, or everything drawn later in the "
                     "fixed-function pipeline gets sphere-map coordinates too")
    return (not hints), "; ".join(hints)


def judge_frame(student: Evidence, reference: Evidence,
                verdicts: dict[str, tuple[bool, str]]) -> tuple[bool, str]:
    frames, why = student.displayed_frames(reference)
    if frames is None:
        return False, why
    frame, ref = frames
    half = ref.shape[1] // 2
    left_ok = share_within(frame[:, :half], ref[:, :half], 24) >= 0.97
    right_ok = share_within(frame[:, half:], ref[:, half:], 24) >= 0.97
    if left_ok and right_ok:
        return True, ""
    if share_within(frame[:, :half], ref[:, half:2 * half], 24) >= 0.97 and \
            share_within(frame[:, half:2 * half], ref[:, :half], 24) >= 0.97:
        return False, "the halves are swapped: the shader's cone goes left, texgen's right"
    kinds = [e.get("kind") for e in student.frame_events()]
    hints = []
    if "draw_cone_shader" not in kinds:
        hints.append("the shader's cone is not drawn: lab.draw_cone_shader(SPHERE_MAP_GLSL, "
                     "launch) in the left viewport")
    if "draw_cone_fixed_function" not in kinds:
        hints.append("the texgen cone is not drawn: draw_cone_texgen() in the right viewport")
    if hints:
        return False, "; ".join(hints)
    if not left_ok:
        if not (verdicts["reflection"][0] and verdicts["sphere_coordinates"][0]):
            hints.append("the left half is judged once tasks 1 and 2 pass")
        else:
            hints.append("the left half (lab.draw_cone_shader in the left viewport) differs "
                         "from the reference")
    if not right_ok:
        if not (verdicts["texgen_setup"][0] and verdicts["texgen_draw"][0]):
            hints.append("the right half is judged once tasks 3 and 4 pass")
        else:
            hints.append("the right half (draw_cone_texgen in the right viewport) differs "
                         "from the reference")
    return False, "; ".join(hints)


def judge(spec: LabSpec, student: Evidence, reference: Evidence) -> list[TaskResult]:
    verdicts = {
        "reflection": judge_reflection(student),
        "sphere_coordinates": judge_coordinates(student),
        "texgen_setup": judge_texgen_setup(student),
        "texgen_draw": judge_texgen_draw(student),
    }
    verdicts["side_by_side"] = judge_frame(student, reference, verdicts)
    return results_with_errors(spec, student, verdicts, GLSL_FUNCTIONS)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture([(student.image("frame"), ref)], shape)
