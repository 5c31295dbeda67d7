"""Lab 20's judge: each task's verdict and hint from what the student's run showed (the
capture's matrices, ENVIRONMENT's parameters and picture, METAL, the sampler uniform,
the frame and the order of the passes), against the reference solution's run. Numpy only.
"""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs import LabSpec
from mirrorlab.labs.judging import Evidence, TaskResult, picture, results_with_errors, share_within
from mirrorlab.labs.kit import Lab20
from mirrorlab.scene.backgrounds import image_sampler

EXTENTS = (-6.0, 2.0, -3.0, 5.0, 0.0, 15.0)
CAPTURE_EYE, CAPTURE_TARGET, CAPTURE_UP = (-7.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)
CORNERS = ((-7, -3, -6), (-7, 5, -6), (-7, 5, 2), (-7, -3, 2))
MIRROR_X = -7.0

GL_LINEAR, GL_NEAREST = 0x2601, 0x2600
GL_CLAMP, GL_CLAMP_TO_EDGE, GL_CLAMP_TO_BORDER = 0x2900, 0x812F, 0x812D
GL_REPEAT, GL_MIRRORED_REPEAT = 0x2901, 0x8370
MIPMAP_FILTERS = {0x2700: "GL_NEAREST_MIPMAP_NEAREST", 0x2701: "GL_LINEAR_MIPMAP_NEAREST",
                  0x2702: "GL_NEAREST_MIPMAP_LINEAR", 0x2703: "GL_LINEAR_MIPMAP_LINEAR"}

TEXCOORD_MISTAKES = (
    # (name, transform of the right (s, t), hint)
    ("right", lambda s, t: (s, t), ""),
    ("flip_s", lambda s, t: (1 - s, t),
     "texture coordinates flipped left-right: s must grow with z, 0 at z = -6 and 1 at z = 2"),
    ("flip_t", lambda s, t: (s, 1 - t),
     "texture coordinates upside down: t must grow with y, 0 at y = -3 and 1 at y = 5"),
    ("rotate_180", lambda s, t: (1 - s, 1 - t),
     "texture coordinates rotated by 180 degrees: corner (-7, -3, -6) takes (0, 0)"),
    ("swap", lambda s, t: (t, s),
     "texture coordinates rotated (s and t swapped): s follows z and t follows y"),
    ("rotate_90", lambda s, t: (t, 1 - s),
     "texture coordinates rotated by 90 degrees: s follows z and t follows y"),
    ("rotate_270", lambda s, t: (1 - t, s),
     "texture coordinates rotated by 90 degrees: s follows z and t follows y"),
    ("swap_flip", lambda s, t: (1 - t, 1 - s),
     "texture coordinates rotated (s and t swapped and flipped): s follows z and t follows y"),
)


def _fmt(values) -> str:
    return ", ".join(f"{v:g}" for v in np.round(np.asarray(values, dtype=np.float64), 2))


def ortho_extents(projection: np.ndarray) -> tuple[float, ...] | None:
    """The glOrtho extents (left, right, bottom, top, near, far) of an orthographic
    ``projection``, or None when it is not one."""
    p = projection
    if not np.allclose(p[3], (0, 0, 0, 1), atol=1e-6) or min(abs(p[0, 0]), abs(p[1, 1]),
                                                              abs(p[2, 2])) < 1e-12:
        return None
    width, height, depth = 2 / p[0, 0], 2 / p[1, 1], -2 / p[2, 2]
    mid_x, mid_y, mid_z = -p[0, 3] * width, -p[1, 3] * height, -p[2, 3] * depth
    return ((mid_x - width) / 2, (mid_x + width) / 2, (mid_y - height) / 2,
            (mid_y + height) / 2, (mid_z - depth) / 2, (mid_z + depth) / 2)


