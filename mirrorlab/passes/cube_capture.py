"""Live cube map: six 90-degree captures of the scene from the reflector's centre, one per
face, each copied into the cube map with ``glCopyTexImage2D`` (the lab's capture, six times)."""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import RenderTarget, TextureCube
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.passes.sky import SkyPass

FACE_VIEWS = (
    # (look direction, up) per face in GL order +X, -X, +Y, -Y, +Z, -Z: with these, the
    # window's x and y run along the face's s and t as the cube-map spec's table has them
    # (+X: s along -z, t along -y; ...), so a copy of the window is the face as it is.
    ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    ((0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
    ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0)),
)


def face_view(center: np.ndarray, face: int) -> np.ndarray:
    """World-to-eye ``(4, 4)`` of the capture camera for cube ``face`` (0..5) at ``center``."""
    direction, up = FACE_VIEWS[face]
    center = np.asarray(center, dtype=np.float64)
    return math3d.look_at(center, center + np.asarray(direction), up)


def face_projection(near: float, far: float) -> np.ndarray:
    """The square 90-degree perspective ``(4, 4)`` every face is captured with."""
    return math3d.perspective(90.0, 1.0, near, far)


class CubeCapturePass:
    """Renders the sky and the scene (never the reflector) six times from ``center`` into
    ``target`` (a square Framebuffer the cube's size) and copies each into a face of
    ``cube``, then rebuilds its mipmaps if it has them."""

    name = "cube-capture"

    def __init__(self, drawer: SceneDrawer, sky: SkyPass, cube: TextureCube,
                 near: float = 0.05, far: float = 200.0) -> None:
        self.drawer = drawer
        self.sky = sky
        self.cube = cube
        self.near, self.far = near, far

    def run(self, target: RenderTarget, center: np.ndarray) -> int:
        """Capture all six faces; returns the number of draw calls."""
        width, height = target.size
        if (width, height) != (self.cube.size, self.cube.size):
            raise ValueError(f"capture target must be {self.cube.size}x{self.cube.size}, "
                             f"got {width}x{height}")
        projection = face_projection(self.near, self.far)
        target.bind()
        GL.glViewport(0, 0, width, height)
        draws = 0
        for face in range(6):
            view = face_view(center, face)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
            draws += self.sky.run(view, projection)
            GL.glEnable(GL.GL_DEPTH_TEST)
            GL.glEnable(GL.GL_CULL_FACE)
            draws += self.drawer.draw(projection @ view)
            target.bind()
            self.cube.copy_face_from_framebuffer(face)
        if self.cube.mipmaps:
            self.cube.generate_mipmaps()
        return draws
