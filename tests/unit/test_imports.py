"""The layering rules that can be checked by importing."""

import subprocess
import sys


def modules_loaded_by(statement: str) -> set[str]:
    code = f"{statement}\nimport sys\nprint(' '.join(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    return set(out.split())


def test_importing_mirrorlab_loads_neither_opengl_nor_glfw():
    loaded = modules_loaded_by("import mirrorlab, mirrorlab.cli")
    assert not {m for m in loaded if m.split(".")[0] in ("OpenGL", "glfw")}


def test_math_scene_and_plan_import_no_opengl():
    loaded = modules_loaded_by(
        "import mirrorlab.math3d, mirrorlab.scene.graph, mirrorlab.scene.robot, "
        "mirrorlab.scene.mesh, mirrorlab.plan")
    assert not {m for m in loaded if m.split(".")[0] in ("OpenGL", "glfw")}


def test_gl_modules_choose_egl_before_opengl_loads():
    loaded = modules_loaded_by(
        "import os; os.environ.pop('PYOPENGL_PLATFORM', None)\n"
        "import mirrorlab.passes.capture\n"
        "assert os.environ['PYOPENGL_PLATFORM'] == 'egl'")
    assert "OpenGL.GL" in loaded
