"""The cube-map lab's judge: the student's GLSL by the face and (s, t) it gives every pixel
of the sphere (against the OpenGL table and the usual slips), the six capture cameras by
the matrices each face was drawn with and the calls that set them, the copies by their
targets and what was cleared and set before each face, the faces against the reference's,
and the frame as a whole, with the sampling the student chose. Numpy only."""

from __future__ import annotations

from typing import Any

import numpy as np

from mirrorlab.envmap import CUBE_FACE_NAMES, cube_map
from mirrorlab.labs import LabSpec, task_name
from mirrorlab.labs.lab_cubemap.trusted import CubeMapLab
from mirrorlab.labs.lab_cubemap.variant import cube_center
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    INTEGER_HALF,
    Context,
    TaskResult,
    Verdicts,
    copy_format_slip,
    differing,
    fmt,
    glsl_body,
    judge_frame,
    matrix,
    misplaced_calls,
    picture,
    results,
    same_picture,
    stacked_ops,
    stopped_hint,
    where,
    wrong_clear_colour,
)
from mirrorlab.labs.trusted.probe import INPUTS, slip, slip_per_face
from mirrorlab.views import CUBE_FACE_AXES

GLSL_FUNCTIONS = ("cube_face", "cube_face_st")
CUBE_INPUTS = INPUTS["cube_face_st"][0].shape[0]
FACE_TARGETS = tuple(
    f"GL_TEXTURE_CUBE_MAP_{'POSITIVE' if n[0] == '+' else 'NEGATIVE'}_{n[1]}"
    for n in CUBE_FACE_NAMES
)
GL_TEXTURE_CUBE_MAP_POSITIVE_X = 0x8515
GL_MODELVIEW, GL_PROJECTION = 0x1700, 0x1701
GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT = 0x4000, 0x0100
MIN_FILTER = 0x2801
MIPMAP_FILTERS = {
    0x2700: "GL_NEAREST_MIPMAP_NEAREST",
    0x2701: "GL_LINEAR_MIPMAP_NEAREST",
    0x2702: "GL_NEAREST_MIPMAP_LINEAR",
    0x2703: "GL_LINEAR_MIPMAP_LINEAR",
}
NEAREST_OBJECT = 1.0
"""Every object of the scene is at least this far from the sphere's centre (its surface
is at 1): a near plane beyond it loses what the sphere would reflect."""
FARTHEST_OBJECT = 9.7
"""The picture behind the scene is this far along -z from any centre of the variants."""


def _task(task_id: str) -> str:
    """How a hint names another task of this lab (``task 8 (passes)``)."""
    return task_name("cubemap", task_id)


def _values(student: Evidence) -> tuple[np.ndarray, np.ndarray] | str:
    """(face, s, t) ``(n, 3)`` the student's functions gave and the kit's r ``(n, 3)``, or
    why there are none."""
    problem = student.state.get("values_error")
    if isinstance(problem, dict):
        return str(problem.get("message", ""))
    mask = student.arrays.get("values_mask")
    if not isinstance(mask, np.ndarray) or mask.dtype != bool or mask.ndim != 2 or mask.sum() < 50:
        return "the sphere could not be drawn with CUBE_MAP_GLSL"
    shape = (*mask.shape, 3)
    values, r = student.floats("values_face_st", shape), student.floats("values_r", shape)
    if values is None or r is None:
        return "the sphere could not be drawn with CUBE_MAP_GLSL"
    return values[mask], r[mask]


