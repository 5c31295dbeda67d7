"""The labs in macOS's OpenGL 4.1 core context, simulated with Mesa's overrides: there the
trusted side carries out the legacy calls itself (labs/trusted/legacy.py) and translates
the compatibility built-ins of GLSL (labs/trusted/compat_glsl.py). Mesa's own
compatibility pipeline is the oracle: each lab's reference solution, untouched starter and
mutants are graded both ways, and each way must give the same verdict and hint for every
task, and the same picture within :data:`PIXEL_TOLERANCE` (docs/labs-teachers.md states
it). Each way makes its own reference from the teacher's solution, as a student's machine
would."""

from __future__ import annotations

import importlib
import io
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from mirrorlab.labs import find_lab, lab_names, unregister
from mirrorlab.labs.trusted.grading import grade_folder
from tests import MACOS_CONTEXT
from tests.labs.classroom import STARTER, starter_text
from tests.labs.conftest import LIMITS, SOLUTIONS
from tests.labs.crashes import CRASHES
from tests.labs.mutants import (
    CUBE_EQUIVALENT,
    CUBEMAP,
    EQUIVALENT,
    LAB20,
    LAB20_MORE,
    PROBED_SLIPS,
    SPHEREMAP,
    write_mutants,
)

PIXEL_TOLERANCE = 2
"""The most a channel of the student's picture may differ (of 255) between the two ways,
but on :data:`STRAY_PIXELS` of the pixels. Measured on every solution, starter and mutant
of the three labs (63 files): at most 1, on at most 0.011% of the pixels; on
:data:`FIXED_FUNCTION`'s (in the quad lab), 10 pixels (0.015%) of a point centred on a
pixel corner, which the core context rasterises as a sprite one row and column over."""
STRAY_PIXELS = 0.0005
"""The judges' own share of pixels a frame may differ on (0.05%)."""

CHOSEN = {
    "lab20": (
        "wrong_corner",
        "mirror_in_capture",
        "legacy_gl_clamp",
        "triangle_fan",
        "two_triangles",
        "vector_calls",
        "no_projection_mode",
        "camera_wrong_side",
    ),
    "spheremap": (
        "texgen_object_linear",
        "texgen_left_on",
        "texgen_only_s",
        "texgen_reflection_map",
        "texgen_unit_1",
        "reflect_sign",
        "reflect_abs_dot",
        "st_minus_one",
    ),
    "cubemap": (
        "no_projection_mode",
        "up_wrong",
        "fov_60",
        "mipmaps_before_faces",
        "other_near_far",
        "st_signed_major_on_one_face",
    ),
}
"""The mutants graded both ways: where the core context's emulation differs most from
Mesa's pipeline (a quad's diagonal under texture coordinates no plane holds, a vertex on
the near plane, GL_CLAMP, the other primitives, texgen's modes, units and switches, the
matrix modes and GLU), a quarter of the time of all of them. ``MIRRORLAB_ORACLE_ALL=1``
grades every mutant (98 s here, against 47 s; 7 minutes, against 103 s, under load)."""
EVERY = {
    "lab20": (*LAB20, *EQUIVALENT, *LAB20_MORE),
    "spheremap": (*SPHEREMAP, *(m for m in PROBED_SLIPS if m.lab == "spheremap")),
    "cubemap": (*CUBEMAP, *CUBE_EQUIVALENT, *(m for m in PROBED_SLIPS if m.lab == "cubemap")),
}


