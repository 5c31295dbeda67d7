"""What the planar techniques share: the mirror's quad (textured front, unlit backing,
plain surface, stencil mask) and the slot textures a capture is copied or drawn into."""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import (
    MeshBuffer,
    Program,
    RenderTarget,
    Texture2D,
    TextureFramebuffer,
)
from mirrorlab.passes.base import SharedResources, ViewDrawer, set_view_uniforms
from mirrorlab.plan import PlannedPass, Rectangle, ReflectorDraw, ViewPlan, bounding
from mirrorlab.scene.model import Background, PlanarReflector
from mirrorlab.views import View, projective_lookup


def mirror_vertices(reflector: PlanarReflector) -> tuple[np.ndarray, np.ndarray]:
    """The quad as ``(4, 8)`` interleaved vertices, positions relative to the mirror's
    centre (placed by :func:`mirror_model`; float32 then keeps their precision anywhere),
    its ortho-capture texture coordinates at the corners, and ``(2, 3)`` triangle
    indices."""
    normals = np.broadcast_to(reflector.normal, (4, 3))
    vertices = np.hstack(
        [reflector.corner_array - reflector.center, normals, reflector.texcoords()]
    )
    return vertices.astype(np.float32), np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)


def mirror_model(reflector: PlanarReflector) -> np.ndarray:
    """``(4, 4)``: the quad of :func:`mirror_vertices` to world (a move to the centre)."""
    return math3d.translate(reflector.center)


QUAD_MODELS_KEPT = 4
"""Views whose quad model a planar pass keeps (a frame draws a mirror in a view or two)."""


