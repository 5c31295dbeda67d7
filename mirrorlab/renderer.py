"""Runs a frame's plan for the lab scene with one mirror technique. It is handed a
context's resource registry and a render target; it never creates a context or a window."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.resources import RenderTarget, Texture2D
from mirrorlab.passes.camera import CameraPass, viewer_view_projection
from mirrorlab.passes.capture import CaptureMode, CapturePass, EnvironmentCapture
from mirrorlab.passes.reflected import ReflectedCapturePass
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.passes.stencil import StencilReflectionPass
from mirrorlab.plan import CaptureState, PlannedPass, check_method, plan_frame
from mirrorlab.scene.robot import Camera, LabScene


@dataclass
class FrameStats:
    """What the last frame did: passes run and skipped (with reasons), draw calls."""

    passes: list[PlannedPass]
    draw_calls: int

    @property
    def ran(self) -> list[str]:
        return [p.name for p in self.passes if p.runs]


class Renderer:
    """Draws the :class:`LabScene` with one of :data:`~mirrorlab.plan.METHODS`.

    ``capture`` chooses how a capture reaches the ENVIRONMENT texture
    (``"copy"``: glCopyTexImage2D, the lab; ``"fbo"``: drawn straight into
    it). ``environment_size`` (width, height) fixes the texture's size; None
    makes it the frame's size, as in the lab. The texture starts blank (1 x 1).
    """

    def __init__(self, registry: ResourceRegistry, scene: LabScene, method: str = "ortho",
                 capture: CaptureMode = "copy",
                 environment_size: tuple[int, int] | None = None) -> None:
        self.method = check_method(method)
        self.scene = scene
        self.drawer = SceneDrawer(registry, scene)
        self.environment = Texture2D.blank(registry, 1, 1)
        self.capture = EnvironmentCapture(registry, self.environment, capture, environment_size)
        self.capture_pass = CapturePass(scene, self.drawer, self.capture)
        self.reflected_pass = ReflectedCapturePass(scene, self.drawer, self.capture)
        self.camera_pass = CameraPass(registry, scene, self.drawer, self.environment)
        self.stencil_pass = (StencilReflectionPass(registry, scene, self.drawer)
                             if method == "stencil" else None)
        self.captured = CaptureState()
        self.last_frame: FrameStats | None = None

    def render(self, target: RenderTarget, camera: Camera,
               force_capture: bool = False) -> FrameStats:
        """Draw one frame of ``camera``'s view into ``target`` (Framebuffer or window)."""
        size = tuple(target.size)
        plan = plan_frame(self.scene, camera, size, self.captured, force_capture, self.method)
        runs = {p.name for p in plan if p.runs}
        draws = 0
        texture_matrix = None
        if "capture" in runs:
            draws += self.capture_pass.run(target)
            self.captured = CaptureState(self.scene.graph.revision, size)
        if "reflected-capture" in runs:
            draws += self.reflected_pass.run(target, camera)
            self.captured = CaptureState(self.scene.graph.revision, size, camera)
        if self.method == "reflected":
            texture_matrix = self.reflected_pass.texture_matrix
        draws += self.camera_pass.run(target, camera, texture_matrix,
                                      draw_mirror=self.stencil_pass is None)
        if self.stencil_pass is not None:
            view_projection = viewer_view_projection(camera, target)
            draws += self.stencil_pass.draw_backing(view_projection)
            if "stencil-reflection" in runs:
                draws += self.stencil_pass.run(view_projection)
        self.last_frame = FrameStats(plan, draws)
        return self.last_frame

    def release(self) -> None:
        """Free every GL object the renderer made. Call with its context current."""
        if self.stencil_pass is not None:
            self.stencil_pass.release()
        self.camera_pass.release()
        self.capture.release()
        self.drawer.release()
        self.environment.release()

    def read_environment(self) -> np.ndarray:
        """The ENVIRONMENT texture as ``(h, w, 3)`` uint8, row 0 at the top."""
        return self.environment.read()
