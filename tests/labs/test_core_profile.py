"""The labs in macOS's OpenGL 4.1 core context, simulated with Mesa's overrides: there the
trusted side carries out the legacy calls itself (labs/trusted/legacy.py) and translates
the compatibility built-ins of GLSL (labs/trusted/compat_glsl.py). Mesa's own
compatibility pipeline is the oracle: each lab's reference solution, untouched starter and
mutants are graded both ways, and each way must give the same verdict and hint for every
task, and the same picture within :data:`PIXEL_TOLERANCE` (docs/labs-teachers.md states
it). Each way makes its own reference from the teacher's solution, as a student's machine
would."""

from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from mirrorlab.labs import LABS
from mirrorlab.labs.trusted.grading import grade_folder
from tests.labs.classroom import STARTER, starter_text
from tests.labs.conftest import LIMITS, SOLUTIONS
from tests.labs.mutants import (
    CUBE_EQUIVALENT,
    CUBEMAP,
    EQUIVALENT,
    LAB20,
    LAB20_MORE,
    SPHEREMAP,
    write_mutants,
)

CORE = {
    "MESA_GL_VERSION_OVERRIDE": "4.1FC", "MESA_GLSL_VERSION_OVERRIDE": "410",
    "MESA_EXTENSION_OVERRIDE": " ".join(f"-GL_{name}" for name in (
        "ARB_shader_draw_parameters", "ARB_multi_draw_indirect", "ARB_base_instance",
        "ARB_shading_language_420pack", "ARB_shader_storage_buffer_object",
        "ARB_compute_shader", "ARB_buffer_storage", "ARB_clear_texture", "ARB_copy_image",
        "ARB_texture_view", "MESA_pack_invert")),
}
"""macOS's context as DESIGN.md simulates it: with 4.1FC every Mesa context is 4.1 core."""
PIXEL_TOLERANCE = 2
"""The most a channel of the student's picture may differ (of 255) between the two ways,
but on :data:`STRAY_PIXELS` of the pixels. Measured on every solution, starter and mutant
of the three labs (63 files): at most 1, on at most 0.011% of the pixels."""
STRAY_PIXELS = 0.0005
"""The judges' own share of pixels a frame may differ on (0.05%)."""

CHOSEN = {
    "lab20": ("wrong_corner", "mirror_in_capture", "legacy_gl_clamp", "triangle_fan",
              "two_triangles", "vector_calls", "no_projection_mode", "camera_wrong_side"),
    "spheremap": ("texgen_object_linear", "texgen_left_on", "texgen_only_s",
                  "texgen_reflection_map", "texgen_unit_1", "reflect_sign"),
    "cubemap": ("no_projection_mode", "up_wrong", "fov_60", "mipmaps_before_faces",
                "other_near_far"),
}
"""The mutants graded both ways: where the core context's emulation differs most from
Mesa's pipeline (a quad's diagonal under texture coordinates no plane holds, a vertex on
the near plane, GL_CLAMP, the other primitives, texgen's modes, units and switches, the
matrix modes and GLU), a quarter of the time of all of them. ``MIRRORLAB_ORACLE_ALL=1``
grades every mutant (7 minutes here, against under 2)."""
EVERY = {"lab20": (*LAB20, *EQUIVALENT, *LAB20_MORE), "spheremap": SPHEREMAP,
         "cubemap": (*CUBEMAP, *CUBE_EQUIVALENT)}


def mutants_of(lab: str) -> tuple:
    if os.environ.get("MIRRORLAB_ORACLE_ALL") == "1":
        return EVERY[lab]
    chosen = [m for m in EVERY[lab] if m.name in CHOSEN[lab]]
    assert len(chosen) == len(CHOSEN[lab]), "a chosen mutant is gone from mutants.py"
    return tuple(chosen)


def test_the_simulated_context_is_core():
    """The overrides give a context where the legacy calls are gone, so that the tests below
    run the emulation and not Mesa's pipeline."""
    script = ("from mirrorlab.gl.context import HeadlessContext, use_platform\n"
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
              "context.release()\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env={**os.environ, **CORE})
    assert done.returncode == 0, done.stderr
    assert "compatibility False" in done.stdout and "glMatrixMode raised" in done.stdout
    native = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert "compatibility True" in native.stdout and "glMatrixMode ok" in native.stdout


def _student_picture(png: bytes) -> np.ndarray:
    """The student's cell of a grade's picture (student | reference | difference)."""
    picture = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.int16)
    cell = (picture.shape[1] - 8) // 3
    return picture[16:16 + cell, :cell]


def _grade(lab, folder, monkeypatch, cache, core: bool):
    with monkeypatch.context() as patch:
        patch.setenv("MIRRORLAB_CACHE", str(cache))
        for key, value in CORE.items():
            if core:
                patch.setenv(key, value)
            else:
                patch.delenv(key, raising=False)
        grades, _ = grade_folder(LABS[lab], folder, 2, None, "pool", LIMITS, progress=False,
                                 solutions=SOLUTIONS)
    return {g.student: g for g in grades}


@pytest.mark.parametrize("lab", sorted(LABS))
def test_core_and_compatibility_grade_alike(lab, tmp_path, monkeypatch):
    spec = LABS[lab]
    folder = tmp_path / "class"
    written = write_mutants(folder, mutants_of(lab))
    (folder / "solution.py").write_text((SOLUTIONS / f"{spec.folder}.py").read_text())
    (folder / "starter.py").write_text(starter_text(lab))
    if lab == "spheremap":  # GLSL naming compatibility built-ins: translated both ways
        (folder / "builtins.py").write_text((SOLUTIONS / f"{spec.folder}.py").read_text()
                                            .replace("return u - 2.0 * dot(n, u) * n;",
                                                     "return u - 2.0 * dot(n, u) * n + 0.0 * "
                                                     "(gl_ModelViewMatrix * vec4(u, 0.0)).xyz;"))
    native = _grade(lab, folder, monkeypatch, tmp_path / "cache-native", core=False)
    core = _grade(lab, folder, monkeypatch, tmp_path / "cache-core", core=True)
    extra = ["builtins"] if lab == "spheremap" else []
    assert sorted(native) == sorted(core) == sorted([*written, "solution", "starter", *extra])
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
    for student in ("solution", *extra):
        assert all(passed for _, passed, _ in core[student].tasks), core[student].tasks
    for task, passed, hint in core["starter"].tasks:
        assert not passed and STARTER[lab][task] in hint, (task, hint)
