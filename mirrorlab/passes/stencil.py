"""The stencil mirror: the mirrored world drawn straight into the view, masked by the
stencil buffer to the visible part of the glass, with no texture in between. Mirrors in
mirrors nest: each level marks its glass one stencil value higher and gives it back
when done, so the reference value belongs to the mirror being drawn, not a constant."""

from __future__ import annotations

from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.base import ViewDrawer, apply_view_state
from mirrorlab.passes.planar import PlanarPass
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.model import PlanarReflector
from mirrorlab.views import View


class StencilMirror(PlanarPass):
    """The ``stencil`` technique, drawn after the objects of its view (its registry entry's
    ``draws_after_objects``), its world's plan nested in the draw (its capture camera,
    :func:`mirrorlab.captures.stencil_camera`); its target needs a stencil buffer
    (mirrorlab's have 8 bits):

    1. where the stencil holds this view's level k, the glass's visible front raises it
       to k + 1 (no colour, no depth);
    2. there, colour is reset to the background and depth to the far plane;
    3. the mirrored world (its own plan, one bounce less) is drawn where the stencil is
       k + 1, front faces turned clockwise and clipped by the mirror's plane;
    4. the glass's depth is put back and the stencil lowered to k again;
    5. its back face shows the backing.
    """

    def update(
        self,
        step: PlannedPass,
        reflector: PlanarReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        raise ValueError("a stencil mirror has no texture to update")

    def draw_own(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        assert draw.nested is not None
        inner = stencil_level + 1
        background = renderer.scene.background.color
        gl.glEnable(GL.GL_STENCIL_TEST)
        gl.glStencilMask(0xFF)
        gl.glStencilFunc(GL.GL_EQUAL, stencil_level, 0xFF)
        gl.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_INCR)
        gl.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)
        gl.glDepthMask(GL.GL_FALSE)
        gl.glEnable(GL.GL_CULL_FACE)
        self.flat_quad(view, background, far_depth=False)

        gl.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
        gl.glDepthMask(GL.GL_TRUE)
        gl.glStencilFunc(GL.GL_EQUAL, inner, 0xFF)
        gl.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_KEEP)
        gl.glDepthFunc(GL.GL_ALWAYS)
        self.flat_quad(view, background, far_depth=True)
        gl.glDepthFunc(GL.GL_LESS)

        draws = renderer.draw_view(draw.nested, target, inner)

        apply_view_state(view, stencil_level)
        gl.glEnable(GL.GL_STENCIL_TEST)
        gl.glStencilFunc(GL.GL_EQUAL, inner, 0xFF)
        gl.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_DECR)
        gl.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)
        gl.glDepthFunc(GL.GL_ALWAYS)
        self.flat_quad(view, background, far_depth=False)
        gl.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
        gl.glDepthFunc(GL.GL_LESS)
        apply_view_state(view, stencil_level)
        return draws + 3 + self.draw_backing(view)
