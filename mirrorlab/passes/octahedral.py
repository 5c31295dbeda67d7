"""Octahedral maps (Engelhardt & Dachsbacher 2008; Cigolle et al., JCGT 2014): the whole
sphere of directions in one square texture, looked up by the octahedral encoding of the
reflected ray (``shaders/octahedral.glsl``; numpy reference
:func:`mirrorlab.envmap.octahedral_map`).

Every mip level carries a one-texel border that holds what lies across the square's
edges (:func:`mirrorlab.envmap.octahedral_wrap`), so bilinear filtering crosses the folds
without a seam; since a level's border is a texel of that level, the levels are the
map's own, not GL's filtering of level 0, and the shader picks and blends two levels
itself. ``octahedral`` is baked once, in numpy, from the background or a picture;
``octahedral-live`` resamples a live cube capture (:mod:`.cube_live`, parallax
corrections and all) into every level, as EEVEE and DDGI store their probes.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab.envmap import bake_octahedral, octahedral_level_sizes, octahedral_picture_environment
from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import (
    MeshBuffer,
    Program,
    RenderTarget,
    Texture2D,
    TextureCube,
    TextureFramebuffer,
)
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.cube_live import LiveCubeMapped
from mirrorlab.passes.envmap import CurvedPass
from mirrorlab.passes.sky import SCREEN_TRIANGLE
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.backgrounds import environment_of, load_picture
from mirrorlab.scene.model import Background, CurvedReflector
from mirrorlab.views import View


@lru_cache(maxsize=8)
def baked_octahedral(source: Background | Path, size: int) -> tuple[np.ndarray, ...]:
    """Every level of an octahedral map ``size`` texels wide of a background, or of the
    square octahedral picture at ``source`` (remembered: baking is numpy work)."""
    if isinstance(source, Path):
        picture = load_picture(source)
        if picture.shape[0] != picture.shape[1]:
            raise ValueError(
                f"picture {source} is {picture.shape[1]}x{picture.shape[0]}: an octahedral "
                f"map's picture must be square"
            )
        env = octahedral_picture_environment(picture)
    else:
        env = environment_of(source)
    return tuple(bake_octahedral(env, size))


def octahedral_uniforms(program: Program, levels: int) -> None:
    """What the octahedral lookup needs besides its texture: how many levels it has."""
    program.set_int("octahedral_levels", levels)


class OctahedralMapped(CurvedPass):
    """The ``octahedral`` technique: a static octahedral map of the background (or of the
    reflector's ``source``, a square octahedral picture), made once."""

    def __init__(
        self, shared: SharedResources, reflector: CurvedReflector, background: Background
    ) -> None:
        super().__init__(shared, reflector, background)
        source = background if reflector.source is None else reflector.source
        levels = baked_octahedral(source, reflector.map_size)
        self.sizes = octahedral_level_sizes(reflector.map_size)
        self.texture = Texture2D.with_levels(
            shared.registry,
            self.sizes,
            list(levels),
            what=f"reflector {reflector.name}'s octahedral map",
        )

    def release(self) -> None:
        self.texture.release()
        super().release()

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.texture

    def lookup_uniforms(
        self, program: Program, reflector: CurvedReflector, view: View, draw: ReflectorDraw | None
    ) -> None:
        octahedral_uniforms(program, len(self.sizes))


class LiveOctahedralMapped(LiveCubeMapped):
    """The ``octahedral-live`` technique: six faces captured as ``cube-live`` captures them
    (at the map's size, with their depths for a distance search), then every level of the
    slot's octahedral map drawn from them (``resample_octahedral.frag``), each texel
    filtered over its area by the cube's own mipmaps. Its lookups take ``cube-live``'s
    parallax corrections."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        # the cube's faces are the map's size (mirrorlab.captures.octahedral_cube_camera)
        self.sizes = octahedral_level_sizes(reflector.map_size)
        self.maps: dict[int, tuple[Texture2D, list[TextureFramebuffer]]] = {}
        self.triangle = MeshBuffer(shared.registry, SCREEN_TRIANGLE, np.arange(3, dtype=np.uint32))
        self.resample = shared.program("envmap_sky.vert", "resample_octahedral.frag")
        self.resample.use()
        self.resample.set_int("cube_map_texture", 0)

    def release(self) -> None:
        for texture, framebuffers in self.maps.values():
            for framebuffer in framebuffers:
                framebuffer.release()
            texture.release()
        self.maps.clear()
        self.triangle.release()
        super().release()

    def octahedral(self, slot: int) -> tuple[Texture2D, list[TextureFramebuffer]]:
        """The octahedral map of ``slot`` and a framebuffer drawing into each level."""
        if slot not in self.maps:
            texture = Texture2D.with_levels(self.shared.registry, self.sizes)
            framebuffers = [
                TextureFramebuffer(self.shared.registry, texture, level, depth=False)
                for level in range(len(self.sizes))
            ]
            self.maps[slot] = (texture, framebuffers)
        return self.maps[slot]

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Capture the cube (:meth:`LiveCubeMapped.update`), then resample it into every
        level of the slot's octahedral map."""
        draws = super().update(step, reflector, renderer, frame_target)
        framebuffers = self.octahedral(step.slot)[1]
        return draws + resample_levels(
            self.resample, self.triangle, self.cube(step.slot), framebuffers, self.sizes
        )

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.octahedral(draw.slot)[0]

    def lookup_uniforms(
        self, program: Program, reflector: CurvedReflector, view: View, draw: ReflectorDraw | None
    ) -> None:
        super().lookup_uniforms(program, reflector, view, draw)
        octahedral_uniforms(program, len(self.sizes))


def resample_levels(
    program: Program,
    triangle: MeshBuffer,
    cube: TextureCube,
    framebuffers: list[TextureFramebuffer],
    sizes: tuple[int, ...],
) -> int:
    """Draw each level of an octahedral map from ``cube`` (mipmapped) through its
    framebuffer; returns the draw count."""
    gl.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
    gl.glDisable(GL.GL_DEPTH_TEST)
    gl.glDisable(GL.GL_CULL_FACE)
    program.use()
    cube.bind(0)
    for framebuffer, size in zip(framebuffers, sizes, strict=True):
        framebuffer.bind()
        gl.glViewport(0, 0, size, size)
        program.set_float("level_size", float(size))
        triangle.draw()
    gl.glEnable(GL.GL_CULL_FACE)
    gl.glEnable(GL.GL_DEPTH_TEST)
    return len(sizes)
