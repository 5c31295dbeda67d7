"""The distant environment drawn behind an environment-mapping scene, from a cube map."""

from __future__ import annotations

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program, TextureCube

_SCREEN_TRIANGLE = np.array(
    [(-1.0, -1.0, 0.0, 0, 0, 1, 0, 0), (3.0, -1.0, 0.0, 0, 0, 1, 0, 0),
     (-1.0, 3.0, 0.0, 0, 0, 1, 0, 0)], dtype=np.float32)


def rotation_only(view: np.ndarray) -> np.ndarray:
    """``view`` ``(4, 4)`` with its translation dropped: directions, not points."""
    rotation = np.eye(4)
    rotation[:3, :3] = np.asarray(view, dtype=np.float64)[:3, :3]
    return rotation


class SkyPass:
    """Fills the bound target with the environment seen in each pixel's direction, without
    touching depth: draw it first, then the scene over it. ``sky`` is a cube map of the
    environment (the renderer's static one)."""

    name = "sky"

    def __init__(self, registry: ResourceRegistry, sky: TextureCube) -> None:
        self.sky = sky
        self.program = Program(registry, "envmap_sky.vert", "envmap_sky.frag")
        self.triangle = MeshBuffer(registry, _SCREEN_TRIANGLE, np.arange(3, dtype=np.uint32))
        self.program.use()
        self.program.set_int("sky_texture", 0)

    def release(self) -> None:
        """Free the program and the triangle (not the shared cube map)."""
        self.program.release()
        self.triangle.release()

    def run(self, view: np.ndarray, projection: np.ndarray) -> int:
        """Draw into the bound target with ``view`` and ``projection`` ``(4, 4)``; returns the
        number of draw calls (1)."""
        inverse = np.linalg.inv(projection @ rotation_only(view))
        GL.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDepthMask(GL.GL_FALSE)
        self.program.use()
        self.program.set_mat4("inverse_rotation_projection", inverse)
        self.sky.bind(0)
        self.triangle.draw()
        GL.glDepthMask(GL.GL_TRUE)
        GL.glEnable(GL.GL_DEPTH_TEST)
        return 1
