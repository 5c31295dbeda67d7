"""The layering rules that can be checked by importing, each in a fresh interpreter."""

import subprocess
import sys

import pytest

GL_PACKAGES = ("OpenGL", "glfw")


def modules_loaded_by(statement: str) -> set[str]:
    code = f"{statement}\nimport sys\nprint(' '.join(sorted(sys.modules)))"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    return set(out.split())


def gl_of(loaded: set[str]) -> set[str]:
    return {m for m in loaded if m.split(".")[0] in GL_PACKAGES}


@pytest.mark.parametrize(
    "module",
    [
        "mirrorlab",
        "mirrorlab.techniques",
        "mirrorlab.plan",
        "mirrorlab.scene.loader",
        "mirrorlab.options",
        "mirrorlab.api",
        "mirrorlab.testing",
        "mirrorlab.cli",
    ],
)
def test_public_modules_load_neither_opengl_nor_glfw(module):
    loaded = modules_loaded_by(f"import {module}")
    assert module in loaded
    assert not gl_of(loaded)


def test_math_scene_and_plan_layers_import_no_opengl_and_no_gl_layer():
    loaded = modules_loaded_by(
        "import mirrorlab.math3d, mirrorlab.envmap, mirrorlab.views, mirrorlab.plan, "
        "mirrorlab.raytrace, mirrorlab.scene.model, mirrorlab.scene.loader, "
        "mirrorlab.scene.animation, mirrorlab.scene.backgrounds, mirrorlab.scene.graph, "
        "mirrorlab.scene.robot, mirrorlab.scene.mesh, mirrorlab.accuracy"
    )
    assert not gl_of(loaded)
    assert not {m for m in loaded if m == "mirrorlab.gl" or m.startswith("mirrorlab.gl.")}
    assert not {m for m in loaded if m.startswith(("mirrorlab.passes", "mirrorlab.renderer"))}


def test_listing_the_techniques_loads_no_pass_module():
    loaded = modules_loaded_by(
        "from mirrorlab.techniques import techniques\nnames = [t.name for t in techniques()]"
    )
    assert not {m for m in loaded if m.startswith("mirrorlab.passes")}
    assert not gl_of(loaded)


def test_gl_modules_choose_egl_before_opengl_loads():
    loaded = modules_loaded_by(
        "import os; os.environ.pop('PYOPENGL_PLATFORM', None)\n"
        "import mirrorlab.passes.ortho\n"
        "assert os.environ['PYOPENGL_PLATFORM'] == 'egl'"
    )
    assert "OpenGL.GL" in loaded
