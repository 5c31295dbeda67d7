"""Dual-paraboloid maps (Heidrich & Seidel 1998): the two hemispheres of directions in two
squares of one texture (the front, ``rz >= 0``, on the left), looked up by the side and
paraboloid of the reflected ray (``shaders/paraboloid.glsl``; numpy reference
:func:`mirrorlab.envmap.paraboloid_map`). Each square holds its disc inside a margin of
what lies past the rim (:data:`mirrorlab.envmap.PARABOLOID_EXTENT`), so bilinear
filtering and mipmaps at the rim read the directions beyond it, and GL's own mipmaps
serve.

Three ways to make one: ``paraboloid`` bakes the background (or a picture) once, in
numpy; ``paraboloid-live`` converts a live cube capture into both halves after each
capture, as GTA V does with its reflection probe; ``paraboloid-warped`` draws the scene
straight into each half through the vertex-stage paraboloid (a warped view,
:class:`mirrorlab.views.Warp`), which bends only the vertices: a large triangle's inside
is filled along straight lines where the paraboloid would curve it.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab.captures import paraboloid_size
from mirrorlab.envmap import bake_paraboloid, paraboloid_picture_environment
from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, RenderTarget, Texture2D, TextureFramebuffer
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.cube_live import LiveCubeMapped
from mirrorlab.passes.envmap import CurvedPass
from mirrorlab.passes.sky import SCREEN_TRIANGLE
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.backgrounds import environment_of, load_picture
from mirrorlab.scene.model import Background, CurvedReflector


@lru_cache(maxsize=8)
def baked_paraboloid(source: Background | Path, size: int) -> np.ndarray:
    """A dual-paraboloid image ``(size, 2 size, 3)`` uint8 of a background, or of the
    dual-paraboloid picture at ``source`` (remembered: baking is numpy work)."""
    if isinstance(source, Path):
        picture = load_picture(source)
        if picture.shape[1] != 2 * picture.shape[0]:
            raise ValueError(
                f"picture {source} is {picture.shape[1]}x{picture.shape[0]}: a dual-paraboloid "
                f"map's picture must be twice as wide as high (the front's disc on the left)"
            )
        env = paraboloid_picture_environment(picture)
    else:
        env = environment_of(source)
    return bake_paraboloid(env, size)


def blank_map(shared: SharedResources, size: int) -> Texture2D:
    """A mipmapped ``2 size`` x ``size`` texture for a live dual-paraboloid map."""
    return Texture2D(shared.registry, 2 * size, size, None, mipmaps=True, clamp=True)


class ParaboloidMapped(CurvedPass):
    """The ``paraboloid`` technique: a static dual-paraboloid map of the background (or of
    the reflector's ``source``), made once."""

    def __init__(
        self, shared: SharedResources, reflector: CurvedReflector, background: Background
    ) -> None:
        super().__init__(shared, reflector, background)
        source = background if reflector.source is None else reflector.source
        image = baked_paraboloid(source, reflector.map_size)
        self.texture = Texture2D(
            shared.registry,
            image.shape[1],
            image.shape[0],
            image,
            mipmaps=True,
            clamp=True,
            what=f"reflector {reflector.name}'s dual-paraboloid map",
        )

    def release(self) -> None:
        self.texture.release()
        super().release()

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.texture


class LiveParaboloidMapped(LiveCubeMapped):
    """The ``paraboloid-live`` technique: six faces captured as ``cube-live`` captures them
    (at :func:`~mirrorlab.captures.paraboloid_size`, with their depths for a distance
    search), then converted into both halves of the slot's map
    (``resample_paraboloid.frag``) and mipmapped. Its lookups take ``cube-live``'s
    parallax corrections."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        self.size = paraboloid_size(reflector.map_size)  # the cube's faces
        self.side = reflector.map_size
        self.maps: dict[int, tuple[Texture2D, TextureFramebuffer]] = {}
        self.triangle = MeshBuffer(shared.registry, SCREEN_TRIANGLE, np.arange(3, dtype=np.uint32))
        self.convert = shared.program("envmap_sky.vert", "resample_paraboloid.frag")
        self.convert.use()
        self.convert.set_int("cube_map_texture", 0)

    def release(self) -> None:
        for texture, framebuffer in self.maps.values():
            framebuffer.release()
            texture.release()
        self.maps.clear()
        self.triangle.release()
        super().release()

    def paraboloid(self, slot: int) -> tuple[Texture2D, TextureFramebuffer]:
        """The map of ``slot`` and a framebuffer drawing into its level 0."""
        if slot not in self.maps:
            texture = blank_map(self.shared, self.side)
            framebuffer = TextureFramebuffer(self.shared.registry, texture, depth=False)
            self.maps[slot] = (texture, framebuffer)
        return self.maps[slot]

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Capture the cube (:meth:`LiveCubeMapped.update`), then convert it into the two
        halves of the slot's map."""
        draws = super().update(step, reflector, renderer, frame_target)
        texture, framebuffer = self.paraboloid(step.slot)
        gl.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        gl.glDisable(GL.GL_DEPTH_TEST)
        gl.glDisable(GL.GL_CULL_FACE)
        program = self.convert
        program.use()
        program.set_float("side_size", float(self.side))
        self.cube(step.slot).bind(0)
        framebuffer.bind()
        for side in (0, 1):
            gl.glViewport(side * self.side, 0, self.side, self.side)
            program.set_int("side", side)
            self.triangle.draw()
        gl.glEnable(GL.GL_CULL_FACE)
        gl.glEnable(GL.GL_DEPTH_TEST)
        texture.generate_mipmaps()
        return draws + 2

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.paraboloid(draw.slot)[0]


class WarpedParaboloidMapped(CurvedPass):
    """The ``paraboloid-warped`` technique: each hemisphere drawn through the vertex-stage
    paraboloid (its capture camera's two warped views,
    :func:`mirrorlab.captures.paraboloid_views`) into a scratch target and copied into its
    half of the slot's map, then mipmapped. Captured again when something it shows
    changes, not when only the viewer moves."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        self.side = reflector.map_size
        self.maps: dict[int, Texture2D] = {}

    def release(self) -> None:
        for texture in self.maps.values():
            texture.release()
        self.maps.clear()
        super().release()

    def paraboloid(self, slot: int) -> Texture2D:
        if slot not in self.maps:
            self.maps[slot] = blank_map(self.shared, self.side)
        return self.maps[slot]

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Draw both hemispheres (each view's plan leaves this reflector out) and copy each
        into its half."""
        texture = self.paraboloid(step.slot)
        target = self.shared.scratch((self.side, self.side))
        draws = 0
        for side, plan in enumerate(step.views):
            draws += renderer.draw_view(plan, target)
            target.bind()
            texture.copy_square_from_framebuffer(side * self.side, self.side, target.size)
        texture.generate_mipmaps()
        return draws

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.paraboloid(draw.slot)
