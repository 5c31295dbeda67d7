"""The lab's mirror: the scene seen by an orthographic camera sitting on the mirror and
looking out along its normal, copied into the ENVIRONMENT texture (pass 1), then the
quad drawn with that texture at its own texture coordinates (pass 2)."""

from __future__ import annotations

from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.base import ViewDrawer
from mirrorlab.passes.planar import CapturingMirror
from mirrorlab.plan import ReflectorDraw
from mirrorlab.views import View


class OrthoMirror(CapturingMirror):
    """The ``ortho`` technique. Its capture does not depend on the viewer: the planner
    reuses it until the scene changes."""

    def draw_own(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        return self.draw_textured(view, self.captures.texture(draw.slot), None)