FIXED_FUNCTION = '''import numpy as np

FAN = [(0.8 + 0.15 * c, 0.8 + 0.15 * s, c, s) for c, s in (
    (1.0, 0.0), (0.8776, 0.4794), (0.5403, 0.8415), (0.0707, 0.9975), (-0.4161, 0.9093),
    (-0.8011, 0.5985), (-0.99, 0.1411))]
WIDTH = HEIGHT = 256
metal = cube = blank = luminance = old_style = 0


def textures():
    """A lab picture, and from copies of the frame so far a cube map and textures of the
    legacy formats (luminance, luminance and alpha, across the quad's edge), GL_CLAMP."""
    global metal, cube, blank, luminance, old_style
    metal, cube, blank, luminance, old_style = (int(t) for t in glGenTextures(5))
    lab.load_picture_texture(metal, "metal")
    glBindTexture(GL_TEXTURE_CUBE_MAP, cube)
    for face in range(6):
        x, y = 20 * face, 30 + 10 * face
        glCopyTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, x, y, 64, 64, 0)
    for pname in (GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER):
        glTexParameteri(GL_TEXTURE_CUBE_MAP, pname, GL_LINEAR)
    glBindTexture(GL_TEXTURE_2D, luminance)
    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_LUMINANCE, 63, 100, 2, 2, 0)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP)
    glBindTexture(GL_TEXTURE_2D, old_style)
    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_LUMINANCE_ALPHA, 62, 120, 4, 1, 0)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR)
    glBindTexture(GL_TEXTURE_2D, blank)  # format 3, its image at level 0, sampled from 1:
    glTexImage2D(GL_TEXTURE_2D, 0, 3, 4, 4, 0, GL_RGB, GL_UNSIGNED_BYTE, None)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 1)  # incomplete: untextured


def fixed_function():
    """Drawing in every fixed pipeline's way (an oracle's test only)."""
    glUseProgram(0)
    glMatrixMode(GL_PROJECTION)
    glPushMatrix()
    glLoadIdentity()
    glOrtho(-1, 1, -1, 1, -1, 1)
    glMatrixMode(GL_MODELVIEW)
    glPushMatrix()
    glLoadIdentity()
    glDisable(GL_DEPTH_TEST)
    glEnable(GL_LIGHTING)
    glEnable(GL_LIGHT0)
    glEnable(GL_COLOR_MATERIAL)
    glEnable(GL_NORMALIZE)
    glBegin(GL_TRIANGLES)
    glColor3f(1, 0, 0)
    glNormal3f(0, 0, 2)
    glVertex2f(-1, -1)
    glColor3f(0, 1, 0)
    glNormal3f(1, 0, 1)
    glVertex2f(-0.5, -1)
    glColor3f(0, 0, 1)
    glNormal3f(0, 1, 1)
    glVertex2f(-0.75, -0.5)
    glEnd()
    glDisable(GL_COLOR_MATERIAL)
    glBegin(GL_QUADS)
    glNormal3f(0.3, 0.2, 1)
    glVertex2f(-1, 0.1)
    glVertex2f(-0.7, 0.1)
    glNormal3f(-0.5, 0.2, 1)
    glVertex2f(-0.7, 0.4)
    glVertex2f(-1, 0.4)
    glEnd()
    glDisable(GL_LIGHTING)
    glShadeModel(GL_FLAT)
    glBegin(GL_QUAD_STRIP)
    for i in range(4):
        glColor3f(i / 3, 0.5, 1 - i / 3)
        glVertex2f(-0.4 + 0.2 * i, -1)
        glVertex2f(-0.4 + 0.2 * i, -0.6)
    glEnd()
    glShadeModel(GL_SMOOTH)
    glActiveTexture(GL_TEXTURE0)
    glBindTexture(GL_TEXTURE_2D, metal)
    glEnable(GL_TEXTURE_2D)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE)
    glMatrixMode(GL_TEXTURE)
    glLoadIdentity()
    glScalef(2, 2, 1)
    glMatrixMode(GL_MODELVIEW)
    glColor3f(1, 0.8, 0.6)
    glBegin(GL_POLYGON)
    for x, y, s, t in ((0.3, -1, 0, 0), (0.7, -1, 1, 0), (0.8, -0.7, 1, 0.6), (0.5, -0.5, 0.5, 1),
                       (0.3, -0.7, 0, 0.6)):
        glTexCoord2f(s, t)
        glVertex2f(x, y)
    glEnd()
    glMatrixMode(GL_TEXTURE)
    glLoadIdentity()
    glMatrixMode(GL_MODELVIEW)
    glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glEnable(GL_TEXTURE_GEN_S)
    glEnable(GL_TEXTURE_GEN_T)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE)
    glBegin(GL_TRIANGLE_FAN)
    glNormal3f(0, 0, 1)
    glVertex3f(0.8, 0.8, 0.5)
    for x, y, c, s in FAN:
        glNormal3f(c, s, 1)
        glVertex3f(x, y, 0.5)
    glEnd()
    glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_OBJECT_LINEAR)
    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_EYE_LINEAR)
    glTexGenfv(GL_S, GL_OBJECT_PLANE, (2.0, 0.5, 0.0, 0.25))
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_DECAL)
    glBegin(GL_TRIANGLE_STRIP)
    glVertex2f(0.2, 0.2)
    glVertex2f(0.5, 0.2)
    glVertex2f(0.2, 0.5)
    glVertex2f(0.5, 0.5)
    glEnd()
    glDisable(GL_TEXTURE_GEN_S)
    glDisable(GL_TEXTURE_GEN_T)
    glDisable(GL_TEXTURE_2D)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE)
    glColor3f(1, 1, 0)
    glBegin(GL_LINE_LOOP)
    glVertex2f(-0.9, 0.5)
    glVertex2f(-0.5, 0.9)
    glVertex2f(-0.1, 0.5)
    glEnd()
    glPointSize(3)
    glBegin(GL_POINTS)
    glVertex2f(0, 0)
    glEnd()
    glBindTexture(GL_TEXTURE_2D, blank)
    glEnable(GL_TEXTURE_2D)
    glColor3f(0.2, 0.9, 0.4)
    glBegin(GL_QUADS)
    glVertex2f(0.55, 0.0)
    glVertex2f(0.75, 0.0)
    glVertex2f(0.75, 0.2)
    glVertex2f(0.55, 0.2)
    glEnd()
    glBindTexture(GL_TEXTURE_2D, luminance)
    glColor3f(1, 0.5, 1)
    glBegin(GL_QUADS)
    for s, t in ((-0.2, -0.2), (1.2, -0.2), (1.2, 1.2), (-0.2, 1.2)):
        glTexCoord2f(s, t)
        glVertex2f(0.8 + 0.2 * s, 0.2 + 0.2 * t)
    glEnd()
    glBindTexture(GL_TEXTURE_2D, old_style)
    glBegin(GL_QUADS)
    for s, t in ((0, 0), (1, 0), (1, 1), (0, 1)):
        glTexCoord2f(s, t)
        glVertex2f(0.8 + 0.2 * s, -0.2 + 0.2 * t)
    glEnd()
    glDisable(GL_TEXTURE_2D)
    glColor3f(1, 1, 1)
    cube_discs()
    glMatrixMode(GL_PROJECTION)
    glPopMatrix()
    glMatrixMode(GL_MODELVIEW)
    glPopMatrix()
    glEnable(GL_DEPTH_TEST)


def cube_discs():
    """The cube map on two discs, through GL_REFLECTION_MAP and GL_NORMAL_MAP texgen."""
    glActiveTexture(GL_TEXTURE1)
    glBindTexture(GL_TEXTURE_CUBE_MAP, cube)
    glEnable(GL_TEXTURE_CUBE_MAP)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE)
    for mode, x in ((GL_REFLECTION_MAP, -0.6), (GL_NORMAL_MAP, -0.2)):
        for coord in (GL_S, GL_T, GL_R):
            glTexGeni(coord, GL_TEXTURE_GEN_MODE, mode)
        for cap in (GL_TEXTURE_GEN_S, GL_TEXTURE_GEN_T, GL_TEXTURE_GEN_R):
            glEnable(cap)
        glBegin(GL_TRIANGLE_FAN)
        glNormal3f(0, 0, 1)
        glVertex3f(x, -0.3, 0.2)
        for i in range(13):
            c, s = (1, 0.866, 0.5, 0, -0.5, -0.866, -1, -0.866, -0.5, 0, 0.5, 0.866, 1)[i], \\
                (0, 0.5, 0.866, 1, 0.866, 0.5, 0, -0.5, -0.866, -1, -0.866, -0.5, 0)[i]
            glNormal3f(c, s, 0.4)
            glVertex3f(x + 0.15 * c, -0.3 + 0.15 * s, 0.2)
        glEnd()
    for cap in (GL_TEXTURE_GEN_S, GL_TEXTURE_GEN_T, GL_TEXTURE_GEN_R, GL_TEXTURE_CUBE_MAP):
        glDisable(cap)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE)
    glActiveTexture(GL_TEXTURE0)


_display = display


def display():
    _display()
    if not metal:
        textures()
    fixed_function()
'''
"""Appended to the quad lab's solution (the test folder's lab that opens every channel the
shipped labs close): drawing in every way the fixed pipeline can (default lighting, the
material GL_COLOR_MATERIAL leaves, flat shading, quads, quad strips, polygons, fans,
texture matrices, texgen's sphere map, object and eye planes, the texture environments,
lines, points, a texture without an image, which leaves its unit untextured, legacy
texture formats from copies and GL_CLAMP, a cube map through GL_REFLECTION_MAP and
GL_NORMAL_MAP texgen), framed by push and pop."""