def judge_face(student: Evidence) -> tuple[bool, str]:
    got = _values(student)
    if isinstance(got, str):
        return False, got
    values, r = got
    if not np.all(np.isfinite(values[:, 0])):
        return False, "cube_face gives no number on the sphere"
    face = np.round(values[:, 0]).astype(np.int64)
    right, _, _ = cube_map(r)
    if np.mean(face == right) >= 0.98:
        return True, ""
    # the slip is named by the probe's values: directions on every face, of several
    # lengths, the major component negative on half of them
    found = slip("cube_face", student.floats("probe_cube_face", (CUBE_INPUTS, 4)))
    if found == "signed":
        return False, (
            "the face is picked by the largest signed component; the major axis is "
            "the one of largest magnitude: compare abs(r.x), abs(r.y), abs(r.z)"
        )
    if found == "opposite":
        return False, (
            "the right axis but the opposite sign: a positive component picks the "
            "POSITIVE face (0, 2, 4)"
        )
    if np.mean(face // 2 == right // 2) >= 0.98:
        return False, "the right axis, but the sign picks the wrong face on some pixels"
    if np.mean((face < 0) | (face > 5)) > 0.02:
        return False, "cube_face returns numbers outside 0..5"
    return False, (
        f"cube_face picks the wrong face on {np.mean(face != right):.0%} of the "
        f"sphere's pixels (the face is the axis of r's largest magnitude)"
    )


def judge_coordinates(student: Evidence) -> tuple[bool, str]:
    got = _values(student)
    if isinstance(got, str):
        return False, got
    values, r = got
    right_face, s, t = cube_map(r)
    face = np.round(values[:, 0]).astype(np.int64)
    ok = face == right_face
    if ok.mean() < 0.5:
        return False, f"judged once {_task('face_selection')} picks the right faces"
    st = values[ok, 1:]
    s, t = s[ok], t[ok]
    if not np.all(np.isfinite(st)):
        return False, "cube_face_st gives NaN or infinity on the sphere"
    if np.mean(np.abs(st - np.stack([s, t], -1)).max(-1) <= 2e-3) >= 0.98:
        return True, ""
    # the slip is named by the probe's values: directions on every face, of several
    # lengths, each with its right face whatever cube_face picks
    hints = {
        "swap": "s and t swapped: the table gives sc and tc per face, s from sc",
        "flip_s": "s mirrored on the faces: check the sign of sc in the table",
        "flip_t": "t upside down on the faces: check the sign of tc in the table",
        "undivided": "sc and tc must be divided by |major axis| before (x + 1) / 2",
        "length": "sc and tc are divided by the length of r; the table divides by |ma|, the "
        "major axis's size: s = (sc/|ma| + 1) / 2",
        "no_shift": "s and t must be (sc/|ma| + 1) / 2: they lie in [-1, 1] now",
        "no_scale": "s and t must be (sc/|ma| + 1) / 2: the / 2 is missing",
        "signed_major": "ma is the major axis's size, abs(...): with its sign, s and t are "
        "mirrored on the negative faces",
        "zero": "s and t are 0 everywhere: s = (sc/|ma| + 1) / 2",
    }
    probed = student.floats("probe_cube_face_st", (CUBE_INPUTS, 4))
    found = slip("cube_face_st", probed)
    # 1/2 in GLSL is integer division, 0: the same values as a factor 0 written out, so
    # only the source tells which it is
    if found == "zero" and INTEGER_HALF.search(glsl_body(student.source, "cube_face_st")):
        return False, (
            "s and t are 0 everywhere: 1/2 in GLSL is integer division, 0; write "
            "0.5, or divide by 2.0: s = (sc/|ma| + 1) / 2.0"
        )
    if found in hints:
        return False, hints[found]
    wrong = slip_per_face(probed)
    if wrong and all(wrong.values()):
        names = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")
        return False, "; ".join(
            f"on the {names[face]} face (face {face}): {hints[named]}"
            for face, named in sorted(wrong.items())
        )
    return False, "cube_face_st differs from the OpenGL table's (sc/|ma| + 1) / 2 on the sphere"


def _face_draws(student: Evidence) -> list[dict[str, Any]]:
    return student.events("draw", who="draw_scene", within="capture_cube")


def _near_far(projection: np.ndarray) -> tuple[float, float]:
    a, b = projection[2, 2], projection[2, 3]
    return float(b / (a - 1)), float(b / (a + 1))


def judge_cameras(
    student: Evidence, center: tuple[float, float, float], face_size: int, context: Context
) -> tuple[bool, str]:
    if not student.called("capture_cube"):
        return False, (
            f"capture_cube() was never called in the last frame: see {_task('live_frame')}"
        )
    draws = _face_draws(student)
    if not draws:
        return False, "capture_cube() draws nothing: lab.draw_scene() once for each face"
    if len(draws) != 6:
        return False, f"capture_cube() draws the scene {len(draws)} times; a cube map needs six"
    misplaced = misplaced_calls(
        student,
        "capture_cube",
        {
            "gluPerspective": GL_PROJECTION,
            "glFrustum": GL_PROJECTION,
            "glOrtho": GL_PROJECTION,
            "gluLookAt": GL_MODELVIEW,
        },
    )
    if misplaced:
        return False, misplaced
    for draw in draws:
        for mode, first in ((GL_PROJECTION, "gluPerspective"), (GL_MODELVIEW, "gluLookAt")):
            stacked = stacked_ops(draw, student, mode, first)
            if stacked:
                return False, stacked
    for draw in draws:
        projection = matrix(draw.get("projection"))
        if projection is None:
            return False, "the capture's matrices could not be read"
        ops = [
            e
            for e in student.events("matrix", within="capture_cube")
            if e["op"] in ("gluPerspective", "glFrustum")
        ]
        where_set = f" ({ops[-1]['op']} at {student.at(ops[-1]['line'])})" if ops else ""
        if not np.allclose(projection[3], (0, 0, -1, 0), atol=1e-6):
            return False, (
                f"the face cameras need a perspective projection{where_set}: "
                f"gluPerspective(90, 1, near, far)"
            )
        fovy = float(np.degrees(2 * np.arctan(1 / projection[1, 1])))
        aspect = float(projection[1, 1] / projection[0, 0])
        if abs(fovy - 90) > 0.05:
            return False, (
                f"field of view {fovy:.0f} degrees{where_set}: each face must see "
                f"exactly 90 (gluPerspective(90, 1, near, far)), or the faces do "
                f"not meet"
            )
        if abs(aspect - 1) > 1e-3:
            return False, f"aspect {aspect:.2f}{where_set}: the faces are square, aspect 1"
        near, far = _near_far(projection)
        if not 0 < near < NEAREST_OBJECT:
            return False, (
                f"the near plane {near:g}{where_set} is beyond the nearest objects, "
                f"about {NEAREST_OBJECT:g} from the sphere's centre, so the faces "
                f"lose them: use a near plane such as 0.05"
            )
        if far < FARTHEST_OBJECT:
            return False, (
                f"the far plane {far:g}{where_set} stops short of the picture behind "
                f"the scene, {FARTHEST_OBJECT:g} away: use a far plane such as 50"
            )
    for i, draw in enumerate(draws):
        modelview = matrix(draw.get("modelview"))
        if modelview is None:
            return False, "the capture's matrices could not be read"
        rotation = modelview[:3, :3]
        eye = -rotation.T @ modelview[:3, 3]
        if not np.allclose(eye, center, atol=1e-3):
            for name, variant in context.differing_others().items():
                if np.allclose(eye, cube_center(variant), atol=1e-3):
                    context.matched = name
                    owner = (
                        "the lab's own numbers"
                        if name == "default"
                        else "another student's variant"
                    )
                    return False, (
                        f"the cameras sit at ({fmt(eye)}), the sphere's centre in "
                        f"{owner}, not yours: your sphere's centre is "
                        f"({fmt(center)})"
                    )
            return False, (
                f"a face camera sits at ({fmt(eye)}): all six sit at the sphere's "
                f"centre ({fmt(center)})"
            )
        forward, up = -rotation[2], rotation[1]
        want_forward = np.asarray(CUBE_FACE_AXES[i][0], dtype=float)
        if np.dot(forward, want_forward) < 0.999:
            match = [j for j, (d, _) in enumerate(CUBE_FACE_AXES) if np.dot(forward, d) > 0.999]
            seen = CUBE_FACE_NAMES[match[0]] if match else "an odd direction"
            return False, (
                f"faces in the wrong order: capture {i} looks towards {seen}, but "
                f"{FACE_TARGETS[i]} is the {CUBE_FACE_NAMES[i]} face"
            )
        want_up = np.asarray(CUBE_FACE_AXES[i][1], dtype=float)
        if np.dot(up, want_up) < 0.999:
            return False, (
                f"the {CUBE_FACE_NAMES[i]} face's camera has up ({fmt(up)}); cube-map "
                f"faces are stored with t running down the side faces, so its up "
                f"must be {tuple(int(v) for v in want_up)}"
            )
    for i, draw in enumerate(draws):
        viewport = draw.get("viewport")
        if viewport != [0, 0, face_size, face_size]:
            setting = (draw.get("state") or {}).get("viewport") or {}
            line = setting.get("line", 0)
            inside = (
                " inside capture_cube()'s loop" if setting.get("function") == "capture_cube" else ""
            )
            by = f" (glViewport at {student.at(line)}{inside})" if line else ""
            size = viewport or [0, 0, 0, 0]
            return False, (
                f"the viewport when the {CUBE_FACE_NAMES[i]} face is drawn is "
                f"{size[2]} x {size[3]}{by}; draw each face in "
                f"glViewport(0, 0, FACE_SIZE, FACE_SIZE)"
            )
    return True, ""


def judge_copy(
    student: Evidence, reference: Evidence, cameras_ok: bool, face_size: int
) -> tuple[bool, str]:
    if student.events("draw", who="draw_sphere", within="capture_cube"):
        return False, "the sphere is drawn into its own capture: draw only lab.draw_scene() there"
    if not student.called("capture_cube"):
        return False, (
            f"capture_cube() was never called in the last frame: see {_task('live_frame')}"
        )
    events = student.last_frame
    draws = _face_draws(student)
    cube = student.state.get("cube_texture")
    copies = student.events("copy", within="capture_cube")
    if not copies:
        return False, (
            "capture_cube() copies nothing: after drawing each face, bind "
            "cube_texture to GL_TEXTURE_CUBE_MAP and glCopyTexImage2D("
            "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0, FACE_SIZE, "
            "FACE_SIZE, 0)"
        )
    positions = [events.index(d) for d in draws]
    previous = 0
    for i, start in enumerate(positions[:6]):
        end = positions[i + 1] if i + 1 < len(positions) else len(events)
        name = CUBE_FACE_NAMES[i]
        clears = [e for e in events[previous:start] if e.get("kind") == "clear"]
        if not clears:
            drawn_over = (
                f"the {CUBE_FACE_NAMES[i - 1]} face's picture" if i else "the last frame's picture"
            )
            return False, (
                f"the {name} face is drawn over {drawn_over}: glClear("
                f"GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT) before each face"
            )
        if clears:
            last = clears[-1]
            if not any(c["mask"] & GL_DEPTH_BUFFER_BIT for c in clears):
                return False, (
                    f"the depth buffer is not cleared between faces: glClear at "
                    f"{student.at(last['line'])} clears only the colour, so each "
                    f"face keeps the depths drawn before it and loses what lies "
                    f"behind them; clear GL_DEPTH_BUFFER_BIT too"
                )
            if wrong := wrong_clear_colour(last, CubeMapLab.BACKGROUND, student):
                return False, (
                    f"the faces are cleared to {wrong}: clear them to the scene's "
                    f"background, lab.BACKGROUND, as display() does"
                )
        face_copies = [e for e in events[start:end] if e.get("kind") == "copy"]
        if not face_copies:
            return False, (
                f"the {name} face is drawn but never copied: glCopyTexImage2D("
                f"{FACE_TARGETS[i]}, ...) after its lab.draw_scene()"
            )
        copy = face_copies[0]
        at = student.at(copy["line"])
        if copy["texture"] != cube:
            return False, (
                f"the copy at {at} went into texture {copy['texture']}, not "
                f"cube_texture: bind it to GL_TEXTURE_CUBE_MAP on unit 1 first"
            )
        if slip := copy_format_slip(copy):
            return False, f"the {name} face's copy at {at} {slip}"
        target = copy["target"] - GL_TEXTURE_CUBE_MAP_POSITIVE_X
        if target != i:
            into = FACE_TARGETS[target] if 0 <= target < 6 else hex(copy["target"])
            return False, (
                f"the {name} face's picture is copied into {into} at {at}: face "
                f"{i} goes into GL_TEXTURE_CUBE_MAP_POSITIVE_X + {i}"
            )
        if (
            copy["level"] != 0
            or (copy["x"], copy["y"]) != (0, 0)
            or (copy["width"], copy["height"]) != (face_size, face_size)
        ):
            return False, (
                f"the copy at {at} takes level {copy['level']}, "
                f"{copy['width']} x {copy['height']} pixels from ({copy['x']}, "
                f"{copy['y']}); copy level 0, FACE_SIZE x FACE_SIZE from (0, 0)"
            )
        previous = start + 1
    faces = student.arrays.get("cube_faces")
    ref = reference.arrays.get("cube_faces")
    if not isinstance(ref, np.ndarray):
        return False, "the reference faces are missing"
    if not isinstance(faces, np.ndarray) or faces.dtype != np.uint8 or faces.ndim != 4:
        return False, "cube_texture holds no six square faces after capture_cube()"
    if faces.shape != ref.shape:
        return False, f"the faces are {faces.shape[1]} texels wide; FACE_SIZE is {ref.shape[1]}"
    bad = [i for i in range(6) if not same_picture(faces[i], ref[i])]
    if not bad:
        return True, ""
    if not cameras_ok:
        return False, f"judged once the cameras, {_task('capture_cameras')}, are right"
    worst = max(bad, key=lambda i: int(differing(faces[i], ref[i]).sum()))
    mask = differing(faces[worst], ref[worst])
    return False, (
        f"face(s) {', '.join(CUBE_FACE_NAMES[i] for i in bad)} differ from the "
        f"reference; the {CUBE_FACE_NAMES[worst]} face in {int(mask.sum())} "
        f"texels, {where(mask)}"
    )


def _sampling(draw: dict[str, Any], student: Evidence) -> str:
    """A hint when the sphere samples mipmaps the cube map does not have (or has stale)."""
    params = draw.get("sampling") or {}
    minify = (params.get(str(MIN_FILTER)) or {}).get("value")
    if minify not in MIPMAP_FILTERS:
        return ""
    line = (params.get(str(MIN_FILTER)) or {}).get("line", 0)
    name = MIPMAP_FILTERS[minify]
    mipmaps = draw.get("mipmaps")
    if not mipmaps:
        return (
            f"cube_texture's minifying filter is {name} ({student.at(line)}), which wants "
            f"mipmaps it does not have, so the sphere is black: keep GL_LINEAR, or "
            f"glGenerateMipmap(GL_TEXTURE_CUBE_MAP) once all six faces are copied"
        )
    if not draw.get("mipmaps_fresh"):
        copies = student.events("copy", within="capture_cube")
        after = f" (the copies at line {copies[-1]['line']} come after it)" if copies else ""
        return (
            f"the sphere samples mipmaps made before the faces were copied: "
            f"glGenerateMipmap at {student.at(mipmaps.get('line', 0))} runs before this "
            f"frame's copies{after}; generate them once all six faces are copied, or keep "
            f"GL_LINEAR"
        )
    return ""


def judge_live_frame(student: Evidence, reference: Evidence) -> tuple[bool, str]:
    events = student.last_frame
    if not events:
        return False, "display() did not draw a frame"
    if hint := stopped_hint(student, "display"):
        return False, hint
    if not student.called("capture_cube"):
        return False, "display() never calls capture_cube(): the live map is captured every frame"
    index = {id(e): i for i, e in enumerate(events)}
    viewer = [
        e
        for e in student.events("draw", who="draw_scene", within="display")
        if "capture_cube" not in e.get("steps", [])
    ]
    capture = _face_draws(student)
    spheres = [
        e
        for e in student.events("draw", who="draw_sphere", within="display")
        if "capture_cube" not in e.get("steps", [])
    ]
    if viewer and capture and index[id(capture[0])] > index[id(viewer[-1])]:
        return False, (
            "passes in the wrong order: capture_cube() draws into the same "
            "framebuffer, so it runs before the frame is cleared and drawn"
        )
    if spheres and capture and index[id(capture[-1])] > index[id(spheres[-1])]:
        return False, "the sphere is drawn before this frame's capture: capture first"
    if not spheres:
        return False, "display() draws no sphere: lab.draw_sphere(CUBE_MAP_GLSL, cube_texture)"
    clears = [
        e
        for e in events[: index[id(viewer[-1])] if viewer else len(events)]
        if e.get("kind") == "clear"
        and "capture_cube" not in e.get("steps", [])
        and e["mask"] & GL_COLOR_BUFFER_BIT
    ]
    if clears and (wrong := wrong_clear_colour(clears[-1], CubeMapLab.BACKGROUND, student)):
        return False, (
            f"the frame is cleared to {wrong}, not the scene's background "
            f"lab.BACKGROUND: a glClearColor for the faces stays in force for the "
            f"frame too"
        )
    sampling = _sampling(spheres[-1], student)
    if sampling:
        return False, sampling
    return True, ""


def _mipmapped(student: Evidence) -> bool:
    spheres = student.events("draw", who="draw_sphere", within="display")
    if not spheres:
        return False
    params = spheres[-1].get("sampling") or {}
    return (params.get(str(MIN_FILTER)) or {}).get("value") in MIPMAP_FILTERS and bool(
        spheres[-1].get("mipmaps_fresh")
    )


def _blurred(image: np.ndarray, radius: int = 2) -> np.ndarray:
    """A box blur of ``image`` ``(h, w, 3)`` uint8 over (2 radius + 1)^2 pixels."""
    padded = np.pad(
        image.astype(np.float64), ((radius, radius), (radius, radius), (0, 0)), mode="edge"
    )
    total = np.zeros(image.shape, dtype=np.float64)
    height, width = image.shape[:2]
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            total += padded[dy : dy + height, dx : dx + width]
    return np.clip(total / (2 * radius + 1) ** 2 + 0.5, 0, 255).astype(np.uint8)


def judge(
    spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    center = cube_center(context.variant)
    faces = reference.arrays.get("cube_faces")
    face_size = int(faces.shape[1]) if isinstance(faces, np.ndarray) else 128
    cameras = judge_cameras(student, center, face_size, context)
    verdicts: Verdicts = {
        "face_selection": judge_face(student),
        "face_coordinates": judge_coordinates(student),
        "capture_cameras": cameras,
        "capture_copy": judge_copy(student, reference, cameras[0], face_size),
        "live_frame": judge_live_frame(student, reference),
    }
    mask = reference.arrays.get("values_mask")
    frame = reference.image("frame")
    regions: dict[str, np.ndarray | None] = {"live_frame": None}
    if isinstance(mask, np.ndarray) and frame is not None and mask.shape == frame.shape[:2]:
        sphere = _grow(mask)
        regions.update(
            {
                key: sphere
                for key in ("face_selection", "face_coordinates", "capture_cameras", "capture_copy")
            }
        )
        regions["sphere"] = sphere
    judged = student
    if _mipmapped(student) and "sphere" in regions and student.image("frame") is not None:
        # mipmaps made after the six faces are allowed: the sphere is then compared as a
        # trilinear filter sees it, both pictures blurred alike there
        region, ours, ref_frame = regions["sphere"], student.image("frame"), frame
        assert region is not None and ours is not None and ref_frame is not None
        sphere = region
        mine, theirs = ours.copy(), ref_frame.copy()
        mine[sphere] = _blurred(ours)[sphere]
        theirs[sphere] = _blurred(ref_frame)[sphere]
        judged = Evidence(student.lab, student.status, arrays={"frame": mine}, state=student.state)
        reference = Evidence(reference.lab, arrays={"frame": theirs})
    verdicts = judge_frame(
        verdicts,
        judged,
        reference,
        regions,
        "live_frame",
        {"sphere": ("live_frame", "the sphere's picture")},
    )
    return results(spec, student, verdicts, GLSL_FUNCTIONS)


def _grow(mask: np.ndarray, by: int = 2) -> np.ndarray:
    grown = mask.copy()
    for _ in range(by):
        shifted = grown.copy()
        shifted[1:] |= grown[:-1]
        shifted[:-1] |= grown[1:]
        shifted[:, 1:] |= grown[:, :-1]
        shifted[:, :-1] |= grown[:, 1:]
        grown = shifted
    return grown


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
        out[top + row * side : top + (row + 1) * side, col * side : (col + 1) * side] = faces[face][
            index
        ][:, index]
    return out


def check_picture(student: Evidence, reference: Evidence) -> np.ndarray:
    ref = reference.image("frame")
    shape = ref.shape[:2] if ref is not None else (256, 256)
    return picture(
        [
            (student.image("frame"), ref),
            (
                faces_grid(student.arrays.get("cube_faces"), shape[0]),
                faces_grid(reference.arrays.get("cube_faces"), shape[0]),
            ),
        ],
        shape,
    )
