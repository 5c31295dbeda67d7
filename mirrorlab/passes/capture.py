"""Pass 1 of the lab: render the scene from the mirror's orthographic camera into the
ENVIRONMENT texture; plus :class:`EnvironmentCapture`, the two ways any capture pass
gets its image into that texture."""

from __future__ import annotations

from typing import Literal

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer, RenderTarget, Texture2D, TextureFramebuffer
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.plan import CAPTURE_MODES
from mirrorlab.scene.robot import LabScene

CaptureMode = Literal["copy", "fbo"]  # the names in mirrorlab.plan.CAPTURE_MODES


class EnvironmentCapture:
    """Where a capture pass draws, and how the picture reaches ``environment``.

    - ``"copy"`` (the lab): draw into a colour framebuffer, then
      ``glCopyTexImage2D`` it into the texture.
    - ``"fbo"``: draw straight into the texture, attached to a framebuffer.

    ``size`` (width, height) fixes the texture's size; None makes it follow
    the frame (the lab's window-sized capture), and in copy mode the capture
    then borrows the frame's own framebuffer, as the lab does. Scratch
    framebuffers are made on first use and re-made when the size changes.
    """

    def __init__(self, registry: ResourceRegistry, environment: Texture2D,
                 mode: CaptureMode = "copy", size: tuple[int, int] | None = None) -> None:
        if mode not in CAPTURE_MODES:
            raise ValueError(f"capture mode must be one of {', '.join(CAPTURE_MODES)}, "
                             f"got {mode!r}")
        self.registry = registry
        self.environment = environment
        self.mode = mode
        self.size = None if size is None else (int(size[0]), int(size[1]))
        self._scratch: Framebuffer | TextureFramebuffer | None = None

    def begin(self, frame_target: RenderTarget) -> RenderTarget:
        """The target to draw the capture into, bound and with its viewport set (the
        caller clears it)."""
        width, height = self.size or tuple(frame_target.size)
        if self.mode == "copy" and self.size is None:
            target: RenderTarget = frame_target
        else:
            target = self._scratch_target(width, height)
        target.bind()
        GL.glViewport(0, 0, width, height)
        return target

    def finish(self, target: RenderTarget) -> None:
        """Bring what was drawn into ``environment`` (a copy, or nothing for an FBO)."""
        if self.mode == "copy":
            width, height = target.size
            self.environment.bind(0)
            self.environment.copy_from_framebuffer(width, height)

    def _scratch_target(self, width: int, height: int) -> RenderTarget:
        scratch = self._scratch
        if scratch is not None and scratch.size == (width, height):
            return scratch
        if scratch is not None:
            scratch.release()
        if self.mode == "copy":
            self._scratch = Framebuffer(self.registry, width, height)
        else:
            self.environment.allocate(width, height)
            self._scratch = TextureFramebuffer(self.registry, self.environment)
        return self._scratch

    def release(self) -> None:
        """Free the scratch framebuffer (not the environment texture)."""
        if self._scratch is not None:
            self._scratch.release()
            self._scratch = None


def clear_to_background(background) -> None:
    """Enable depth testing and back-face culling, then clear colour (to ``background``
    RGB), depth and stencil of the bound target."""
    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glEnable(GL.GL_CULL_FACE)
    GL.glClearColor(*background, 1.0)
    GL.glClearStencil(0)
    GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT | GL.GL_STENCIL_BUFFER_BIT)


class CapturePass:
    """The lab's capture: the scene without the mirror, seen by the orthographic camera
    that sits on the mirror, into the ENVIRONMENT texture.

    The mirror quad's fixed texture coordinates pair with this image.
    """

    name = "capture"

    def __init__(self, scene: LabScene, drawer: SceneDrawer,
                 capture: EnvironmentCapture) -> None:
        self.scene = scene
        self.drawer = drawer
        self.capture = capture

    def run(self, frame_target: RenderTarget) -> int:
        """Returns the number of draw calls."""
        scene = self.scene
        target = self.capture.begin(frame_target)
        clear_to_background(scene.background)
        view_projection = scene.capture.projection() @ scene.capture.view()
        draws = self.drawer.draw(view_projection)
        self.capture.finish(target)
        return draws
