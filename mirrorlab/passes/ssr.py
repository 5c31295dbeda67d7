"""Screen-space reflections with a probe fallback (technique ``ssr``), for planar mirrors
and curved reflectors alike.

Its texture is the view's own frame (the ``screen`` kind: :mod:`.view_frame`). Drawn
after the view's objects, in four steps:

1. the reflector as its probe draws it (its ``fallback`` draw: any curved technique,
   :func:`mirrorlab.screen_space.probe_reflector`), or in the background's colour with
   no probe; the reflector's pixels keep alpha 0, marking them as its own;
2. the target's colour and depth (the view's objects, the other reflectors drawn so
   far and this one's probe) copied into textures;
3. the copied depth's nearest-depth pyramid (:class:`~mirrorlab.gl.resources.DepthPyramid`,
   ``ssr_pyramid.frag``), then the reflector drawn again into a target of the pass's own,
   each visible fragment marching its reflected ray through the copied depth, passing
   over blocks of samples the pyramid shows the ray in front of (``ssr_march.frag``; the
   numpy reference is :func:`mirrorlab.screen_space.march`): the hit's colour, and its
   weight, reason and pixel (what :meth:`ScreenSpaceReflections.miss_mask` reads back);
4. a rectangle over the reflector's footprint mixes each covered pixel's probe colour
   with its hit's by the hit's weight, and gives alpha back.

In a view seen through a stencil mirror (stencil level above 0) the frame copy holds
other views' pixels too, and a warped view (a paraboloid capture) has no matrix to
project a ray by, so there it draws the probe alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import (
    AttachmentFramebuffer,
    DepthPyramid,
    MeshBuffer,
    RenderTarget,
    Texture2D,
)
from mirrorlab.gl.resources import TextureCube as _TextureCube
from mirrorlab.passes.base import SharedResources, ViewDrawer, apply_view_state, set_clip_plane
from mirrorlab.passes.planar import PlanarPass, mirror_model
from mirrorlab.passes.view_frame import ViewFrame
from mirrorlab.plan import PlannedPass, Rectangle, ReflectorDraw, ViewPlan
from mirrorlab.scene.model import Background, CurvedReflector, PlanarReflector, Reflector
from mirrorlab.screen_space import DEFAULTS, END_FADE, MissMask, probe_reflector
from mirrorlab.techniques import technique
from mirrorlab.views import View, is_orthographic

if TYPE_CHECKING:
    from mirrorlab.renderer import SceneRenderer

COLOR_UNIT = 0
DEPTH_UNIT = 1
HITS_UNIT = 2
PYRAMID_UNIT = 4
"""Texture units of the frame copy's colour and depth, of the march's hit colours (the
composite reads the march's results on units 2 and 3), and of the nearest-depth
pyramid."""
PYRAMID_LEVELS = 8
"""The levels of the nearest-depth pyramid the march climbs (blocks up to 128 pixels a
side); 1 marches the plain DDA, every sample looked at."""
OUTPUT_MARCH = 0
OUTPUT_RAY_ORIGIN = 1
OUTPUT_RAY_DIRECTION = 2
"""What the march writes into its second target: what happened (weight, reason, hit
pixel), or for checks each fragment's eye-space ray origin or unit direction."""
TARGETS_KEPT = 4
"""The march's own targets kept, by view size."""

_ZEROS = np.zeros(4, dtype=np.float32)
_ZEROS.flags.writeable = False  # handed to GL by every recorded frame
_UNIT_SQUARE = np.array(
    [
        (0.0, 0.0, 0.0, 0, 0, 1, 0, 0),
        (1.0, 0.0, 0.0, 0, 0, 1, 1, 0),
        (1.0, 1.0, 0.0, 0, 0, 1, 1, 1),
        (0.0, 1.0, 0.0, 0, 0, 1, 0, 1),
    ],
    dtype=np.float32,
)


class ScreenSpaceReflections:
    """The ``ssr`` technique for one reflector: its probe's pass (made from the probe
    technique's registry entry), the frame copies, its own march targets and programs."""

    def __init__(
        self, shared: SharedResources, reflector: Reflector, background: Background
    ) -> None:
        self.shared = shared
        self.entry = technique(reflector.technique)
        self.background = background
        self.output_mode = OUTPUT_MARCH
        self.planar: PlanarPass | None = None
        if isinstance(reflector, PlanarReflector):
            self.planar = PlanarPass(shared, reflector, background)
        probe = probe_reflector(reflector)
        self.probe = None
        if probe is not None:
            self.probe = technique(probe.technique).load()(shared, probe, background)
            if self.planar is not None:
                self.probe.mesh = self.planar.quad  # the probe's lookup on the glass itself
        self.frame = ViewFrame(shared.registry)
        self.program = shared.program(self.entry.vertex_shader, self.entry.fragment_shader)
        self.program.use()
        self.program.set_int("frame_color", COLOR_UNIT)
        self.program.set_int("frame_depth", DEPTH_UNIT)
        self.composite = shared.program("ssr_composite.vert", "ssr_composite.frag")
        self.composite.use()
        self.composite.set_int("frame_color", COLOR_UNIT)
        self.composite.set_int("hit_colors", HITS_UNIT)
        self.composite.set_int("hit_infos", HITS_UNIT + 1)
        self.downsample = shared.program("ssr_composite.vert", "ssr_pyramid.frag")
        self.pyramids: dict[tuple[int, int], DepthPyramid] = {}
        self.pyramid_levels = PYRAMID_LEVELS
        self.square = MeshBuffer(shared.registry, _UNIT_SQUARE, np.array([0, 1, 2, 0, 2, 3]))
        self.targets: dict[tuple[int, int], AttachmentFramebuffer] = {}
        self.drawn: dict[tuple[int, int], View] = {}
        """The view each size's target was last marched for (its results are that
        view's)."""

    # ------------------------------------------------------------------ the contract

    def update(
        self,
        step: PlannedPass,
        reflector: Reflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """The only textures planned for it are its probe's: make the one ``step`` asks
        for."""
        probe = probe_reflector(reflector)
        if self.probe is None or probe is None:
            raise ValueError(f"reflector {reflector.name!r} has no probe to update")
        return self.probe.update(step, probe, renderer, frame_target)

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | _TextureCube | None:
        """What its probe's draw sampled (the frame copy is the view itself)."""
        if draw.fallback is None or self.probe is None:
            return None
        return self.probe.shown_texture(draw.fallback)

    def release(self) -> None:
        for target in (*self.targets.values(), *self.pyramids.values()):
            target.release()
        self.targets.clear()
        self.pyramids.clear()
        self.drawn.clear()
        self.frame.release()
        self.square.release()
        if self.probe is not None:
            self.probe.release()
        if self.planar is not None:
            self.planar.release()

    def draw(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        reflector = draw.reflector
        if self.planar is not None:
            assert isinstance(reflector, PlanarReflector)
            self.planar.place(reflector)
            if draw.mode != "screen":
                return self.planar.draw(draw, view, renderer, target, stencil_level)
        elif draw.mode == "plain":
            assert isinstance(reflector, CurvedReflector)
            return renderer.drawer.draw_plain(renderer.scene, reflector, view)
        # the march projects rays by the view's matrix: no march through a stencil mirror
        # (other views' pixels in the frame) or in a warped view (no matrix projects it)
        marching = stencil_level == 0 and view.warp is None
        draws = self.draw_probe(draw, view, renderer, target, stencil_level, marking=marching)
        if marching:
            draws += self.march(draw, view, target)
        apply_view_state(view, stencil_level)
        return draws

    # ------------------------------------------------------------------ its steps

    def draw_probe(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
        marking: bool,
    ) -> int:
        """Step 1: the reflector as its probe draws it (or in the background's colour),
        its pixels' alpha 0 when ``marking``."""
        if marking:  # colour as drawn, alpha 0: the reflector's own pixels
            gl.glEnable(GL.GL_BLEND)
            gl.glBlendFuncSeparate(GL.GL_ONE, GL.GL_ZERO, GL.GL_ZERO, GL.GL_ZERO)
        try:
            if draw.fallback is not None and self.probe is not None:
                return self.probe.draw(draw.fallback, view, renderer, target, stencil_level)
            return self.draw_flat(draw.reflector, view, self.background.color)
        finally:
            if marking:
                gl.glBlendFunc(GL.GL_ONE, GL.GL_ZERO)
                gl.glDisable(GL.GL_BLEND)

    def draw_flat(self, reflector: Reflector, view: View, color) -> int:
        """The reflector's front in one unlit colour (no probe: the background's)."""
        program = self.shared.program("flat.vert", "flat.frag", view.warp)
        program.use()
        program.set_mat4("view_projection", view.uniforms[0])
        set_clip_plane(program, view)
        program.set_mat4("model", view.relative(self.model(reflector)).astype(np.float32))
        program.set_vec3("color", color)
        program.set_int("far_depth", False)
        gl.glEnable(GL.GL_CULL_FACE)
        self.mesh(reflector).draw()
        return 1

    def model(self, reflector: Reflector) -> np.ndarray:
        if isinstance(reflector, PlanarReflector):
            return mirror_model(reflector)
        return reflector.model_matrix()

    def mesh(self, reflector: Reflector) -> MeshBuffer:
        if self.planar is not None:
            return self.planar.quad
        assert isinstance(reflector, CurvedReflector)
        return self.shared.mesh(reflector.mesh)

    def target(self, size: tuple[int, int]) -> AttachmentFramebuffer:
        held = self.targets.get(size)
        if held is None:
            while len(self.targets) >= TARGETS_KEPT:
                oldest = next(iter(self.targets))
                self.targets.pop(oldest).release()
                self.drawn.pop(oldest, None)
            held = self.targets[size] = AttachmentFramebuffer(
                self.shared.registry, *size, (GL.GL_RGBA8, GL.GL_RGBA32F)
            )
        return held

    def pyramid(self, size: tuple[int, int]) -> DepthPyramid:
        held = self.pyramids.get(size)
        if held is None:
            while len(self.pyramids) >= TARGETS_KEPT:
                self.pyramids.pop(next(iter(self.pyramids))).release()
            held = self.pyramids[size] = DepthPyramid(self.shared.registry, *size)
        return held

    def build_pyramid(self, size: tuple[int, int], levels: int) -> DepthPyramid:
        """The frame copy's depth (bound on :data:`DEPTH_UNIT`) and its nearest depths, up
        to ``levels`` levels; each level drawn from the one below (which alone is then
        readable: no level is read and drawn at once)."""
        pyramid = self.pyramid(size)
        program = self.downsample
        program.use()
        program.set_vec4("rect", (-1.0, -1.0, 1.0, 1.0))
        gl.glActiveTexture(GL.GL_TEXTURE0 + PYRAMID_UNIT)
        gl.glBindTexture(GL.GL_TEXTURE_2D, pyramid.texture)
        for level in range(min(levels, pyramid.levels)):
            gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, pyramid.framebuffers[level])
            gl.glViewport(0, 0, *pyramid.sizes[level])
            program.set_int("level", level)
            if level == 0:
                program.set_int("source", DEPTH_UNIT)
            else:
                program.set_int("source", PYRAMID_UNIT)
                program.set_ivec2("below", pyramid.sizes[level - 1])
                gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_BASE_LEVEL, level - 1)
                gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, level - 1)
            self.square.draw()
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_BASE_LEVEL, 0)
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, pyramid.levels - 1)
        gl.glViewport(0, 0, *size)
        return pyramid

    def march(self, draw: ReflectorDraw, view: View, target: RenderTarget) -> int:
        """Steps 2 to 4: copy the frame (and its depth's pyramid), march into the pass's
        own target, mix."""
        reflector = draw.reflector
        settings = reflector.ssr or DEFAULTS
        size = view.size
        drawn = (0, 0, *size)  # a view with a screen draw is drawn whole (its plan)
        # made first: making them binds their textures (on the active unit) and framebuffers
        own, pyramid, frame = self.target(size), self.pyramid(size), self.frame.textures(size)
        target.bind()
        frame.copy(None)
        frame.bind(COLOR_UNIT, DEPTH_UNIT)
        gl.glDisable(GL.GL_CULL_FACE)
        gl.glDisable(GL.GL_DEPTH_TEST)
        gl.glDepthMask(GL.GL_FALSE)
        levels = max(1, min(self.pyramid_levels, pyramid.levels))
        self.build_pyramid(size, levels)
        own.bind()
        gl.glClearBufferfv(GL.GL_COLOR, 0, _ZEROS)
        gl.glClearBufferfv(GL.GL_COLOR, 1, _ZEROS)
        gl.glEnable(GL.GL_CULL_FACE)  # (no depth test: the shader tests the copied depth)
        program = self.program
        program.use()
        program.set_int("frame_color", COLOR_UNIT)
        program.set_int("frame_depth", DEPTH_UNIT)
        program.set_int("pyramid", PYRAMID_UNIT)
        program.set_int("top_level", levels - 1)
        model = self.model(reflector)
        program.set_mat4("model", view.relative(model))
        program.set_mat4("view", view.relative_view)
        program.set_mat4("projection", view.projection)
        program.set_mat3("normal_matrix", _normal_matrix(model))
        set_clip_plane(program, view)
        if program.has_uniform("texgen"):  # the per-vertex sphere map is not read
            program.set_int("texgen", False)
        program.set_int("orthographic", is_orthographic(view.projection))
        rows = _depth_rows(view.projection)
        program.set_vec4("depth_row_z", rows[0])
        program.set_vec4("depth_row_w", rows[1])
        program.set_vec2("viewport", size)
        x, y, w, h = drawn
        program.set_vec4("screen", (x, y, x + w, y + h))
        program.set_float("stride", settings.stride)
        program.set_int("steps", settings.steps)
        program.set_float("thickness", settings.thickness)
        program.set_float("max_distance", settings.max_distance)
        program.set_int("refine", settings.refine)
        program.set_float("edge_fade", settings.edge_fade)
        program.set_float("end_fade", END_FADE)
        program.set_int("output_mode", self.output_mode)
        self.mesh(reflector).draw()
        self.drawn[size] = view

        target.bind()
        gl.glDisable(GL.GL_CULL_FACE)
        composite = self.composite
        composite.use()
        composite.set_vec4("rect", _ndc_rect(_covered(draw, drawn), size))
        own.bind_texture(0, HITS_UNIT)
        own.bind_texture(1, HITS_UNIT + 1)
        gl.glActiveTexture(GL.GL_TEXTURE0 + COLOR_UNIT)
        self.square.draw()
        gl.glEnable(GL.GL_CULL_FACE)
        gl.glDepthMask(GL.GL_TRUE)
        gl.glEnable(GL.GL_DEPTH_TEST)
        return 2

    # ------------------------------------------------------------------ for readers

    def miss_mask(self, view: View) -> MissMask | None:
        """What the march did at each pixel of ``view`` when this reflector was last drawn
        there (None: it was not marched in a view of that size since, or last in
        another view). Call with the context current, after the frame."""
        own = self.targets.get(view.size)
        if own is None or self.drawn.get(view.size) is not view:
            return None
        info = own.read_float(1)
        return MissMask(
            reason=np.rint(info[..., 1]).astype(np.uint8),
            weight=info[..., 0].astype(np.float32),
            pixel=info[..., 2:4].astype(np.float32),
        )

    def fallback_mask(self, draw: ReflectorDraw, view: View) -> np.ndarray | None:
        """``(h, w)`` bool, row 0 at the top: the pixels of ``view`` where this reflector
        showed its probe alone, no screen colour at all (what :attr:`MissMask.miss_share`
        counts); the :class:`~mirrorlab.passes.base.ReportsFallback` the accuracy sweep
        reads. ``draw`` is this pass's own reflector's."""
        mask = self.miss_mask(view)
        return None if mask is None else mask.reflector & (mask.weight <= 0.0)

    def read_rays(self, view: View) -> np.ndarray | None:
        """``(h, w, 4)`` float32: what the march's second target holds for ``view`` (its
        rays' origins or directions with :attr:`output_mode` set for checks)."""
        own = self.targets.get(view.size)
        if own is None or self.drawn.get(view.size) is not view:
            return None
        return own.read_float(1)

    def frame_copy(self, size: tuple[int, int]):
        """The frame copy of views of ``size`` (for checks)."""
        return self.frame.textures(size)


