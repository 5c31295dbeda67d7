"""The renderer in macOS's OpenGL: a forward-compatible 4.1 core context, simulated on
Mesa (DESIGN.md, "Stage 4"), in a child process (PyOpenGL and Mesa read the overrides
once, when a context is made). Every shipped scene and every technique draws there the
frames it draws in the default context (llvmpipe's 4.5 compatibility context), exactly;
every shader the renderer ships compiles there; and the renderer's Python makes no
fixed-function or client-state call."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mirrorlab.data import scenes_dir
from mirrorlab.testing import difference_image
from tests import MACOS_CONTEXT
from tests.gl.core_frames import EITHER_SIZE, FRAMES, either_kind_frames
from tests.gl.frames import draw
from tests.gl.golden_frames import draw_sequence, sequences
from tests.imagecheck import save_failure

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def core_frames(tmp_path_factory):
    """What the child drawing in the simulated macOS context saved: ``(info, frames)``."""
    out = tmp_path_factory.mktemp("core") / "frames.npz"
    env = {**os.environ, **MACOS_CONTEXT}
    result = subprocess.run(
        [sys.executable, "-m", "tests.gl.core_frames", str(out)],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    with np.load(out) as saved:
        info = json.loads(str(saved["info"]))
        frames = {name: saved[name] for name in saved.files if name != "info"}
    return info, frames


def test_the_child_context_is_macos_like(core_frames):
    info, _ = core_frames
    assert info["version"] == [4, 1] and info["core"] and info["forward_compatible"], info
    assert info["draw_path"] == "per-draw"  # no multi-draw indirect, no base instance


def test_every_renderer_shader_compiles_in_the_core_context(core_frames):
    info, _ = core_frames
    assert info["compile_errors"] == {}


SEQUENCES = list(sequences())


@pytest.mark.parametrize("sequence", SEQUENCES, ids=[s.name for s in SEQUENCES])
def test_frames_in_the_core_context_equal_the_default_contexts(
    core_frames, scene_renderer, sequence
):
    _, frames = core_frames
    short = type(sequence)(sequence.name, sequence.frames[:FRAMES])
    default = draw_sequence(scene_renderer, short)
    core = frames[sequence.name]
    if not np.array_equal(core, default):
        folder = save_failure(
            f"core_{sequence.name}",
            core=core,
            default=default,
            diff=difference_image(core, default),
        )
        pytest.fail(
            f"{sequence.name}: {int((core != default).any(axis=-1).sum())} pixels "
            f"differ between the core and the default context; images in {folder}"
        )


EITHER = list(either_kind_frames())


@pytest.mark.parametrize("name,scene", EITHER, ids=[name for name, _ in EITHER])
def test_a_technique_for_either_kind_draws_every_shipped_scene_alike_in_both_contexts(
    core_frames, scene_renderer, name, scene
):
    """A technique that serves planar and curved reflectors (screen-space reflections)
    on every shipped scene that has a reflector: the same frame in both contexts, exactly
    (tolerance 0: the same Mesa compiles the same shaders)."""
    _, frames = core_frames
    default, stats = draw(scene_renderer, scene, EITHER_SIZE)
    assert any(d.own for d in stats.plan.top.draws) or not any(
        d.mode != "hidden" for d in stats.plan.top.draws
    )
    core = frames[name]
    if not np.array_equal(core, default):
        folder = save_failure(
            f"core_{name.replace(':', '_')}",
            core=core,
            default=default,
            diff=difference_image(core, default),
        )
        pytest.fail(f"{name}: {int((core != default).any(axis=-1).sum())} pixels differ; {folder}")


def test_every_shipped_scene_is_drawn_in_the_core_context(core_frames):
    _, frames = core_frames
    shipped = {path.stem for path in scenes_dir().glob("*.toml")}
    assert "spheremap_cone" in shipped and shipped <= set(frames)


LEGACY = re.compile(
    r"\b(glEnableClientState|glDisableClientState|glVertexPointer|glNormalPointer|"
    r"glTexCoordPointer|glColorPointer|glTexGen\w*|glTexEnv\w*|glMatrixMode|glLoadMatrix\w*|"
    r"glLoadIdentity|glPushMatrix|glPopMatrix|glMultMatrix\w*|glOrtho|glFrustum|glBegin|"
    r"glEnd|glVertex[234]\w*|glNormal3\w*|glTexCoord[1234]\w*|glColor[34]\w*|glClipPlane|"
    r"glRenderMode|glFeedbackBuffer|glLight\w*|glMaterial\w*|glShadeModel|GL_TEXTURE_GEN_\w+|"
    r"GL_SPHERE_MAP|GL_NORMALIZE|GL_LIGHTING|GL_QUADS|gl_ModelViewMatrix\w*|"
    r"gl_ModelViewProjectionMatrix\w*|gl_ProjectionMatrix\w*|gl_NormalMatrix|gl_Vertex|"
    r"gl_Normal|gl_MultiTexCoord\d|gl_TexCoord|gl_FrontColor|gl_Color|gl_FragColor|"
    r"texture2D|textureCube|compatibility)\b"
)


def test_the_renderer_names_nothing_outside_the_core_profile():
    """No fixed-function, client-state or compatibility name in the renderer's Python
    and shaders (the labs' kit and trusted side, which carry out the students' legacy
    calls, are not the renderer)."""
    package = REPO / "mirrorlab"
    found = []
    for path in sorted(package.rglob("*")):
        relative = path.relative_to(package)
        if relative.parts[0] == "labs" or path.name.startswith("kit_"):
            continue
        if path.suffix not in (".py", ".vert", ".frag", ".glsl"):
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0] if path.suffix == ".py" else line.split("//", 1)[0]
            if path.suffix == ".py":  # names in strings and docstrings are prose
                code = re.sub(r"(\"[^\"]*\"|'[^']*')", "", code)
                if not re.search(r"\bGL\.|\bRAW\.", code):
                    continue
            for match in LEGACY.finditer(code):
                found.append(f"{relative}:{number}: {match.group(0)}")
    assert not found, "\n".join(found)