SLOW_CRASHES = {
    "four_thousand_legal_calls",
    "twenty_thousand_legal_calls",
    "glsl_preprocessor_bomb",
}
"""Crash files left out of the comparison: they test size and time limits, not what the
context does, and take seconds each."""


def crashes_of(lab: str) -> dict[str, str]:
    """The lab's crash files (:mod:`tests.labs.crashes`), by student name: legal files
    that once broke the checker, which the core context must judge as the native one."""
    return {
        f"crash_{c.name}": c.source()
        for c in CRASHES
        if c.lab == lab and c.name not in SLOW_CRASHES
    }


def mutants_of(lab: str) -> tuple:
    if os.environ.get("MIRRORLAB_ORACLE_ALL") == "1":
        return EVERY[lab]
    chosen = [m for m in EVERY[lab] if m.name in CHOSEN[lab]]
    assert len(chosen) == len(CHOSEN[lab]), "a chosen mutant is gone from mutants.py"
    return tuple(chosen)


def test_the_simulated_context_is_core():
    """The overrides give a context where the legacy calls are gone, so that the tests below
    run the emulation and not Mesa's pipeline."""
    script = (
        "from mirrorlab.gl.context import HeadlessContext, use_platform\n"
        "use_platform('egl')\n"
        "context = HeadlessContext()\n"
        "from mirrorlab.gl.opengl import GL\n"
        "from mirrorlab.labs.trusted import legacy\n"
        "print('compatibility', legacy.has_compatibility())\n"
        "try:\n"
        "    GL.glMatrixMode(GL.GL_MODELVIEW)\n"
        "    print('glMatrixMode ok')\n"
        "except Exception as exc:\n"
        "    print('glMatrixMode raised', type(exc).__name__)\n"
        "context.release()\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env={**os.environ, **MACOS_CONTEXT},
    )
    assert done.returncode == 0, done.stderr
    assert "compatibility False" in done.stdout and "glMatrixMode raised" in done.stdout
    native = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert "compatibility True" in native.stdout and "glMatrixMode ok" in native.stdout


