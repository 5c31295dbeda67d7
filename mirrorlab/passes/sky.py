"""The distant background drawn behind everything, from a cube map of it."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from mirrorlab.envmap import bake_cube_faces
from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program, TextureCube
from mirrorlab.passes.base import SharedResources, cube_from_folder
from mirrorlab.scene.backgrounds import environment_of, load_cube_faces
from mirrorlab.scene.model import Background
from mirrorlab.views import View, Warp

SKY_SIZE = 256
"""Edge of the cube map a baked background is drawn from."""

SCREEN_TRIANGLE = np.array(
    [
        (-1.0, -1.0, 0.0, 0, 0, 1, 0, 0),
        (3.0, -1.0, 0.0, 0, 0, 1, 0, 0),
        (-1.0, 3.0, 0.0, 0, 0, 1, 0, 0),
    ],
    dtype=np.float32,
)
"""One triangle covering the whole target (as :class:`~mirrorlab.gl.resources.MeshBuffer`
vertices: NDC x, y; ``envmap_sky.vert`` draws it), for passes that fill a target."""


@lru_cache(maxsize=8)
def background_faces(background: Background, size: int = SKY_SIZE) -> np.ndarray:
    """Six cube faces ``(6, n, n, 3)`` uint8 of a background: its own pictures, or baked
    from it at ``size`` (a plain colour at 1 x 1). Remembered: do not change the array."""
    if not background.is_environment:
        size = 1
    if background.kind == "cube_faces":
        assert background.path is not None
        return load_cube_faces(background.path)
    return bake_cube_faces(environment_of(background), size)


def background_cube(shared: SharedResources, background: Background) -> TextureCube:
    """The background as a cube map: a folder of pictures read face by face (its GL
    storage made from the first picture's header, so a size the GL cannot hold is refused
    before any picture is decoded), anything else baked (:func:`background_faces`)."""
    if background.kind == "cube_faces":
        assert background.path is not None
        return cube_from_folder(shared.registry, background.path)
    return TextureCube.from_faces(
        shared.registry, background_faces(background), what="the background's cube map face"
    )


def ray_directions(view: View) -> np.ndarray:
    """``(3, 3)``: (ndc x, ndc y, 1) to the world direction of the view ray through that
    point. Only the projection's x, y and w rows enter, so an oblique near plane (which
    changes only the z row) does not disturb it. A warped view's is its eye-to-world
    rotation: its warp's shader gives the eye direction (warp.glsl)."""
    projection = np.asarray(view.projection, dtype=np.float64)
    rotation = np.asarray(view.view, dtype=np.float64)[:3, :3]
    if view.warp is not None:
        return rotation.T
    if view.orthographic:
        to_eye = np.zeros((3, 3))
        to_eye[2, 2] = -1.0
    else:  # eye direction d = (dx, dy, -1): w = 1, and rows x, y give dx, dy
        a = projection[:2, :2]
        inverse = np.linalg.inv(a)
        to_eye = np.zeros((3, 3))
        to_eye[:2, :2] = inverse
        to_eye[:2, 2] = inverse @ projection[:2, 2]
        to_eye[2, 2] = -1.0
    return rotation.T @ to_eye


class SkyPass:
    """Fills the view with the background seen in each pixel's direction, without touching
    depth: draw it first, then the scene over it."""

    def __init__(self, shared: SharedResources, background: Background) -> None:
        self.background = background
        self.cube = background_cube(shared, background)
        self.shared = shared
        self.triangle = MeshBuffer(shared.registry, SCREEN_TRIANGLE, np.arange(3, dtype=np.uint32))
        self.program(None)

    def program(self, warp: Warp | None) -> Program:
        """The background's program for views of ``warp``, bound."""
        program = self.shared.program("envmap_sky.vert", "envmap_sky.frag", warp)
        program.use()
        program.set_int("sky_texture", 0)  # set once: a program skips an unchanged value
        return program

    def release(self) -> None:
        """Free the cube map and the triangle (the program is shared)."""
        self.cube.release()
        self.triangle.release()

    def run(self, view: View) -> int:
        """Draw into the bound target; returns the number of draw calls (1)."""
        gl.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        gl.glDisable(GL.GL_DEPTH_TEST)
        gl.glDepthMask(GL.GL_FALSE)
        gl.glDisable(GL.GL_CULL_FACE)
        self.program(view.warp).set_mat3("ndc_to_direction", ray_directions(view))
        self.cube.bind(0)
        self.triangle.draw()
        gl.glEnable(GL.GL_CULL_FACE)
        gl.glDepthMask(GL.GL_TRUE)
        gl.glEnable(GL.GL_DEPTH_TEST)
        return 1
