"""Run as ``python -m tests.gl.maps_frames OUT.npz``: every shipped scene that has a curved
reflector, drawn with each of the octahedral and dual-paraboloid maps by one renderer in
turn (a frame each, its maps made for it), saved to OUT.npz, with whether the context was
a core profile. In the environment of :data:`tests.MACOS_CONTEXT` it
draws them as macOS's OpenGL 4.1 core context would; ``tests/gl/test_direction_maps.py``
compares them with the default context's. Test helper."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from typing import Any

import numpy as np

METHODS = ("octahedral", "octahedral-live", "paraboloid", "paraboloid-live", "paraboloid-warped")
SIZE = (64, 64)
MAP_SIZE = 32


def configured() -> Iterator[tuple[str, object]]:
    """``(label, scene)``: each shipped scene with a curved reflector, each map."""
    import mirrorlab
    from mirrorlab.data import scenes_dir
    from mirrorlab.options import apply_options

    for path in sorted(scenes_dir().glob("*.toml")):
        name = path.stem
        scene = mirrorlab.load_scene(name)
        if any(r.kind == "curved" for r in scene.reflectors):
            for method in METHODS:
                options = {"method": method, "map_size": MAP_SIZE}
                yield f"{name}__{method}", apply_options(scene, options)


def draw_all(registry) -> dict[str, Any]:
    """Every configuration's frame ``(h, w, 3)`` uint8, by label, drawn in order by one
    renderer on the context of ``registry``."""
    from mirrorlab.renderer import SceneRenderer
    from tests.gl.frames import draw

    renderer = SceneRenderer(registry)
    try:
        return {label: draw(renderer, scene, SIZE)[0] for label, scene in configured()}
    finally:
        renderer.release()


def main(out: str) -> None:
    from mirrorlab.gl.context import HeadlessContext
    from mirrorlab.gl.opengl import GL

    with HeadlessContext(debug=True) as context:
        core = bool(int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK)) & 1)
        frames = draw_all(context.resources)
    np.savez_compressed(out, core=np.array(core), **frames)


if __name__ == "__main__":
    main(sys.argv[1])