def camera_of(modelview: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eye position, look direction and up of a rigid ``modelview``."""
    rotation = modelview[:3, :3]
    return -rotation.T @ modelview[:3, 3], -rotation[2], rotation[1]


def judge_camera(student: Evidence) -> tuple[bool, str]:
    projection = student.matrix("projection_capture")
    modelview = student.matrix("modelview_capture")
    drawn = projection is not None
    if projection is None:
        projection = student.matrix("projection_after_capture")
        modelview = student.matrix("modelview_after_capture")
    if projection is None or modelview is None:
        return False, "create_mirror() did not run, so the capture's matrices were never set"
    hints = []
    expected_p = math3d.ortho(*EXTENTS)
    if not np.allclose(projection, expected_p, atol=1e-4):
        extents = ortho_extents(projection)
        if np.allclose(projection, np.eye(4)):
            hints.append("no projection is set: glMatrixMode(GL_PROJECTION), glLoadIdentity(), "
                         "then glOrtho(-6, 2, -3, 5, 0, 15)")
        elif extents is None:
            hints.append("the capture's projection is not orthographic (glFrustum or "
                         "gluPerspective?): use glOrtho(-6, 2, -3, 5, 0, 15)")
        else:
            hints.append(f"wrong extents: the projection is glOrtho({_fmt(extents)}); the "
                         f"mirror needs glOrtho(-6, 2, -3, 5, 0, 15)")
    expected_m = math3d.look_at(CAPTURE_EYE, CAPTURE_TARGET, CAPTURE_UP)
    if not np.allclose(modelview, expected_m, atol=1e-4):
        eye, forward, up = camera_of(modelview)
        rigid = np.allclose(modelview[:3, :3] @ modelview[:3, :3].T, np.eye(3), atol=1e-4)
        if rigid and np.dot(forward, (1, 0, 0)) < -0.9:
            hints.append(f"camera on the wrong side: it sits at ({_fmt(eye)}) looking towards "
                         f"-x, away from the robot; put it on the mirror at (-7, 0, 0) looking "
                         f"at the origin: gluLookAt(-7, 0, 0, 0, 0, 0, 0, 1, 0)")
        elif rigid and np.allclose(eye, (7, 0, 0), atol=0.1):
            hints.append("camera on the wrong side: it sits at (7, 0, 0); the mirror is at "
                         "x = -7: gluLookAt(-7, 0, 0, 0, 0, 0, 0, 1, 0)")
        elif rigid and np.allclose(forward, (1, 0, 0), atol=1e-3) and \
                not np.allclose(up, (0, 1, 0), atol=1e-3):
            hints.append(f"the capture camera's up is ({_fmt(up)}): use up (0, 1, 0), or the "
                         f"reflection turns")
        elif np.allclose(modelview, expected_m @ expected_m, atol=1e-4):
            hints.append("gluLookAt was applied twice: call glLoadIdentity() on the modelview "
                         "before gluLookAt each frame")
        else:
            hints.append(f"the capture camera sits at ({_fmt(eye)}) looking along "
                         f"({_fmt(forward)}); expected gluLookAt(-7, 0, 0, 0, 0, 0, 0, 1, 0)")
    if hints:
        return False, "; ".join(hints)
    if not drawn:
        return False, "the matrices are right but create_mirror() draws nothing with them"
    return True, ""


def judge_capture(student: Evidence, reference: Evidence, camera_ok: bool) -> tuple[bool, str]:
    ref = reference.image("capture")
    cap = student.image("capture", ref.shape if ref is not None else None)
    if mirror_inside_capture(student.last_frame_calls()):
        return False, ("the mirror is drawn into its own capture: render_mirror() runs inside "
                       "create_mirror(); draw only the scene there")
    drew = any(e.get("kind") == "draw_scene" and "create_mirror" in (e.get("steps") or [])
               for e in student.frame_events())
    if not drew:
        return False, ("create_mirror() draws nothing: call lab.draw_scene(robot) once its "
                       "projection and camera are set")
    if ref is None:
        return False, "the reference capture is missing"
    if cap is None:
        return False, "ENVIRONMENT could not be read after create_mirror() (see task 3)"
    if share_within(cap, ref, 24) >= 0.97:
        return True, ""
    if not camera_ok:
        return False, "the capture shows the wrong view: fix its projection and camera (task 1)"
    if student.state.get("metal_intact") is False:
        return False, "the capture went into METAL, not ENVIRONMENT: judged once task 3 passes"
    if student.state.get("base_texture") != "metal":
        return False, "the base is in the capture: judged once task 5 passes"
    mirror_like = share_within(cap, np.broadcast_to(cap.reshape(-1, 3).mean(0), cap.shape), 8)
    if mirror_like > 0.9:
        return False, ("the capture is one flat colour: was the mirror drawn over the scene "
                       "before the copy?")
    return False, (f"the capture differs from the reference in "
                   f"{100 * (1 - share_within(cap, ref, 24)):.0f}% of its pixels")


def mirror_inside_capture(calls: list[str]) -> bool:
    """Whether render_mirror() ran while create_mirror() was running."""
    depth = 0
    for call in calls:
        if call == "start create_mirror":
            depth += 1
        elif call == "end create_mirror":
            depth -= 1
        elif call == "start render_mirror" and depth > 0:
            return True
    return False


def judge_copy(student: Evidence, reference: Evidence) -> tuple[bool, str]:
    frame = student.image("frame")
    if "start create_mirror" not in student.calls:
        return False, "create_mirror() was never called (see task 8)"
    if student.state.get("metal_intact") is False:
        return False, ("the copy overwrote METAL: bind ENVIRONMENT first (glActiveTexture("
                       "GL_TEXTURE1); glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])), "
                       "since glCopyTexImage2D writes into the texture bound now")
    cap = student.image("capture")
    if cap is None:
        return False, "ENVIRONMENT has no picture after create_mirror(): copy the framebuffer " \
                      "with glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)"
    if frame is not None and cap.shape != frame.shape:
        return False, (f"ENVIRONMENT holds {cap.shape[1]}x{cap.shape[0]} pixels, the "
                       f"framebuffer {frame.shape[1]}x{frame.shape[0]}: copy all of it "
                       f"(WIDTH x HEIGHT) at level 0")
    if not cap.any() and mirror_inside_capture(student.last_frame_calls()):
        return True, "ENVIRONMENT holds the black mirror that covered the capture (task 2)"
    if not cap.any():
        return False, ("ENVIRONMENT is still blank: nothing was copied into its level 0 "
                       "(glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0) "
                       "with ENVIRONMENT bound)")
    return True, ""


def judge_environment(student: Evidence) -> tuple[bool, str]:
    params = student.state.get("environment_parameters")
    if not isinstance(params, dict):
        return False, "ENVIRONMENT (tex_ids[ENVIRONMENT]) is not a texture after load_textures()"
    hints = []
    minify = params.get("GL_TEXTURE_MIN_FILTER")
    if minify in MIPMAP_FILTERS:
        hints.append(f"mipmaps on ENVIRONMENT: its minifying filter is {MIPMAP_FILTERS[minify]},"
                     f" but the capture fills level 0 only, so the texture is incomplete "
                     f"(black); use GL_LINEAR")
    elif params.get("level1_width", 0):
        hints.append("mipmaps on ENVIRONMENT: glGenerateMipmap made levels the capture never "
                     "updates; give it level 0 only")
    elif minify != GL_LINEAR or params.get("GL_TEXTURE_MAG_FILTER") != GL_LINEAR:
        hints.append("ENVIRONMENT's filters must both be GL_LINEAR (GL_TEXTURE_MIN_FILTER and "
                     "GL_TEXTURE_MAG_FILTER)")
    wraps = (params.get("GL_TEXTURE_WRAP_S"), params.get("GL_TEXTURE_WRAP_T"))
    if any(w in (GL_REPEAT, GL_MIRRORED_REPEAT) for w in wraps):
        hints.append("repeat wrapping on ENVIRONMENT: the mirror's edges would blend in the "
                      "opposite edge; clamp both (GL_CLAMP_TO_EDGE, or GL_CLAMP as the lab "
                      "text has it)")
    elif any(w not in (GL_CLAMP, GL_CLAMP_TO_EDGE) for w in wraps):
        hints.append("ENVIRONMENT's wrapping must clamp: GL_CLAMP_TO_EDGE for "
                     "GL_TEXTURE_WRAP_S and GL_TEXTURE_WRAP_T")
    return (not hints), "; ".join(hints)


def judge_base(student: Evidence) -> tuple[bool, str]:
    texture = student.state.get("base_texture")
    if texture == "metal":
        return True, ""
    if texture == "none":
        return False, ("base not textured: set robot[\"base\"].texture = tex_ids[METAL] in "
                       "build_scene_graph()")
    if texture == "environment":
        return False, "the base wears ENVIRONMENT: give it tex_ids[METAL]"
    return False, f"the base's texture is {texture}; expected tex_ids[METAL]"


def mirror_coordinates(size: tuple[int, int], inset: float = 0.1) -> tuple[np.ndarray, ...]:
    """For a ``size`` (w, h) frame of the lab's viewer: a mask ``(h, w)`` of the pixels whose
    ray meets the mirror's front (``inset`` world units inside its edges), and the mirror's
    (s, t) at each of them (``(n,)`` each)."""
    width, height = size
    projection, view = _viewer(size)
    inverse = np.linalg.inv(projection @ view)
    ys, xs = np.mgrid[0:height, 0:width]
    ndc_x = (xs + 0.5) / width * 2 - 1
    ndc_y = 1 - (ys + 0.5) / height * 2
    near = np.stack([ndc_x, ndc_y, -np.ones_like(ndc_x), np.ones_like(ndc_x)], -1) @ inverse.T
    far = np.stack([ndc_x, ndc_y, np.ones_like(ndc_x), np.ones_like(ndc_x)], -1) @ inverse.T
    near = near[..., :3] / near[..., 3:]
    far = far[..., :3] / far[..., 3:]
    direction = far - near
    with np.errstate(divide="ignore", invalid="ignore"):
        k = (MIRROR_X - near[..., 0]) / direction[..., 0]
    hit = near + k[..., None] * direction
    y, z = hit[..., 1], hit[..., 2]
    mask = (k > 0) & (y > -3 + inset) & (y < 5 - inset) & (z > -6 + inset) & (z < 2 - inset)
    return mask, (z[mask] + 6) / 8, (y[mask] + 3) / 8


def _viewer(size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    width, height = size
    return (math3d.perspective(Lab20.FOVY, width / height, Lab20.NEAR, Lab20.FAR),
            math3d.look_at(Lab20.EYE, Lab20.TARGET, (0.0, 1.0, 0.0)))


def classify_mirror(frame: np.ndarray, reference: Evidence, student_capture: np.ndarray | None,
                    metal: np.ndarray) -> tuple[str, float]:
    """What the student's mirror shows: a texture-coordinate mistake name from
    :data:`TEXCOORD_MISTAKES` (sampling the student's own capture, or the reference's),
    ``metal``, ``black`` or ``unknown``; and the share of mirror pixels that fit it."""
    height, width = frame.shape[:2]
    mask, s, t = mirror_coordinates((width, height))
    ref_frame, ref_capture = reference.image("frame"), reference.image("capture")
    if ref_frame is None or ref_capture is None or not mask.any():
        return "unknown", 0.0
    # only where the reference's mirror is seen (the robot may stand in front of it)
    seen = np.abs(ref_frame[mask].astype(float)
                  - 255 * image_sampler(ref_capture)(s, t)).max(-1) <= 24
    if seen.sum() < 50:
        return "unknown", 0.0
    pixels = frame[mask][seen].astype(np.float64)
    s, t = s[seen], t[seen]
    candidates: list[tuple[str, np.ndarray]] = []
    for capture in (student_capture, ref_capture):
        if capture is None or capture.shape != ref_capture.shape:
            continue
        sample = image_sampler(capture)
        for name, transform, _ in TEXCOORD_MISTAKES:
            ts, tt = transform(s, t)
            candidates.append((name, 255 * sample(ts, tt)))
    metal_sample = image_sampler(metal)
    candidates.append(("metal", 255 * metal_sample(s % 1.0, t % 1.0)))
    candidates.append(("black", np.zeros_like(pixels)))
    best, best_share = "unknown", 0.0
    for name, predicted in candidates:
        share = float(np.mean(np.abs(pixels - predicted).max(-1) <= 32))
        if share > best_share + 1e-9:
            best, best_share = name, share
    return (best, best_share) if best_share >= 0.8 else ("unknown", best_share)


def judge_mirror(student: Evidence, reference: Evidence) -> dict[str, tuple[bool, str]]:
    from mirrorlab.labs.kit import picture as kit_picture

    frame = student.image("frame")
    ref_frame = reference.image("frame")
    calls = student.last_frame_calls()
    if hint := student.stopped_hint("render_mirror"):
        return {"mirror_texture": (False, hint), "mirror_quad": (False, hint)}
    if "start render_mirror" not in calls:
        hint = "render_mirror() was not called in the last frame (see task 8)"
        return {"mirror_texture": (False, hint), "mirror_quad": (False, hint)}
    if frame is None or ref_frame is None or frame.shape != ref_frame.shape:
        hint = "no frame to judge the mirror by"
        return {"mirror_texture": (False, hint), "mirror_quad": (False, hint)}
    kind, share = classify_mirror(frame, reference, student.image("capture"),
                                  kit_picture("metal"))
    sampler = student.state.get("sampler")
    units = student.state.get("environment_units") or []
    if kind == "right":
        return {"mirror_texture": (True, ""), "mirror_quad": (True, "")}
    hints = {name: hint for name, _, hint in TEXCOORD_MISTAKES}
    if kind in hints:
        return {"mirror_texture": (True, ""), "mirror_quad": (False, hints[kind])}
    if kind == "metal" or (isinstance(sampler, int) and units and sampler not in units):
        if sampler == 0:
            hint = ("the mirror shows METAL: the sampler uniform is not set, so texSampler "
                    "reads unit 0; call glUniform1i(lab.texSampler, 1) after "
                    "glUseProgram(lab.textureShader)")
        else:
            hint = (f"the mirror shows the wrong texture: texSampler reads unit {sampler} but "
                    f"ENVIRONMENT is bound on unit(s) {units or 'none'}")
        return {"mirror_texture": (False, hint), "mirror_quad": (False, "judged once task 6 "
                                                                   "passes")}
    if kind == "black":
        hint = ("the mirror is black: ENVIRONMENT is not bound on the sampler's unit, or is "
                "incomplete (see task 4)")
        return {"mirror_texture": (False, hint), "mirror_quad": (False, "judged once task 6 "
                                                                   "passes")}
    if not units:
        return {"mirror_texture": (False, "ENVIRONMENT is not bound when the mirror is drawn: "
                                          "glActiveTexture(GL_TEXTURE1); glBindTexture("
                                          "GL_TEXTURE_2D, tex_ids[ENVIRONMENT])"),
                "mirror_quad": (False, "judged once task 6 passes")}
    return {"mirror_texture": (True, ""),
            "mirror_quad": (False, f"only {share:.0%} of the mirror's pixels show ENVIRONMENT "
                                   f"where they should: check the corners (-7,-3,-6), "
                                   f"(-7,5,-6), (-7,5,2), (-7,-3,2) and their texture "
                                   f"coordinates")}


def judge_passes(student: Evidence) -> tuple[bool, str]:
    calls = student.last_frame_calls()
    if not calls:
        return False, "display() did not draw a frame"
    if hint := student.stopped_hint("display"):
        return False, hint
    events = student.frame_events()
    camera = next((i for i, e in enumerate(events) if e.get("kind") == "draw_scene"
                   and e.get("steps") == ["display"]), None)
    capture = next((i for i, e in enumerate(events) if e.get("kind") == "draw_scene"
                    and "create_mirror" in (e.get("steps") or [])), None)
    if "start create_mirror" not in calls:
        return False, ("display() never calls create_mirror(): pass 1 must run every frame, "
                       "before the camera pass")
    if "start render_mirror" not in calls:
        return False, "display() never calls render_mirror() after drawing the scene"
    if camera is None:
        return False, "display() does not draw the scene from the viewer (lab.draw_scene)"
    if capture is not None and capture > camera:
        return False, ("passes in the wrong order: create_mirror() draws into the same "
                       "framebuffer, so it must run before the frame is cleared and drawn "
                       "from the viewer")
    outside = [c for i, c in enumerate(calls) if c in ("start render_mirror", "end create_mirror")
               and not mirror_inside_capture(calls[:i + 1])]
    if outside and outside[0] == "start render_mirror":
        return False, ("passes in the wrong order: render_mirror() runs before create_mirror() "
                       "has copied this frame's capture")
    return True, ""


def judge(spec: LabSpec, student: Evidence, reference: Evidence) -> list[TaskResult]:
    camera_ok, camera_hint = judge_camera(student)
    passes = judge_passes(student)
    mirror = judge_mirror(student, reference)
    if not passes[0] and "wrong order" in passes[1]:
        mirror = {key: (False, "judged once task 8 passes: this frame is not the camera pass")
                  for key in mirror}
    verdicts = {
        "capture_camera": (camera_ok, camera_hint),
        "capture_scene": judge_capture(student, reference, camera_ok),
        "capture_copy": judge_copy(student, reference),
        "environment_texture": judge_environment(student),
        "base_texture": judge_base(student),
        **mirror,
        "passes": passes,
    }
    return results_with_errors(spec, student, verdicts)


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    """Frame and capture: student | reference | difference."""
    ref_frame = reference.image("frame")
    shape = ref_frame.shape[:2] if ref_frame is not None else (256, 256)
    return picture([(student.image("frame"), ref_frame),
                    (student.image("capture"), reference.image("capture"))], shape)
