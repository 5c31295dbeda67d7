"""The cube-map lab's judge: the student's GLSL by the face and (s, t) it gives every pixel
of the sphere (against the OpenGL table and the usual slips), the six capture cameras by
the matrices the scene was drawn with, the captured faces against the reference's, and
the frame. Numpy only."""

from __future__ import annotations

import numpy as np

from mirrorlab.envmap import cube_map
from mirrorlab.labs import LabSpec
from mirrorlab.labs.judging import Evidence, TaskResult, picture, results_with_errors, share_within
from mirrorlab.labs.kit import CubeMapLab
from mirrorlab.views import CUBE_FACE_NAMES, CUBE_FACES

GLSL_FUNCTIONS = ("cube_face", "cube_face_st")
FACE_TARGETS = tuple(f"GL_TEXTURE_CUBE_MAP_{'POSITIVE' if n[0] == '+' else 'NEGATIVE'}_{n[1]}"
                     for n in CUBE_FACE_NAMES)


def _values(student: Evidence) -> tuple[np.ndarray, np.ndarray] | None:
    """(face, s, t) ``(n, 3)`` the student's functions gave and the kit's r ``(n, 3)``."""
    mask = student.arrays.get("values_mask")
    if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.ndim != 2 or \
            mask.sum() < 50:
        return None
    shape = (*mask.shape, 3)
    values, r = student.floats("values_face_st", shape), student.floats("values_r", shape)
    if values is None or r is None:
        return None
    return values[mask], r[mask]


