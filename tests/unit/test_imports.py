"""The layering rules that can be checked by importing, each in a fresh interpreter."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import mirrorlab

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


COMMAND_LINE_MODULES = ("argparse", "mirrorlab.cli", "mirrorlab.commands")
"""What knows a command line: the argument parser and mirrorlab's own command modules."""


def imported_names(path: Path) -> set[str]:
    """Every module ``path`` imports, at its top or inside a function (absolute names)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module is not None:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def test_nothing_below_the_command_line_knows_one():
    package = Path(mirrorlab.__file__).parent
    above = {package / "cli.py", package / "__main__.py", *(package / "commands").rglob("*.py")}
    offenders = {
        str(path.relative_to(package)): sorted(
            name
            for name in imported_names(path)
            if any(name == m or name.startswith(m + ".") for m in COMMAND_LINE_MODULES)
        )
        for path in sorted(package.rglob("*.py"))
        if path not in above
    }
    assert {path: names for path, names in offenders.items() if names} == {}
