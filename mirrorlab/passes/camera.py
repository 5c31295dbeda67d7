"""Pass 2 of the lab: render the scene from the viewer, then the mirror quad textured
with the ENVIRONMENT capture."""

from __future__ import annotations

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program, RenderTarget, Texture2D
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.scene.robot import Camera, Mirror

MIRROR_BACKING = (0.33, 0.3, 0.27)


def mirror_vertices(mirror: Mirror) -> tuple[np.ndarray, np.ndarray]:
    """The mirror quad as ``(4, 8)`` interleaved vertices and ``(2, 3)`` triangle indices."""
    normals = np.broadcast_to(mirror.normal, (4, 3))
    vertices = np.hstack([mirror.corners, normals, mirror.texcoords]).astype(np.float32)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


class CameraPass:
    """Clears ``target``, draws the scene from ``camera``, then the mirror (both faces)."""

    name = "camera"

    def __init__(self, registry: ResourceRegistry, drawer: SceneDrawer,
                 environment: Texture2D) -> None:
        self.drawer = drawer
        self.environment = environment
        self.program = Program(registry, "mirror.vert", "mirror.frag")
        self.quad = MeshBuffer(registry, *mirror_vertices(drawer.scene.mirror))
        self.program.use()
        self.program.set_int("environment", 0)
        self.program.set_vec3("backing_color", MIRROR_BACKING)

    def release(self) -> None:
        """Free the mirror's program and quad (not the shared drawer or texture)."""
        self.program.release()
        self.quad.release()

    def run(self, target: RenderTarget, camera: Camera) -> int:
        """Returns the number of draw calls."""
        width, height = target.size
        target.bind()
        GL.glViewport(0, 0, width, height)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glClearColor(*self.drawer.scene.background, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        view_projection = camera.projection(width / height) @ camera.view()
        GL.glEnable(GL.GL_CULL_FACE)
        draws = self.drawer.draw(view_projection)
        GL.glDisable(GL.GL_CULL_FACE)  # the mirror's back face shows its backing
        self.program.use()
        self.program.set_mat4("view_projection", view_projection)
        self.environment.bind(0)
        self.quad.draw()
        return draws + 1
