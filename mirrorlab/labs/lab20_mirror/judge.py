"""Lab 20's judge: each task from the calls the trusted side executed (the state at the
capture's draw and copy, ENVIRONMENT's parameters, the mirror quad's vertices and texture
coordinates, the order of the passes), then the pictures, then the final frame as a
whole, all against the student's own variant. Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs import LabSpec, task_name
from mirrorlab.labs.lab20_mirror.trusted import Lab20
from mirrorlab.labs.lab20_mirror.variant import lab20_geometry
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    Verdicts,
    copy_format_slip,
    differing,
    fmt,
    judge_frame,
    matrix,
    misplaced_calls,
    picture,
    results,
    same_picture,
    stacked_ops,
    stopped_hint,
    triangles_mask,
    viewer_camera,
    where,
    wrong_clear_colour,
)

GL_LINEAR = 0x2601
GL_CLAMP, GL_CLAMP_TO_EDGE = 0x2900, 0x812F
GL_REPEAT, GL_MIRRORED_REPEAT = 0x2901, 0x8370
GL_MODELVIEW, GL_PROJECTION = 0x1700, 0x1701
GL_TEXTURE_2D = 0x0DE1
GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT = 0x4000, 0x0100
FILTER_NAMES = {
    0x2600: "GL_NEAREST",
    0x2601: "GL_LINEAR",
    0x2700: "GL_NEAREST_MIPMAP_NEAREST",
    0x2701: "GL_LINEAR_MIPMAP_NEAREST",
    0x2702: "GL_NEAREST_MIPMAP_LINEAR",
    0x2703: "GL_LINEAR_MIPMAP_LINEAR",
}
MIPMAP_FILTERS = {k: v for k, v in FILTER_NAMES.items() if k >= 0x2700}
QUAD_MODES = {
    0x0007: "GL_QUADS",
    0x0009: "GL_POLYGON",
    0x0006: "GL_TRIANGLE_FAN",
    0x0004: "GL_TRIANGLES",
    0x0005: "GL_TRIANGLE_STRIP",
    0x0008: "GL_QUAD_STRIP",
}

TEXCOORD_MISTAKES = (
    # (transform of the right (s, t), hint)
    (
        lambda s, t: (1 - s, t),
        "texture coordinates flipped left-right: s must grow with z, "
        "0 at z = {z0:g} and 1 at z = {z1:g}",
    ),
    (
        lambda s, t: (s, 1 - t),
        "texture coordinates upside down: t must grow with y, 0 at y = {y0:g} and 1 at y = {y1:g}",
    ),
    (
        lambda s, t: (1 - s, 1 - t),
        "texture coordinates rotated by 180 degrees: corner {c0} takes (0, 0)",
    ),
    (
        lambda s, t: (t, s),
        "texture coordinates rotated (s and t swapped): s follows z and t follows y",
    ),
    (
        lambda s, t: (t, 1 - s),
        "texture coordinates rotated by 90 degrees: s follows z and t follows y",
    ),
    (
        lambda s, t: (1 - t, s),
        "texture coordinates rotated by 90 degrees: s follows z and t follows y",
    ),
    (
        lambda s, t: (1 - t, 1 - s),
        "texture coordinates rotated (s and t swapped and flipped): s follows z and t follows y",
    ),
)


def _task(task_id: str) -> str:
    """How a hint names another task of this lab (``task 8 (passes)``)."""
    return task_name("lab20", task_id)


def _point(values: Any) -> str:
    return f"({fmt(values)})"


def _corners(geometry: dict[str, Any]) -> str:
    return ", ".join(_point(c) for c in geometry["corners"])


def _capture_draw(student: Evidence) -> dict[str, Any] | None:
    draws = student.events("draw", who="draw_scene", within="create_mirror")
    return draws[0] if draws else None


def _leave(student: Evidence, function: str) -> dict[str, Any] | None:
    found = [
        e for e in student.last_frame if e.get("kind") == "leave" and e.get("function") == function
    ]
    return found[0] if found else None


def expected_capture(geometry: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The capture's projection and view for a variant's mirror (row-major (4, 4))."""
    return (
        math3d.ortho(*geometry["extents"]),
        math3d.look_at(geometry["eye"], (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
    )


def ortho_extents(projection: np.ndarray) -> tuple[float, ...] | None:
    """The glOrtho extents (left, right, bottom, top, near, far) of an orthographic
    ``projection``, or None when it is not one."""
    p = projection
    if (
        not np.allclose(p[3], (0, 0, 0, 1), atol=1e-6)
        or min(abs(p[0, 0]), abs(p[1, 1]), abs(p[2, 2])) < 1e-12
    ):
        return None
    width, height, depth = 2 / p[0, 0], 2 / p[1, 1], -2 / p[2, 2]
    mid_x, mid_y, mid_z = -p[0, 3] * width, -p[1, 3] * height, -p[2, 3] * depth
    return (
        (mid_x - width) / 2,
        (mid_x + width) / 2,
        (mid_y - height) / 2,
        (mid_y + height) / 2,
        (mid_z - depth) / 2,
        (mid_z + depth) / 2,
    )


def camera_of(modelview: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eye position, look direction and up of a rigid ``modelview``."""
    rotation = modelview[:3, :3]
    return -rotation.T @ modelview[:3, 3], -rotation[2], rotation[1]


def capture_matches(
    projection: np.ndarray, modelview: np.ndarray, geometry: dict[str, Any]
) -> bool:
    """Whether the capture camera shows the mirror's box: the x and y rows of
    projection @ view as the variant's, and the robot between its near and far planes
    (the frame behind the glass outside them)."""
    clip = projection @ modelview
    want_p, want_v = expected_capture(geometry)
    want = want_p @ want_v
    if not np.allclose(clip[[0, 1, 3]], want[[0, 1, 3]], atol=1e-4):
        return False
    robot = np.array([[-2.5, 0.0, 0.0, 1.0], [2.5, 0.0, 0.0, 1.0]])
    behind = np.array([[geometry["x"] - 0.2, 0.0, 0.0, 1.0]])
    z_robot = (robot @ clip.T)[:, 2]
    z_behind = (behind @ clip.T)[:, 2]
    return bool(np.all(np.abs(z_robot) <= 1.0) and np.all(np.abs(z_behind) > 1.0))


def judge_camera(student: Evidence, geometry: dict[str, Any], context: Context) -> tuple[bool, str]:
    draw = _capture_draw(student)
    event = draw or _leave(student, "create_mirror")
    if event is None:
        return False, f"create_mirror() did not run in the last frame: see {_task('passes')}"
    projection, modelview = matrix(event.get("projection")), matrix(event.get("modelview"))
    if projection is None or modelview is None:
        return False, "the capture's matrices could not be read"
    misplaced = misplaced_calls(
        student,
        "create_mirror",
        {
            "glOrtho": GL_PROJECTION,
            "glFrustum": GL_PROJECTION,
            "gluPerspective": GL_PROJECTION,
            "gluLookAt": GL_MODELVIEW,
        },
    )
    if misplaced:
        return False, misplaced
    for mode, first in ((GL_PROJECTION, "glOrtho"), (GL_MODELVIEW, "gluLookAt")):
        stacked = stacked_ops(event, student, mode, first)
        if stacked:
            return False, stacked
    if capture_matches(projection, modelview, geometry):
        return (
            (True, "")
            if draw is not None
            else (False, "the matrices are right but create_mirror() draws nothing with them")
        )
    for name, variant in context.differing_others().items():
        if capture_matches(projection, modelview, lab20_geometry(variant)):
            context.matched = name
            return False, (
                f"this capture is for {_another(name)}, not yours: your mirror's "
                f"corners are {_corners(geometry)}"
            )
    return False, _camera_hint(projection, modelview, geometry)


def _another(name: str) -> str:
    return (
        "the lab's own mirror (the default variant)"
        if name == "default"
        else "another student's mirror (their variant's numbers)"
    )


def _camera_hint(projection: np.ndarray, modelview: np.ndarray, geometry: dict[str, Any]) -> str:
    hints = []
    want_p, want_v = expected_capture(geometry)
    ortho = "glOrtho(" + fmt(geometry["extents"]) + ")"
    look = "gluLookAt(" + fmt([*geometry["eye"], 0, 0, 0, 0, 1, 0]) + ")"
    if not np.allclose(projection, want_p, atol=1e-4):
        extents = ortho_extents(projection)
        if np.allclose(projection, np.eye(4)):
            hints.append(
                f"no projection is set: glMatrixMode(GL_PROJECTION), glLoadIdentity(), then {ortho}"
            )
        elif extents is None:
            hints.append(
                f"the capture's projection is not orthographic (glFrustum or "
                f"gluPerspective?): use {ortho}"
            )
        elif np.allclose(extents[:4], geometry["extents"][:4], atol=1e-3):
            hints.append(
                f"the near and far planes glOrtho(..., {fmt(extents[4:])}) cut the "
                f"robot or show what is behind the glass: near {fmt([0])} is the "
                f"glass, far {fmt([15])} reaches past the robot"
            )
        else:
            hints.append(
                f"wrong extents: the projection is glOrtho({fmt(extents)}); your "
                f"mirror needs {ortho} (its corners are {_corners(geometry)})"
            )
    if not np.allclose(modelview, want_v, atol=1e-4):
        eye, forward, up = camera_of(modelview)
        rigid = np.allclose(modelview[:3, :3] @ modelview[:3, :3].T, np.eye(3), atol=1e-4)
        if rigid and np.dot(forward, (1, 0, 0)) < -0.9:
            hints.append(
                f"camera on the wrong side: it sits at ({fmt(eye)}) looking towards -x, "
                f"away from the robot; put it on the mirror: {look}"
            )
        elif (
            rigid
            and np.allclose(forward, (1, 0, 0), atol=1e-3)
            and not np.allclose(up, (0, 1, 0), atol=1e-3)
        ):
            hints.append(
                f"the capture camera's up is ({fmt(up)}): use up (0, 1, 0), or the reflection turns"
            )
        elif np.allclose(modelview, want_v @ want_v, atol=1e-4):
            hints.append(
                "gluLookAt was applied twice: call glLoadIdentity() on the modelview "
                "before gluLookAt each frame"
            )
        elif rigid and np.allclose(forward, (1, 0, 0), atol=1e-3):
            hints.append(
                f"the capture camera sits at ({fmt(eye)}); the mirror's centre line "
                f"starts at ({fmt(geometry['eye'])}): {look}"
            )
        else:
            hints.append(
                f"the capture camera sits at ({fmt(eye)}) looking along "
                f"({fmt(forward)}); expected {look}"
            )
    return "; ".join(hints) or (
        f"the capture's camera does not show the mirror's box: expected {ortho} and {look}"
    )


def mirror_inside_capture(student: Evidence) -> bool:
    return any(
        e.get("kind") == "enter"
        and e.get("function") == "render_mirror"
        and "create_mirror" in (e.get("steps") or [])
        for e in student.last_frame
    )


def _first_copy(student: Evidence) -> dict[str, Any] | None:
    copies = student.events("copy", within="create_mirror")
    return copies[0] if copies else None


def judge_capture(
    student: Evidence, reference: Evidence, camera_ok: bool, base_ok: bool
) -> tuple[bool, str]:
    if mirror_inside_capture(student):
        return False, (
            "the mirror is drawn into its own capture: render_mirror() runs inside "
            "create_mirror(); draw only the scene there"
        )
    draw = _capture_draw(student)
    if draw is None:
        return False, (
            "create_mirror() draws nothing: call lab.draw_scene(robot) once its "
            "projection and camera are set"
        )
    copy = _first_copy(student)
    if copy is None:
        return False, (f"not judged: create_mirror() copies nothing, see {_task('capture_copy')}")
    seen = student.image(copy.get("picture", ""))
    ref_copy = _first_copy(reference)
    ref = reference.image(ref_copy.get("picture", "")) if ref_copy else None
    if seen is None or ref is None:
        return False, "the capture's picture is missing"
    if same_picture(seen, ref):
        return True, ""
    if not camera_ok:
        return False, (
            "the capture shows the wrong view: fix its projection and camera, "
            f"{_task('capture_camera')}"
        )
    if student.state.get("metal_intact") is False:
        return False, (
            "the base in the capture wears what the copy wrote over METAL: judged "
            f"once {_task('capture_copy')} passes"
        )
    if not base_ok:
        return False, f"the base in the capture is judged once {_task('base_texture')} passes"
    frame_events = student.last_frame
    index = frame_events.index(draw)
    clears = [
        e
        for e in frame_events[:index]
        if e.get("kind") == "clear" and "create_mirror" in (e.get("steps") or [])
    ]
    if not any(e["mask"] & GL_COLOR_BUFFER_BIT for e in clears):
        return False, (
            "create_mirror() draws over the last frame's picture: clear "
            "(glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)) before its "
            "lab.draw_scene"
        )
    if not any(e["mask"] & GL_DEPTH_BUFFER_BIT for e in clears):
        return False, (
            "the depth buffer is not cleared before the capture: glClear(... | "
            "GL_DEPTH_BUFFER_BIT), or the last frame's depths hide the robot"
        )
    if wrong := wrong_clear_colour(clears[-1], Lab20.BACKGROUND, student):
        return False, (
            f"the capture is cleared to {wrong}; the lab's background is ({fmt(Lab20.BACKGROUND)})"
        )
    viewport = draw.get("viewport")
    if viewport != [0, 0, seen.shape[1], seen.shape[0]]:
        return False, (
            f"the capture is drawn in glViewport({fmt(viewport)}); it needs the "
            f"whole frame, glViewport(0, 0, WIDTH, HEIGHT)"
        )
    mask = differing(seen, ref)
    return False, (
        f"the capture differs from the reference in {int(mask.sum())} pixels, {where(mask)}"
    )


def judge_copy(student: Evidence, size: tuple[int, int]) -> tuple[bool, str]:
    if not student.called("create_mirror"):
        return False, (f"create_mirror() was never called in the last frame: see {_task('passes')}")
    copy = _first_copy(student)
    environment, metal = student.state.get("environment"), student.state.get("metal")
    bind = "glActiveTexture(GL_TEXTURE1); glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])"
    if copy is None:
        return False, (
            f"create_mirror() copies nothing into ENVIRONMENT: bind it ({bind}), "
            f"then glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, "
            f"0)"
        )
    at = student.at(copy["line"])
    if copy["texture"] != environment:
        if copy["texture"] == metal:
            return False, (
                f"the copy at {at} overwrote METAL, the texture bound on unit "
                f"{copy['unit']} then (the scene's drawing binds it): bind "
                f"ENVIRONMENT first ({bind})"
            )
        return False, (
            f"the copy at {at} went into texture {copy['texture']}, not ENVIRONMENT "
            f"(the texture the mirror shows): bind ENVIRONMENT first ({bind})"
        )
    width, height = size
    if copy["level"] != 0:
        return False, f"the copy at {at} fills level {copy['level']}; the mirror shows level 0"
    if (copy["x"], copy["y"]) != (0, 0) or copy.get("offset", [0, 0]) != [0, 0]:
        return False, (
            f"the copy at {at} starts at ({copy['x']}, {copy['y']}) of the "
            f"framebuffer: copy from its corner (0, 0)"
        )
    if (copy["width"], copy["height"]) != (width, height):
        return False, (
            f"the copy at {at} takes {copy['width']} x {copy['height']} pixels; "
            f"copy the whole framebuffer, WIDTH x HEIGHT ({width} x {height})"
        )
    if slip := copy_format_slip(copy):
        return False, f"the copy at {at} {slip}"
    events = student.last_frame
    draw = _capture_draw(student)
    if draw is not None and events.index(copy) < events.index(draw):
        return False, (
            f"the copy at {at} comes before lab.draw_scene at "
            f"{student.at(draw['line'])}: copy the picture once it is drawn"
        )
    return True, ""


def judge_environment(student: Evidence) -> tuple[bool, str]:
    params = student.state.get("environment_parameters")
    record = student.texture(student.state.get("environment"))
    if not isinstance(params, dict) or record is None:
        return False, "ENVIRONMENT (tex_ids[ENVIRONMENT]) is not a texture the mirror shows"
    lines = {int(k): v.get("line", 0) for k, v in (record.get("params") or {}).items()}

    def at(pname: int) -> str:
        return f" (line {lines[pname]})" if lines.get(pname) else " (GL's default)"

    hints = []
    minify = params.get("GL_TEXTURE_MIN_FILTER")
    if minify in MIPMAP_FILTERS:
        hints.append(
            f"mipmaps on ENVIRONMENT: its minifying filter is {MIPMAP_FILTERS[minify]}"
            f"{at(0x2801)}, which wants mipmaps, but the capture fills level 0 only, "
            f"so the texture is incomplete (black); use GL_LINEAR"
        )
    elif params.get("level1_width", 0):
        line = (record.get("mipmaps") or {}).get("line", 0)
        hints.append(
            f"mipmaps on ENVIRONMENT: glGenerateMipmap{f' at line {line}' if line else ''}"
            f" made levels the capture never updates; give it level 0 only"
        )
    elif minify != GL_LINEAR or params.get("GL_TEXTURE_MAG_FILTER") != GL_LINEAR:
        hints.append(
            "ENVIRONMENT's filters must both be GL_LINEAR (GL_TEXTURE_MIN_FILTER and "
            "GL_TEXTURE_MAG_FILTER)"
        )
    wraps = (params.get("GL_TEXTURE_WRAP_S"), params.get("GL_TEXTURE_WRAP_T"))
    if any(w in (GL_REPEAT, GL_MIRRORED_REPEAT) for w in wraps):
        pname = 0x2802 if wraps[0] in (GL_REPEAT, GL_MIRRORED_REPEAT) else 0x2803
        hints.append(
            f"repeat wrapping on ENVIRONMENT{at(pname)}: the mirror's edges would "
            f"blend in the opposite edge; clamp both (GL_CLAMP_TO_EDGE, or GL_CLAMP "
            f"as the lab text has it)"
        )
    elif any(w not in (GL_CLAMP, GL_CLAMP_TO_EDGE) for w in wraps):
        hints.append(
            "ENVIRONMENT's wrapping must clamp: GL_CLAMP_TO_EDGE for "
            "GL_TEXTURE_WRAP_S and GL_TEXTURE_WRAP_T"
        )
    return (not hints), "; ".join(hints)


def _viewer_draw(student: Evidence) -> dict[str, Any] | None:
    draws = [
        e
        for e in student.events("draw", who="draw_scene")
        if "create_mirror" not in (e.get("steps") or [])
    ]
    return draws[-1] if draws else None


def judge_base(student: Evidence) -> tuple[bool, str]:
    draw = _viewer_draw(student) or _capture_draw(student)
    if draw is None:
        return False, stopped_hint(
            student, "build_scene_graph"
        ) or f"not judged: the scene was never drawn, see {_task('passes')}"
    texture = (draw.get("textures") or {}).get("base")
    if texture is not None and texture == student.state.get("metal"):
        return True, ""
    if texture is None:
        return False, (
            'base not textured: set robot["base"].texture = tex_ids[METAL] in build_scene_graph()'
        )
    if texture == student.state.get("environment"):
        return False, "the base wears ENVIRONMENT: give it tex_ids[METAL]"
    shown = texture.get("other") if isinstance(texture, dict) else texture
    return False, f"the base's texture is {shown}; expected tex_ids[METAL]"


def _mirror_draws(student: Evidence) -> list[dict[str, Any]]:
    return [
        e
        for e in student.events("draw", who="primitive", within="render_mirror")
        if len(e.get("vertices") or []) >= 3
    ]


def judge_mirror_texture(student: Evidence, spec_programs: int, env_ok: bool) -> tuple[bool, str]:
    if hint := stopped_hint(student, "render_mirror"):
        return False, hint
    draws = _mirror_draws(student)
    if not draws:
        return False, (f"judged once render_mirror() draws the quad, see {_task('mirror_quad')}")
    draw = draws[-1]
    state = draw.get("state") or {}
    environment = student.state.get("environment")
    program = state.get("program", {})
    if program.get("value") != spec_programs:
        return False, (
            "the mirror is drawn without lab.textureShader: glUseProgram("
            "lab.textureShader) before glBegin"
        )
    sampler = draw.get("sampler")
    units = [
        int(u)
        for u, entry in (state.get("units") or {}).items()
        if (entry.get("2d") or {}).get("value") == environment and environment
    ]
    if not units:
        return False, (
            "ENVIRONMENT is not bound when the mirror is drawn: "
            "glActiveTexture(GL_TEXTURE1); glBindTexture(GL_TEXTURE_2D, "
            "tex_ids[ENVIRONMENT])"
        )
    if sampler not in units:
        set_at = draw.get("sampler_set")
        if not set_at:
            return False, (
                f"the mirror shows the texture on unit {sampler}: the sampler uniform "
                f"is not set, so texSampler reads unit 0; call "
                f"glUniform1i(lab.texSampler, {units[0]}) after "
                f"glUseProgram(lab.textureShader)"
            )
        return False, (
            f"the mirror shows the wrong texture: texSampler reads unit {sampler} "
            f"(glUniform1i at {student.at(set_at.get('line', 0))}) but ENVIRONMENT "
            f"is bound on unit {', '.join(map(str, units))}"
        )
    if not env_ok:
        params = student.state.get("environment_parameters") or {}
        if params.get("GL_TEXTURE_MIN_FILTER") in MIPMAP_FILTERS:
            return False, (
                "the mirror is black: ENVIRONMENT's filter wants mipmaps it does "
                f"not have: see {_task('environment_texture')}"
            )
    return True, ""


def _triangles(mode: int, points: list[np.ndarray]) -> list[tuple[int, int, int]]:
    n = len(points)
    if mode in (0x0007,):  # quads
        return [t for i in range(0, n - 3, 4) for t in ((i, i + 1, i + 2), (i, i + 2, i + 3))]
    if mode in (0x0009, 0x0006):  # polygon, fan
        return [(0, i, i + 1) for i in range(1, n - 1)]
    if mode == 0x0004:
        return [(i, i + 1, i + 2) for i in range(0, n - 2, 3)]
    if mode in (0x0005, 0x0008):  # strips
        return [(i, i + 1, i + 2) for i in range(n - 2)]
    return []


def judge_quad(student: Evidence, geometry: dict[str, Any], context: Context) -> tuple[bool, str]:
    if hint := stopped_hint(student, "render_mirror"):
        return False, hint
    if not student.called("render_mirror"):
        return False, (f"render_mirror() was not called in the last frame: see {_task('passes')}")
    draws = _mirror_draws(student)
    if not draws:
        return False, (
            "render_mirror() draws no quad: glBegin(GL_QUADS), a glTexCoord2f "
            "before each glVertex3f, glEnd()"
        )
    draw = draws[-1]
    mode = draw.get("mode")
    at = student.at(draw.get("begin_line", 0))
    if mode not in QUAD_MODES:
        return False, f"the mirror at {at} is drawn as points or lines: use glBegin(GL_QUADS)"
    modelview, view = matrix(draw.get("modelview")), Lab20.viewer_for((1, 1))[1]
    if modelview is None:
        return False, "the mirror's matrices could not be read"
    to_world = np.linalg.inv(view) @ modelview
    vertices = draw["vertices"]
    world = [to_world @ np.asarray(v[0], dtype=np.float64) for v in vertices]
    points = [w[:3] / w[3] if abs(w[3]) > 1e-12 else w[:3] for w in world]
    texcoords = [np.asarray(v[1][0], dtype=np.float64) for v in vertices]
    g = geometry
    corners = np.array(g["corners"], dtype=np.float64)
    for name, variant in context.differing_others().items():
        theirs = np.array(lab20_geometry(variant)["corners"], dtype=np.float64)
        if all(np.min(np.linalg.norm(theirs - p, axis=1)) < 1e-3 for p in points) and not all(
            np.min(np.linalg.norm(corners - p, axis=1)) < 1e-3 for p in points
        ):
            context.matched = context.matched or name
            return False, (
                f"this quad is {_another(name)}, not yours: your mirror's corners are {_corners(g)}"
            )
    xs = np.array([p[0] for p in points])
    if not np.allclose(xs, g["x"], atol=1e-3):
        if np.allclose(xs, xs[0], atol=1e-3):
            return False, (
                f"the quad at {at} lies in the plane x = {xs[0]:g}; your mirror is in "
                f"x = {g['x']:g}: its corners are {_corners(g)}"
            )
        return False, (
            f"the quad at {at} is not flat in the mirror's plane x = {g['x']:g}: its "
            f"corners are {_corners(g)}"
        )
    for point in points:
        inside = (
            g["y0"] - 1e-3 <= point[1] <= g["y1"] + 1e-3
            and g["z0"] - 1e-3 <= point[2] <= g["z1"] + 1e-3
        )
        nearest = corners[np.argmin(np.linalg.norm(corners - point, axis=1))]
        if not inside or (len(vertices) <= 4 and not np.allclose(point, nearest, atol=1e-3)):
            return False, (
                f"the vertex ({fmt(point)}) is not a corner of your mirror; the "
                f"nearest corner is ({fmt(nearest)}) (corners: {_corners(g)})"
            )
    if not _covers(mode, points, g):
        return False, f"the quad does not cover your mirror: its corners are {_corners(g)}"
    want = np.array(
        [
            [(p[2] - g["z0"]) / (g["z1"] - g["z0"]), (p[1] - g["y0"]) / (g["y1"] - g["y0"])]
            for p in points
        ]
    )
    got = np.array([t[:2] for t in texcoords])
    if np.allclose(got, want, atol=1e-3):
        return True, ""
    for transform, hint in TEXCOORD_MISTAKES:
        s, t = transform(want[:, 0], want[:, 1])
        if np.allclose(got, np.stack([s, t], -1), atol=1e-3):
            return False, hint.format(c0=_point(g["corners"][0]), **g)
    for point, have, expected in zip(points, got, want, strict=True):
        if not np.allclose(have, expected, atol=1e-3):
            return False, (
                f"the texture coordinates ({fmt(have)}) at the corner "
                f"({fmt(point)}) should be ({fmt(expected)}): s = "
                f"{_from('z', g['z0'])} / {g['z1'] - g['z0']:g}, t = "
                f"{_from('y', g['y0'])} / {g['y1'] - g['y0']:g}"
            )
    return True, ""


def _from(axis: str, start: float) -> str:
    """``(z + 6)`` for the distance of ``axis`` from ``start`` = -6."""
    return f"({axis} + {-start:g})" if start < 0 else f"({axis} - {start:g})" if start else axis


def _covers(mode: int, points: list[np.ndarray], g: dict[str, Any]) -> bool:
    """Whether the primitive's triangles cover the mirror's rectangle (sampled on a grid)."""
    triangles = _triangles(mode, points)
    yz = [np.array([p[1], p[2]]) for p in points]
    ys = np.linspace(g["y0"] + 0.05, g["y1"] - 0.05, 12)
    zs = np.linspace(g["z0"] + 0.05, g["z1"] - 0.05, 12)
    for y in ys:
        for z in zs:
            q = np.array([y, z])
            if not any(_in_triangle(q, yz[a], yz[b], yz[c]) for a, b, c in triangles):
                return False
    return True


def _in_triangle(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> bool:
    def cross(o: np.ndarray, p: np.ndarray, r: np.ndarray) -> float:
        return float((p[0] - o[0]) * (r[1] - o[1]) - (p[1] - o[1]) * (r[0] - o[0]))

    d1, d2, d3 = cross(a, b, q), cross(b, c, q), cross(c, a, q)
    negative = d1 < -1e-9 or d2 < -1e-9 or d3 < -1e-9
    positive = d1 > 1e-9 or d2 > 1e-9 or d3 > 1e-9
    return not (negative and positive)


def judge_passes(student: Evidence) -> tuple[bool, str]:
    events = student.last_frame
    if not events:
        return False, "display() did not draw a frame"
    if hint := stopped_hint(student, "display"):
        return False, hint
    if not student.called("create_mirror"):
        return False, (
            "display() never calls create_mirror(): pass 1 must run every frame, "
            "before the camera pass"
        )
    if not student.called("render_mirror"):
        return False, "display() never calls render_mirror() after drawing the scene"
    viewer = _viewer_draw(student)
    if viewer is None:
        return False, "display() does not draw the scene from the viewer (lab.draw_scene)"
    index = events.index(viewer)
    capture = [
        i
        for i, e in enumerate(events)
        if e.get("kind") == "draw" and "create_mirror" in (e.get("steps") or [])
    ]
    if capture and capture[0] > index:
        return False, (
            "passes in the wrong order: create_mirror() draws into the same "
            "framebuffer, so it must run before the frame is cleared and drawn "
            "from the viewer"
        )
    clears = [
        i
        for i, e in enumerate(events[:index])
        if e.get("kind") == "clear"
        and e["mask"] & GL_COLOR_BUFFER_BIT
        and not e.get("scissor")
        and "create_mirror" not in (e.get("steps") or [])
    ]
    if capture and (not clears or clears[-1] < capture[-1]):
        enter = next(
            e for e in events if e.get("kind") == "enter" and e.get("function") == "create_mirror"
        )
        if clears:
            where_clear = f"the frame's last clear (line {events[clears[-1]]['line']})"
        else:
            where_clear = "a clear"
        return False, (
            f"the capture's picture stays in the frame: create_mirror() (called at "
            f"line {enter['line']}) draws after {where_clear}; call it first, then "
            f"clear and draw from the viewer"
        )
    copies = [
        i
        for i, e in enumerate(events)
        if e.get("kind") == "copy" and "create_mirror" in (e.get("steps") or [])
    ]
    mirrors = [
        i
        for i, e in enumerate(events)
        if e.get("kind") == "draw"
        and e.get("who") == "primitive"
        and "render_mirror" in (e.get("steps") or [])
    ]
    if mirrors and copies and mirrors[0] < copies[0]:
        return False, (
            "passes in the wrong order: render_mirror() runs before create_mirror() "
            "has copied this frame's capture"
        )
    if clears and (wrong := wrong_clear_colour(events[clears[-1]], Lab20.BACKGROUND, student)):
        return False, (
            f"the frame is cleared to {wrong}; the lab's background is "
            f"({fmt(Lab20.BACKGROUND)}), as the given code leaves it"
        )
    return viewer_camera(student, viewer, Lab20)


def mirror_region(size: tuple[int, int], geometry: dict[str, Any], grow: int = 2) -> np.ndarray:
    """The pixels of a ``size`` (w, h) frame where the viewer sees the variant's mirror
    (``grow`` pixels wider), ``(h, w)`` bool."""
    width, height = size
    projection, view = Lab20.viewer_for(size)
    corners = np.array([[*c, 1.0] for c in geometry["corners"]]) @ (projection @ view).T
    ndc = corners[:, :2] / corners[:, 3:]
    xs = (ndc[:, 0] + 1) / 2 * width
    ys = (1 - ndc[:, 1]) / 2 * height
    yy, xx = np.mgrid[0:height, 0:width] + 0.5
    inside = np.ones((height, width), dtype=bool)
    polygon = list(zip(xs, ys, strict=True))
    area = sum(
        x0 * y1 - x1 * y0
        for (x0, y0), (x1, y1) in zip(polygon, polygon[1:] + polygon[:1], strict=True)
    )
    sign = 1.0 if area > 0 else -1.0
    for (x0, y0), (x1, y1) in zip(polygon, polygon[1:] + polygon[:1], strict=True):
        inside &= sign * ((x1 - x0) * (yy - y0) - (y1 - y0) * (xx - x0)) >= -grow * np.hypot(
            x1 - x0, y1 - y0
        )
    return inside


def drawn_region(draw: dict[str, Any], size: tuple[int, int]) -> np.ndarray:
    """The pixels a primitive the student drew covers (2 px wider), ``(h, w)`` bool."""
    projection, modelview = matrix(draw.get("projection")), matrix(draw.get("modelview"))
    if projection is None or modelview is None:
        return np.zeros((size[1], size[0]), dtype=bool)
    clip = [
        projection @ modelview @ np.asarray(v[0], dtype=np.float64)
        for v in draw.get("vertices") or []
    ]
    return triangles_mask(clip, _triangles(int(draw.get("mode", 0)), clip), size)


def clamp_rim(
    student: Evidence, size: tuple[int, int], geometry: dict[str, Any]
) -> np.ndarray | None:
    """The mirror's outline, 3 pixels either side, when ENVIRONMENT wraps with GL_CLAMP
    (which the handout accepts): there its linear filter darkens a thin rim with the
    border colour, not a mark of the file's; else None."""
    params = student.state.get("environment_parameters") or {}
    if GL_CLAMP not in (params.get("GL_TEXTURE_WRAP_S"), params.get("GL_TEXTURE_WRAP_T")):
        return None
    return mirror_region(size, geometry, 3) & ~mirror_region(size, geometry, -3)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    geometry = lab20_geometry(context.variant)
    frame = reference.image("frame")
    size = (frame.shape[1], frame.shape[0]) if frame is not None else (256, 256)
    camera = judge_camera(student, geometry, context)
    base = judge_base(student)
    environment = judge_environment(student)
    passes = judge_passes(student)
    program = int(student.state.get("texture_shader", -1))
    verdicts: Verdicts = {
        "capture_camera": camera,
        "capture_scene": judge_capture(student, reference, camera[0], base[0]),
        "capture_copy": judge_copy(student, size),
        "environment_texture": environment,
        "base_texture": base,
        "mirror_texture": judge_mirror_texture(student, program, environment[0]),
        "mirror_quad": judge_quad(student, geometry, context),
        "passes": passes,
    }
    if not passes[0] and "wrong order" in passes[1]:
        for key in ("mirror_texture", "mirror_quad"):
            if verdicts[key][0]:
                continue
            verdicts[key] = (
                False,
                f"judged once {_task('passes')} passes: this frame is not the camera pass",
            )
    mirror = mirror_region(size, geometry)
    for draw in _mirror_draws(student):
        mirror = mirror | drawn_region(draw, size)
    regions: dict[str, np.ndarray | None] = {
        key: mirror
        for key in (
            "capture_camera",
            "capture_scene",
            "capture_copy",
            "environment_texture",
            "mirror_texture",
            "mirror_quad",
        )
    }
    regions.update(capture_copy=None, base_texture=None, passes=None, mirror=mirror)
    verdicts = judge_frame(
        verdicts,
        student,
        reference,
        regions,
        "passes",
        {"mirror": ("mirror_quad", "the mirror's picture")},
        clamp_rim(student, size, geometry),
    )
    return results(spec, student, verdicts)


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