def _student_picture(png: bytes) -> np.ndarray:
    """The student's cell of a grade's picture (student | reference | difference)."""
    picture = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)
    cell = (picture.shape[1] - 8) // 3
    return picture[16 : 16 + cell, :cell]


def _grade(lab, folder, monkeypatch, cache, core: bool):
    with monkeypatch.context() as patch:
        patch.setenv("MIRRORLAB_CACHE", str(cache))
        # the value probe's inputs the same both ways, so that a hint naming an input
        # names the same one
        patch.setenv("MIRRORLAB_PROBE_SEED", "20261207")
        for key, value in MACOS_CONTEXT.items():
            if core:
                patch.setenv(key, value)
            else:
                patch.delenv(key, raising=False)
        grades, _ = grade_folder(
            find_lab(lab), folder, 2, None, "pool", LIMITS, progress=False, solutions=SOLUTIONS
        )
    return {g.student: g for g in grades}


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_core_and_compatibility_grade_alike(lab, tmp_path, monkeypatch):
    spec = find_lab(lab)
    folder = tmp_path / "class"
    written = write_mutants(folder, mutants_of(lab))
    (folder / "solution.py").write_text((SOLUTIONS / f"{spec.folder}.py").read_text())
    (folder / "starter.py").write_text(starter_text(lab))
    crashes = crashes_of(lab)
    for student, source in crashes.items():
        (folder / f"{student}.py").write_text(source)
    if lab == "spheremap":  # GLSL naming compatibility built-ins: translated both ways
        (folder / "builtins.py").write_text(
            (SOLUTIONS / f"{spec.folder}.py")
            .read_text()
            .replace(
                "return u - 2.0 * dot(n, u) * n;",
                "return u - 2.0 * dot(n, u) * n + 0.0 * (gl_ModelViewMatrix * vec4(u, 0.0)).xyz;",
            )
        )
    native = _grade(lab, folder, monkeypatch, tmp_path / "cache-native", core=False)
    core = _grade(lab, folder, monkeypatch, tmp_path / "cache-core", core=True)
    extra = ["builtins"] if lab == "spheremap" else []
    assert (
        sorted(native)
        == sorted(core)
        == sorted([*written, "solution", "starter", *extra, *crashes])
    )
    for student, expected in native.items():
        got = core[student]
        assert got.status == expected.status, (student, got.status, expected.status)
        assert got.tasks == expected.tasks, student
        a, b = _student_picture(expected.picture_png), _student_picture(got.picture_png)
        assert a.shape == b.shape
        difference = np.abs(a - b).max(axis=-1)
        stray = float((difference > PIXEL_TOLERANCE).mean())
        assert stray <= STRAY_PIXELS, (student, stray, int(difference.max()))
    # the done-when lines of the issue, in the core context
    for student in ("solution", "builtins") if lab == "spheremap" else ("solution",):
        assert all(passed for _, passed, _ in core[student].tasks), core[student].tasks
    for task, passed, hint in core["starter"].tasks:
        assert not passed and STARTER[lab][task] in hint, (task, hint)