def _normal_matrix(model: np.ndarray) -> np.ndarray:
    from mirrorlab import math3d

    return math3d.normal_matrix(model)


def _depth_rows(projection: np.ndarray) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """Rows 2 and 3 of the inverse of ``projection`` (float64): a window pixel's normalised
    device coordinates to its eye-space z and w."""
    inverse = np.linalg.inv(np.asarray(projection, dtype=np.float64))
    return tuple(float(v) for v in inverse[2]), tuple(float(v) for v in inverse[3])


def _covered(draw: ReflectorDraw, drawn: Rectangle) -> Rectangle:
    """The pixels the reflector may cover: its footprint's rectangle within the drawn
    part of the view."""
    footprint = draw.footprint
    bounds = None if footprint is None else footprint.bounds
    if bounds is None:
        return drawn
    x0, y0 = max(bounds[0], drawn[0]), max(bounds[1], drawn[1])
    x1 = min(bounds[0] + bounds[2], drawn[0] + drawn[2])
    y1 = min(bounds[1] + bounds[3], drawn[1] + drawn[3])
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)


def _ndc_rect(rectangle: Rectangle, size: tuple[int, int]) -> tuple[float, float, float, float]:
    x, y, w, h = rectangle
    width, height = size
    return (
        2.0 * x / width - 1.0,
        2.0 * y / height - 1.0,
        2.0 * (x + w) / width - 1.0,
        2.0 * (y + h) / height - 1.0,
    )


def frame_mask(renderer: SceneRenderer, plan: ViewPlan) -> MissMask:
    """What screen-space reflections did at each pixel of ``plan``'s view, as ``renderer``
    drew it last (the camera's view of its last frame): every reflector drawn by this
    technique there (one drawn later, in front, over one before it); zero elsewhere.
    Call with the renderer's context current."""
    width, height = plan.view.size
    reason = np.zeros((height, width), dtype=np.uint8)
    weight = np.zeros((height, width), dtype=np.float32)
    pixel = np.zeros((height, width, 2), dtype=np.float32)
    for draw in plan.shown:
        drawn = renderer.drawn_pass(draw) if draw.mode == "screen" else None
        mask = drawn.miss_mask(plan.view) if isinstance(drawn, ScreenSpaceReflections) else None
        if mask is None:
            continue
        mine = mask.reason != 0
        reason[mine], weight[mine], pixel[mine] = (
            mask.reason[mine],
            mask.weight[mine],
            mask.pixel[mine],
        )
    return MissMask(reason, weight, pixel)
