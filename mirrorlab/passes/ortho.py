"""The lab's mirror: the scene seen by an orthographic camera sitting on the mirror and
looking out along its normal, copied into the ENVIRONMENT texture (pass 1), then the
quad drawn with that texture at its own texture coordinates (pass 2)."""

from __future__ import annotations

from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.planar import CaptureTextures, PlanarPass
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.model import Background, PlanarReflector
from mirrorlab.views import View


class OrthoMirror(PlanarPass):
    """The ``ortho`` technique. Its capture does not depend on the viewer: the planner
    reuses it until the scene changes."""

    def __init__(self, shared: SharedResources, reflector: PlanarReflector,
                 background: Background | None = None) -> None:
        super().__init__(shared, reflector, background)
        self.captures = CaptureTextures(shared, reflector.capture)

    def release(self) -> None:
        self.captures.release()
        super().release()

    def update(self, step: PlannedPass, reflector: PlanarReflector, renderer: ViewDrawer,
               frame_target: RenderTarget) -> int:
        (plan,) = step.views
        return self.captures.capture(step.slot, plan, renderer, frame_target)

    def draw_own(self, draw: ReflectorDraw, view: View, renderer: ViewDrawer,
                 target: RenderTarget, stencil_level: int) -> int:
        return self.draw_textured(view, self.captures.texture(draw.slot), None)