def judge_face(student: Evidence) -> tuple[bool, str]:
    got = _values(student)
    if got is None:
        return False, "the sphere could not be drawn with CUBE_MAP_GLSL"
    values, r = got
    if not np.all(np.isfinite(values[:, 0])):
        return False, "cube_face gives no number on the sphere"
    face = np.round(values[:, 0]).astype(np.int64)
    right, _, _ = cube_map(r)
    if np.mean(face == right) >= 0.98:
        return True, ""
    axis = np.argmax(r, axis=-1)
    signed = 2 * axis + (np.take_along_axis(r, axis[:, None], -1)[:, 0] < 0)
    if np.mean(face == signed) >= 0.98:
        return False, ("the face is picked by the largest signed component; the major axis is "
                       "the one of largest magnitude: compare abs(r.x), abs(r.y), abs(r.z)")
    if np.mean(face == (right ^ 1)) >= 0.98:
        return False, ("the right axis but the opposite sign: a positive component picks the "
                       "POSITIVE face (0, 2, 4)")
    if np.mean(face // 2 == right // 2) >= 0.98:
        return False, "the right axis, but the sign picks the wrong face on some pixels"
    if np.mean((face < 0) | (face > 5)) > 0.02:
        return False, "cube_face returns numbers outside 0..5"
    return False, (f"cube_face picks the wrong face on {np.mean(face != right):.0%} of the "
                   f"sphere's pixels (the face is the axis of r's largest magnitude)")


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    got = _values(student)
    if got is None:
        return False, "the sphere could not be drawn with CUBE_MAP_GLSL"
    values, r = got
    right_face, s, t = cube_map(r)
    face = np.round(values[:, 0]).astype(np.int64)
    ok = face == right_face
    if ok.mean() < 0.5:
        return False, "judged once task 1 picks the right faces"
    st = values[ok, 1:]
    s, t, r, faces = s[ok], t[ok], r[ok], right_face[ok]
    if not np.all(np.isfinite(st)):
        return False, "cube_face_st gives NaN or infinity on the sphere"
    right = np.stack([s, t], -1)
    major = np.abs(np.take_along_axis(r, (faces // 2)[:, None], -1))
    undivided = (2 * right - 1) * major
    candidates = {
        "right": right, "swap": right[:, ::-1], "flip_s": np.stack([1 - s, t], -1),
        "flip_t": np.stack([s, 1 - t], -1), "undivided": (undivided + 1) / 2,
        "no_shift": 2 * right - 1, "no_scale": (2 * right - 1) + 1}
    hints = {
        "swap": "s and t swapped: the table gives sc and tc per face, s from sc",
        "flip_s": "s mirrored on the faces: check the sign of sc in the table",
        "flip_t": "t upside down on the faces: check the sign of tc in the table",
        "undivided": "sc and tc must be divided by |major axis| before (x + 1) / 2",
        "no_shift": "s and t must be (sc/|ma| + 1) / 2: they lie in [-1, 1] now",
        "no_scale": "s and t must be (sc/|ma| + 1) / 2: the / 2 is missing",
    }
    for name, predicted in candidates.items():
        if np.mean(np.abs(st - predicted).max(-1) <= 2e-3) >= 0.98:
            return (True, "") if name == "right" else (False, hints[name])
    return False, "cube_face_st differs from the OpenGL table's (sc/|ma| + 1) / 2 on the sphere"


def judge_cameras(student: Evidence) -> tuple[bool, str]:
    if "start capture_cube" not in student.calls:
        return False, "capture_cube() was never called (see task 5)"
    projections = student.arrays.get("capture_projections")
    modelviews = student.arrays.get("capture_modelviews")
    if not isinstance(projections, np.ndarray) or projections.ndim != 3 or \
            not isinstance(modelviews, np.ndarray) or modelviews.shape != projections.shape:
        return False, "capture_cube() draws nothing: lab.draw_scene() once for each face"
    count = len(projections)
    if count != 6:
        return False, f"capture_cube() draws the scene {count} times; a cube map needs six"
    hints: list[str] = []
    for projection in projections:
        if not np.allclose(projection[3], (0, 0, -1, 0), atol=1e-6):
            hints.append("the face cameras need a perspective projection: gluPerspective(90, 1, "
                         "near, far)")
            break
        fovy = float(np.degrees(2 * np.arctan(1 / projection[1, 1])))
        aspect = float(projection[1, 1] / projection[0, 0])
        if abs(fovy - 90) > 0.05:
            hints.append(f"field of view {fovy:.0f} degrees: each face must see exactly 90 "
                         f"(gluPerspective(90, 1, near, far)), or the faces do not meet")
            break
        if abs(aspect - 1) > 1e-3:
            hints.append(f"aspect {aspect:.2f}: the faces are square, aspect 1")
            break
    center = np.asarray(CubeMapLab.CENTER)
    forwards, ups = [], []
    for modelview in modelviews:
        rotation = modelview[:3, :3]
        eye = -rotation.T @ modelview[:3, 3]
        if not np.allclose(eye, center, atol=1e-3):
            hints.append(f"a face camera sits at ({', '.join(f'{v:g}' for v in np.round(eye, 2))})"
                         f": all six sit at the sphere's centre {CubeMapLab.CENTER}")
            break
        forwards.append(-rotation[2])
        ups.append(rotation[1])
    if not hints:
        expected = [np.asarray(d, dtype=float) for d, _ in CUBE_FACES]
        for i, forward in enumerate(forwards):
            if np.dot(forward, expected[i]) < 0.999:
                match = [j for j, e in enumerate(expected) if np.dot(forward, e) > 0.999]
                seen = f"{CUBE_FACE_NAMES[match[0]]}" if match else "an odd direction"
                hints.append(f"faces in the wrong order: capture {i} looks towards {seen}, but "
                             f"{FACE_TARGETS[i]} is the {CUBE_FACE_NAMES[i]} face")
                break
    if not hints:
        for i, up in enumerate(ups):
            want = np.asarray(CUBE_FACES[i][1], dtype=float)
            if np.dot(up, want) < 0.999:
                hints.append(f"the {CUBE_FACE_NAMES[i]} face's camera has up "
                             f"({', '.join(f'{v:g}' for v in np.round(up, 2))}); cube-map faces "
                             f"are stored with t running down the side faces, so its up must be "
                             f"{tuple(int(v) for v in want)}")
                break
    viewports = student.state.get("capture_viewports")
    if not hints and isinstance(viewports, list) and viewports:
        sizes = {tuple(v[2:4]) for v in viewports if isinstance(v, list) and len(v) == 4}
        if any(w != h for w, h in sizes):
            hints.append("the viewport of a face capture is not square: glViewport(0, 0, "
                         "FACE_SIZE, FACE_SIZE)")
    return (not hints), "; ".join(hints)


def judge_copy(student: Evidence, reference: Evidence, cameras_ok: bool) -> tuple[bool, str]:
    if any(e.get("kind") == "draw_sphere" and "capture_cube" in (e.get("steps") or [])
           for e in student.frame_events()):
        return False, "the sphere is drawn into its own capture: draw only lab.draw_scene() there"
    if "start capture_cube" not in student.calls:
        return False, "capture_cube() was never called (see task 5)"
    faces = student.arrays.get("cube_faces")
    ref = reference.arrays.get("cube_faces")
    if not isinstance(ref, np.ndarray):
        return False, "the reference faces are missing"
    if not isinstance(faces, np.ndarray) or faces.dtype != np.uint8 or faces.ndim != 4:
        return False, ("cube_texture holds no six square faces after capture_cube(): "
                       "glCopyTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0, "
                       "FACE_SIZE, FACE_SIZE, 0) with the cube map bound")
    if faces.shape != ref.shape:
        return False, f"the faces are {faces.shape[1]} texels wide; FACE_SIZE is {ref.shape[1]}"
    if not faces.any():
        return False, ("the faces are still blank: nothing was copied into them (bind "
                       "cube_texture to GL_TEXTURE_CUBE_MAP, then glCopyTexImage2D("
                       "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, ...) after drawing each face)")
    bad = [i for i in range(6) if share_within(faces[i], ref[i], 24) < 0.97]
    if not bad:
        return True, ""
    if not cameras_ok:
        return False, "judged once the cameras (task 3) are right"
    return False, (f"face(s) {', '.join(CUBE_FACE_NAMES[i] for i in bad)} differ from the "
                   f"reference: is each copied right after its own picture, into its own face?")


def judge_frame(student: Evidence, reference: Evidence,
                verdicts: dict[str, tuple[bool, str]]) -> tuple[bool, str]:
    calls = student.last_frame_calls()
    events = student.frame_events()
    if not calls:
        return False, "display() did not draw a frame"
    if "start capture_cube" not in calls:
        return False, "display() never calls capture_cube(): the live map is captured every frame"
    viewer = next((i for i, e in enumerate(events) if e.get("kind") == "draw_scene"
                   and e.get("steps") == ["display"]), None)
    capture = next((i for i, e in enumerate(events) if e.get("kind") == "draw_scene"
                    and "capture_cube" in (e.get("steps") or [])), None)
    sphere = next((i for i, e in enumerate(events) if e.get("kind") == "draw_sphere"
                   and e.get("steps") == ["display"]), None)
    if viewer is not None and capture is not None and capture > viewer:
        return False, ("passes in the wrong order: capture_cube() draws into the same "
                       "framebuffer, so it runs before the frame is cleared and drawn")
    if sphere is not None and capture is not None and capture > sphere:
        return False, "the sphere is drawn before this frame's capture: capture first"
    frames, why = student.displayed_frames(reference)
    if frames is None:
        return False, why
    frame, ref = frames
    sphere_mask = reference.arrays.get("values_mask")
    in_sphere = share_within(frame, ref, 24, sphere_mask) if isinstance(
        sphere_mask, np.ndarray) and sphere_mask.shape == frame.shape[:2] else 0.0
    if share_within(frame, ref, 24) >= 0.97 and in_sphere >= 0.95:
        return True, ""
    if not all(verdicts[key][0] for key in verdicts):
        return False, "the frame is judged once tasks 1 to 4 pass"
    return False, (f"the sphere differs from the reference's on {1 - in_sphere:.0%} of its "
                   f"pixels")


def judge(spec: LabSpec, student: Evidence, reference: Evidence) -> list[TaskResult]:
    cameras = judge_cameras(student)
    verdicts = {
        "face_selection": judge_face(student),
        "face_coordinates": judge_coordinates(student),
        "capture_cameras": cameras,
        "capture_copy": judge_copy(student, reference, cameras[0]),
    }
    verdicts["live_frame"] = judge_frame(student, reference, verdicts)
    return results_with_errors(spec, student, verdicts, GLSL_FUNCTIONS)


def faces_grid(faces: np.ndarray | None, height: int) -> np.ndarray | None:
    """The six faces in GL order as a 3 x 2 grid (+X -X +Y over -Y +Z -Z), in a square
    picture ``height`` on a side."""
    if not isinstance(faces, np.ndarray) or faces.ndim != 4 or faces.shape[0] != 6:
        return None
    side = height // 3
    index = np.linspace(0, faces.shape[1] - 1, side).astype(int)
    out = np.full((height, height, 3), 255, dtype=np.uint8)
    top = (height - 2 * side) // 2
    for face in range(6):
        row, col = divmod(face, 3)
        out[top + row * side:top + (row + 1) * side, col * side:(col + 1) * side] = \
            faces[face][index][:, index]
    return out


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture([(student.image("frame"), ref),
                    (faces_grid(student.arrays.get("cube_faces"), shape[0]),
                     faces_grid(reference.arrays.get("cube_faces"), shape[0]))], shape)


