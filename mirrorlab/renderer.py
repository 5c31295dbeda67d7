"""The lab's two-pass renderer. It is handed a context's resource registry and a render
target; it never creates a context or a window."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.resources import RenderTarget, Texture2D
from mirrorlab.passes.camera import CameraPass
from mirrorlab.passes.capture import CapturePass
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.plan import CaptureState, PlannedPass, plan_frame
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
    """Runs the capture pass (when planned) and the camera pass for a :class:`LabScene`.

    The ENVIRONMENT texture starts blank (1 x 1) and takes the target's size
    at the first capture.
    """

    def __init__(self, registry: ResourceRegistry, scene: LabScene) -> None:
        self.scene = scene
        self.drawer = SceneDrawer(registry, scene)
        self.environment = Texture2D.blank(registry, 1, 1)
        self.capture_pass = CapturePass(self.drawer, self.environment)
        self.camera_pass = CameraPass(registry, self.drawer, self.environment)
        self.captured = CaptureState()
        self.last_frame: FrameStats | None = None

    def render(self, target: RenderTarget, camera: Camera,
               force_capture: bool = False) -> FrameStats:
        """Draw one frame of ``camera``'s view into ``target`` (Framebuffer or window)."""
        size = tuple(target.size)
        plan = plan_frame(self.scene, camera, size, self.captured, force_capture)
        draws = 0
        for planned in plan:
            if not planned.runs:
                continue
            if planned.name == "capture":
                draws += self.capture_pass.run(target)
                self.captured = CaptureState(self.scene.graph.revision, size)
            else:
                draws += self.camera_pass.run(target, camera)
        self.last_frame = FrameStats(plan, draws)
        return self.last_frame

    def release(self) -> None:
        """Free every GL object the renderer made. Call with its context current."""
        self.camera_pass.release()
        self.drawer.release()
        self.environment.release()

    def read_environment(self) -> np.ndarray:
        """The ENVIRONMENT texture as ``(h, w, 3)`` uint8, row 0 at the top."""
        return self.environment.read()
