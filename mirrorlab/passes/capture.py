"""Pass 1 of the lab: render the scene from the mirror's orthographic camera and copy
the framebuffer into the ENVIRONMENT texture with ``glCopyTexImage2D``."""

from __future__ import annotations

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import RenderTarget, Texture2D
from mirrorlab.passes.scene_draw import SceneDrawer


class CapturePass:
    """Renders the scene without the mirror into ``target``, then copies it to ``environment``.

    ``target`` is a Framebuffer or DefaultFramebuffer; the copy has its full
    size, as the lab copies a window-sized image into a window-sized blank texture.
    """

    name = "capture"

    def __init__(self, drawer: SceneDrawer, environment: Texture2D) -> None:
        self.drawer = drawer
        self.environment = environment

    def run(self, target: RenderTarget) -> int:
        """Returns the number of draw calls."""
        capture = self.drawer.scene.capture
        width, height = target.size
        target.bind()
        GL.glViewport(0, 0, width, height)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glClearColor(*self.drawer.scene.background, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        draws = self.drawer.draw(capture.projection() @ capture.view())
        self.environment.bind(0)
        self.environment.copy_from_framebuffer(width, height)
        return draws
