"""Pass 2 of the lab: render the scene from the viewer, then the mirror quad textured
with the ENVIRONMENT capture."""

from __future__ import annotations

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program, RenderTarget, Texture2D
from mirrorlab.passes.capture import clear_to_background
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.scene.robot import Camera, LabScene, Mirror


def mirror_vertices(mirror: Mirror) -> tuple[np.ndarray, np.ndarray]:
    """The mirror quad as ``(4, 8)`` interleaved vertices and ``(2, 3)`` triangle indices."""
    normals = np.broadcast_to(mirror.normal, (4, 3))
    vertices = np.hstack([mirror.corners, normals, mirror.texcoords]).astype(np.float32)
    return vertices, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def viewer_view_projection(camera: Camera, target: RenderTarget) -> np.ndarray:
    """``(4, 4)`` projection @ view of ``camera`` for ``target``'s aspect ratio."""
    width, height = target.size
    return camera.projection(width / height) @ camera.view()


class CameraPass:
    """Clears ``target``, draws the scene from ``camera``, then the mirror (both faces)
    textured with ``environment``.

    ``texture_matrix`` ``(4, 4)`` maps world points on the mirror to
    homogeneous environment coordinates (a reflected capture); None keeps the
    quad's own texture coordinates (the lab's orthographic capture). With
    ``draw_mirror=False`` only the scene is drawn, for a pass that reflects
    by other means.
    """

    name = "camera"

    def __init__(self, registry: ResourceRegistry, scene: LabScene, drawer: SceneDrawer,
                 environment: Texture2D) -> None:
        self.scene = scene
        self.drawer = drawer
        self.environment = environment
        self.program = Program(registry, "mirror.vert", "mirror.frag")
        self.quad = MeshBuffer(registry, *mirror_vertices(scene.mirror))
        self.program.use()
        self.program.set_int("environment", 0)
        self.program.set_vec3("backing_color", scene.mirror_backing)

    def release(self) -> None:
        """Free the mirror's program and quad (not the shared drawer or texture)."""
        self.program.release()
        self.quad.release()

    def run(self, target: RenderTarget, camera: Camera,
            texture_matrix: np.ndarray | None = None, draw_mirror: bool = True) -> int:
        """Returns the number of draw calls."""
        width, height = target.size
        target.bind()
        GL.glViewport(0, 0, width, height)
        clear_to_background(self.scene.background)
        view_projection = viewer_view_projection(camera, target)
        draws = self.drawer.draw(view_projection)
        if not draw_mirror:
            return draws
        GL.glDisable(GL.GL_CULL_FACE)  # the mirror's back face shows its backing
        self.program.use()
        self.program.set_mat4("view_projection", view_projection)
        self.program.set_int("projective", texture_matrix is not None)
        if texture_matrix is not None:
            self.program.set_mat4("texture_matrix", texture_matrix)
        self.environment.bind(0)
        self.quad.draw()
        GL.glEnable(GL.GL_CULL_FACE)
        return draws + 1
