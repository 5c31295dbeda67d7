"""The reflected-camera mirror: the scene seen by the viewer's mirror image (eye, target
and up reflected in the mirror's plane, near plane on the glass), captured into a
texture, then sampled on the mirror through that camera (projective coordinates), so
each point of the glass shows what the viewer sees there."""

from __future__ import annotations

from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.base import ViewDrawer
from mirrorlab.passes.planar import CapturingMirror
from mirrorlab.plan import ReflectorDraw
from mirrorlab.views import View


class ReflectedMirror(CapturingMirror):
    """The ``reflected`` technique: one capture per viewer (see
    :func:`mirrorlab.views.reflected_capture_view`)."""

    def draw_own(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        assert draw.source is not None
        return self.draw_textured(view, self.captures.texture(draw.slot), draw.source)
