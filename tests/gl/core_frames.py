"""Run as ``python -m tests.gl.core_frames OUT.npz`` in a process whose environment makes
Mesa simulate macOS's OpenGL (:data:`MACOS_CONTEXT`): compiles every shader the renderer
ships on its own, draws the first two frames of every golden sequence
(:mod:`tests.gl.golden_frames`: every shipped scene, every technique) with a renderer of
the context's own draw path, and each technique for either kind of reflector on every
shipped scene with a reflector (:func:`either_kind_frames`), and saves them to OUT.npz
with what the context is (its version, whether it is a core profile, the draw path
taken). Test helper of
``tests/gl/test_core_profile.py``."""

from __future__ import annotations

import os
import sys
from typing import Any

from tests import MACOS_CONTEXT

FRAMES = 2
"""Frames of each sequence drawn (the second reuses the first's captures)."""


def renderer_shaders() -> list[str]:
    """The renderer's own shader files (``*.vert``, ``*.frag``): all but the labs'
    ``kit_*``."""
    from importlib.resources import files

    return sorted(
        entry.name
        for entry in files("mirrorlab.shaders").iterdir()
        if entry.name.endswith((".vert", ".frag")) and not entry.name.startswith("kit_")
    )


DEFINES = {"LIGHT_COUNT": (0, 3), "PARALLAX": (0, 1, 2, 3)}
"""The values of the ``#define`` s the renderer's programs are built with, each tried."""


def compile_errors() -> dict[str, str]:
    """Each renderer shader (with each value of a define it reads) that does not compile
    in the current context: its log."""
    from mirrorlab.gl.opengl import GL
    from mirrorlab.gl.resources import expand_includes

    errors = {}
    for name in renderer_shaders():
        kind = GL.GL_VERTEX_SHADER if name.endswith(".vert") else GL.GL_FRAGMENT_SHADER
        version, _, body = expand_includes(name).partition("\n")
        variants = [("", "")] + [
            (f"{key}={value}", f"#define {key} {value}\n")
            for key, values in DEFINES.items()
            if key in body
            for value in values
        ]
        for label, header in variants[1:] or variants:
            shader = GL.glCreateShader(kind)
            GL.glShaderSource(shader, f"{version}\n{header}{body}")
            GL.glCompileShader(shader)
            if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
                errors[f"{name} {label}".strip()] = (
                    GL.glGetShaderInfoLog(shader).decode(errors="replace").strip()
                )
            GL.glDeleteShader(shader)
    return errors


def main(out: str) -> None:
    import json

    import numpy as np

    from mirrorlab.gl.context import HeadlessContext, gl_version
    from mirrorlab.gl.opengl import GL
    from mirrorlab.renderer import SceneRenderer
    from tests.gl.frames import draw
    from tests.gl.golden_frames import draw_sequence, sequences

    with HeadlessContext(debug=True) as context:
        mask = int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK))
        flags = int(GL.glGetIntegerv(GL.GL_CONTEXT_FLAGS))
        frames: dict[str, Any] = {}  # name: (h, w, 3) uint8 frames side by side
        renderer = SceneRenderer(context.resources)
        info = {
            "version": list(gl_version()),
            "core": bool(mask & GL.GL_CONTEXT_CORE_PROFILE_BIT),
            "forward_compatible": bool(flags & GL.GL_CONTEXT_FLAG_FORWARD_COMPATIBLE_BIT),
            "draw_path": renderer.drawer.draw_path,
            "compile_errors": compile_errors(),
        }
        renderer.release()
        for sequence in sequences():
            short = type(sequence)(sequence.name, sequence.frames[:FRAMES])
            renderer = SceneRenderer(context.resources)
            try:
                frames[sequence.name] = draw_sequence(renderer, short)
            finally:
                renderer.release()
        renderer = SceneRenderer(context.resources)
        try:
            for name, scene in either_kind_frames():
                frames[name] = draw(renderer, scene, EITHER_SIZE)[0]
        finally:
            renderer.release()
    np.savez_compressed(out, info=np.array(json.dumps(info)), **frames)


EITHER_SIZE = (64, 64)
"""The size of :func:`either_kind_frames`' frames."""


def either_kind_frames():
    """``(name, scene)``: each technique that serves both kinds of reflector on every
    shipped scene with a reflector (``--method`` giving it to every reflector), one frame
    each (the golden sequences show each curved technique on one scene only)."""
    import mirrorlab
    from mirrorlab.data import scenes_dir
    from mirrorlab.options import apply_options
    from mirrorlab.techniques import techniques

    either = [t.name for t in techniques() if t.kind == "both"]
    for path in sorted(scenes_dir().glob("*.toml")):
        scene = mirrorlab.load_scene(path.stem)
        if not scene.reflectors:
            continue
        for method in either:
            yield f"{method}:{path.stem}", apply_options(scene, {"method": method})


if __name__ == "__main__":
    if any(os.environ.get(key) != value for key, value in MACOS_CONTEXT.items()):
        sys.exit("run with tests.gl.core_frames.MACOS_CONTEXT in the environment")
    main(sys.argv[1])
