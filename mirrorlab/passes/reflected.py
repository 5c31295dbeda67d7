"""The reflected-camera mirror: the scene seen by the viewer's mirror image (eye, target
and up reflected in the mirror's plane, near plane on the glass), captured into a
texture, then sampled on the mirror through that camera (projective coordinates), so
each point of the glass shows what the viewer sees there."""

from __future__ import annotations

from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.planar import CaptureTextures, PlanarPass
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.model import Background, PlanarReflector
from mirrorlab.views import View


class ReflectedMirror(PlanarPass):
    """The ``reflected`` technique: one capture per viewer (see
    :func:`mirrorlab.views.reflected_capture_view`)."""

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
        assert draw.source is not None
        return self.draw_textured(view, self.captures.texture(draw.slot),
                                  draw.source.texture_matrix())