def test_the_fixed_pipeline_draws_alike_in_both_contexts(tmp_path, monkeypatch):
    """Every way of the fixed pipeline (:data:`FIXED_FUNCTION`), in the quad lab of the
    test folder, which opens every channel the shipped labs close: the same verdicts and
    the same picture within the tolerance, Mesa's pipeline against the emulation."""
    spec = importlib.import_module("tests.labs.fourth_lab").SPEC
    try:
        folder = tmp_path / "class"
        folder.mkdir()
        (folder / "solution.py").write_text(spec.solution.read_text())
        (folder / "fixed_function.py").write_text(
            spec.solution.read_text() + "\n\n" + FIXED_FUNCTION
        )
        native = _grade(spec.name, folder, monkeypatch, tmp_path / "cache-native", core=False)
        core = _grade(spec.name, folder, monkeypatch, tmp_path / "cache-core", core=True)
    finally:
        unregister(spec.name)
    assert sorted(native) == sorted(core) == ["fixed_function", "solution"]
    assert all(passed for _, passed, _ in core["solution"].tasks)
    for student, expected in native.items():
        got = core[student]
        assert got.status == expected.status == "ok", (student, got.status, got.detail)
        assert got.tasks == expected.tasks, student
        a, b = _student_picture(expected.picture_png), _student_picture(got.picture_png)
        difference = np.abs(a - b).max(axis=-1)
        stray = float((difference > PIXEL_TOLERANCE).mean())
        assert stray <= STRAY_PIXELS, (student, stray, int(difference.max()))
    # the fixed-function file drew what it draws (its display() raised nothing, which no
    # task of the quad lab would say)
    drawn = _student_picture(native["fixed_function"].picture_png)
    plain = _student_picture(native["solution"].picture_png)
    assert float((np.abs(drawn - plain).max(axis=-1) > 40).mean()) > 0.1