class PlanarPass:
    """The parts of a planar technique that do not depend on the technique: drawing the
    mirror plain, its back alone, or its front with a texture. The mirror may move
    between frames (its pass is kept): each draw places the quad where the reflector it
    is given is, updating the quad's four vertices when its shape or place changed."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: PlanarReflector,
        background: Background | None = None,
    ) -> None:
        self.shared = shared
        self.reflector = reflector
        self.quad = MeshBuffer(shared.registry, *mirror_vertices(reflector))
        self._quad_of = reflector
        self._placed: list[tuple[View, PlanarReflector, np.ndarray]] = []
        """The quad's origin-relative model in the last few views (:meth:`quad_model`)."""
        self.mirror_program(None)  # made now: its texture unit set once

    def release(self) -> None:
        self.quad.release()

    def mirror_program(self, view: View | None) -> Program:
        """The textured mirror's program for ``view`` (its warp's, when warped)."""
        program = self.shared.program(
            "mirror.vert", "mirror.frag", None if view is None else view.warp
        )
        program.use()
        program.set_int("environment", 0)  # set once: a program skips an unchanged value
        return program

    def place(self, reflector: PlanarReflector) -> None:
        """Make the quad ``reflector``'s (its corners and texture coordinates)."""
        self.reflector = reflector
        if (reflector.corners, reflector.ortho) != (self._quad_of.corners, self._quad_of.ortho):
            self.quad.update_vertices(mirror_vertices(reflector)[0])
            self._quad_of = reflector

    def quad_model(self, view: View) -> np.ndarray:
        """``(4, 4)`` float32: the quad's model relative to ``view``'s origin
        (:meth:`View.relative` of :func:`mirror_model`, composed in float64), kept for the
        last few views while the mirror stays."""
        reflector = self.reflector
        for held_view, held_reflector, model in self._placed:
            if held_view is view and held_reflector is reflector:
                return model
        model = math3d.read_only(view.relative(mirror_model(reflector)).astype(np.float32))
        self._placed = [(view, reflector, model), *self._placed[: QUAD_MODELS_KEPT - 1]]
        return model

    def flat_quad(self, view: View, color, far_depth: bool) -> None:
        """The quad in one flat colour (``far_depth``: at the far plane's depth)."""
        program = self.shared.program("flat.vert", "flat.frag", view.warp)
        program.use()
        set_view_uniforms(program, view)
        program.set_mat4("model", self.quad_model(view))
        program.set_vec3("color", color)
        program.set_int("far_depth", far_depth)
        self.quad.draw()

    def draw_backing(self, view: View) -> int:
        """The mirror's back face in its unlit backing colour; returns the draw count."""
        gl.glEnable(GL.GL_CULL_FACE)
        gl.glCullFace(GL.GL_FRONT)
        self.flat_quad(view, self.reflector.backing, far_depth=False)
        gl.glCullFace(GL.GL_BACK)
        return 1

    def draw_textured(self, view: View, texture: Texture2D, source: View | None) -> int:
        """Front textured (by the quad's own coordinates, or projectively: where the
        capture view ``source`` saw each point, :func:`~mirrorlab.views.projective_lookup`),
        back in its backing colour; returns 1."""
        gl.glDisable(GL.GL_CULL_FACE)
        program = self.mirror_program(view)
        set_view_uniforms(program, view)
        program.set_mat4("model", self.quad_model(view))
        program.set_vec3("backing_color", self.reflector.backing)
        program.set_int("projective", source is not None)
        if source is not None:
            program.set_mat4("texture_matrix", projective_lookup(source, view))
        texture.bind(0)
        self.quad.draw()
        gl.glEnable(GL.GL_CULL_FACE)
        return 1

    def draw(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        """The modes every planar technique shares: ``plain`` and ``back``."""
        assert isinstance(draw.reflector, PlanarReflector)
        self.place(draw.reflector)
        if draw.mode == "back":
            return self.draw_backing(view)
        if draw.mode == "plain":
            return renderer.drawer.draw_plain(
                renderer.scene, draw.reflector, view, self.quad, mirror_model(self.reflector)
            ) + self.draw_backing(view)
        return self.draw_own(draw, view, renderer, target, stencil_level)

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | None:
        """None: a planar pass samples no texture but its capture's
        (:class:`CapturingMirror`)."""
        return None

    def draw_own(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:  # pragma: no cover
        raise NotImplementedError


class CapturingMirror(PlanarPass):
    """A planar technique that captures the scene into slot textures (``ortho``,
    ``reflected``): one capture camera, its picture copied or drawn into the slot."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: PlanarReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        self.captures = CaptureTextures(shared, reflector.capture)

    def release(self) -> None:
        self.captures.release()
        super().release()

    def update(
        self,
        step: PlannedPass,
        reflector: PlanarReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        (plan,) = step.views
        return self.captures.capture(step.slot, plan, renderer, frame_target)

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | None:
        """The capture a ``texture`` draw samples (None for any other draw)."""
        return self.captures.texture(draw.slot) if draw.mode == "texture" else None


class CaptureTextures:
    """The slot textures of a planar capture (blank, level 0 only, GL_LINEAR, clamped:
    the lab's ENVIRONMENT texture) and how a capture reaches them: ``copy`` draws into a
    colour framebuffer and ``glCopyTexImage2D``-s it (the frame's own when the sizes
    match, as the lab does), ``fbo`` draws straight into the texture."""

    def __init__(self, shared: SharedResources, mode: str) -> None:
        self.shared = shared
        self.mode = mode
        self.textures: dict[int, Texture2D] = {}
        self._framebuffers: dict[int, TextureFramebuffer] = {}
        self._copied: dict[int, Rectangle | None] = {}
        """Each slot's last ``copy``: the pixel rectangle outside which what it copied was
        the cleared background (None: anything may lie anywhere)."""

    def texture(self, slot: int) -> Texture2D:
        if slot not in self.textures:
            self.textures[slot] = Texture2D.blank(self.shared.registry, 1, 1)
        return self.textures[slot]

    def capture(
        self, slot: int, plan: ViewPlan, renderer: ViewDrawer, frame_target: RenderTarget
    ) -> int:
        """Draw ``plan`` into slot ``slot``'s texture; returns the number of draw calls."""
        size = plan.view.size
        texture = self.texture(slot)
        if self.mode == "copy":
            # The frame's own target when it has the capture's size (as the lab does),
            # else a framebuffer of exactly that size: the copy never reads outside what
            # was drawn, whatever size the window has.
            target: RenderTarget = (
                frame_target if tuple(frame_target.size) == size else self.shared.scratch(size)
            )
            # A scissored capture draws only within plan.scissor: once the texture has
            # the capture's size, it is as a whole copy would leave it when the rectangle
            # holding this scissor and the last one is cleared, drawn and copied (outside
            # both, both copies hold the background). Nothing outside that rectangle is
            # read, so nothing outside it is cleared.
            region = (
                bounding(self._copied[slot], plan.scissor)
                if slot in self._copied and (texture.width, texture.height) == size
                else None
            )
            draws = renderer.draw_view(plan, target, cleared=region)
            target.bind()
            self._copied.pop(slot, None)  # a failed copy leaves the texture unknown
            texture.copy_from_framebuffer(
                *size, source=(target.size[0], target.size[1]), region=region
            )
            self._copied[slot] = plan.scissor  # (not reached when the copy failed)
            return draws
        framebuffer = self._framebuffers.get(slot)
        if framebuffer is None or framebuffer.size != size:
            if framebuffer is not None:
                framebuffer.release()
            texture.allocate(*size)
            framebuffer = self._framebuffers[slot] = TextureFramebuffer(
                self.shared.registry, texture
            )
        return renderer.draw_view(plan, framebuffer)

    def release(self) -> None:
        for resource in (*self._framebuffers.values(), *self.textures.values()):
            resource.release()
        self._framebuffers.clear()
        self.textures.clear()
        self._copied.clear()
