"""Environment-mapped (curved) reflectors with maps that hold only the background: sphere
maps (per fragment, per vertex, by GL_SPHERE_MAP texgen's formula in a shader, and the
"demo style" normal lookup), a static cube map and a latitude-longitude map. :class:`CurvedPass`
is what every curved technique shares, the live cube map (:mod:`.cube_live`) included.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from mirrorlab import math3d
from mirrorlab.envmap import bake_cube_faces, bake_latlong, bake_sphere_map
from mirrorlab.gl.calls import gl
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Program, RenderTarget, Texture2D, TextureCube
from mirrorlab.passes.base import SharedResources, ViewDrawer, cube_from_folder, set_clip_plane
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.backgrounds import environment_of, load_picture
from mirrorlab.scene.model import Background, CurvedReflector
from mirrorlab.techniques import technique
from mirrorlab.views import View, Warp, eye_position

OUTPUT_COLOR = 0
OUTPUT_COORDINATES = 1
OUTPUT_RAY_ORIGIN = 2
OUTPUT_RAY_DIRECTION = 3
"""What the shader paths write: the colour, or (for checks) the lookup coordinates: (s, t, 0)
for sphere, latlong and normal maps, the unit direction for cube maps (after any parallax
correction). The cube maps' shader also writes, for checks of the parallax corrections,
the reflected ray each fragment looks along: its world origin and unit direction."""


@lru_cache(maxsize=16)
def baked_cube(background: Background, size: int) -> np.ndarray:
    """Six faces of the background at ``size`` (remembered: baking is numpy work)."""
    return bake_cube_faces(environment_of(background), size)


@lru_cache(maxsize=8)
def baked_latlong(background: Background, size: int) -> np.ndarray:
    return bake_latlong(environment_of(background), 2 * size, size)


class CurvedPass:
    """A curved reflector drawn by its technique's shader program that samples a map;
    plain when bounces run out. What it sets besides the view and the map follows the
    technique's registry entry (:mod:`mirrorlab.techniques`). ``output_mode`` chooses
    colour or lookup coordinates (for numerical checks)."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        self.shared = shared
        self.entry = technique(reflector.technique)
        self.output_mode = OUTPUT_COLOR
        self.mesh = shared.mesh(reflector.mesh)
        self.made_for = reflector
        self.program = self.make_program(shared, reflector)
        self._warped: dict[Warp, Program] = {}

    def make_program(
        self, shared: SharedResources, reflector: CurvedReflector, warp: Warp | None = None
    ) -> Program:
        """The technique's shader program (for views of ``warp``), its map on texture
        unit 0."""
        program = shared.program(self.entry.vertex_shader, self.entry.fragment_shader, warp)
        program.use()
        program.set_int(self.entry.sampler, 0)
        return program

    def program_for(self, view: View) -> Program:
        """The program that draws the reflector in ``view``: :attr:`program`, or one made
        for a warped view's warp."""
        if view.warp is None:
            return self.program
        held = self._warped.get(view.warp)
        if held is None:
            held = self._warped[view.warp] = self.make_program(
                self.shared, self.made_for, view.warp
            )
        return held

    def release(self) -> None:
        """Nothing of its own: the program and the mesh are shared."""

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        raise ValueError(f"{self.entry.name} has no texture to update")

    def map_for(self, draw: ReflectorDraw) -> Texture2D | TextureCube:  # pragma: no cover
        raise NotImplementedError

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | TextureCube | None:
        """The map a ``map`` or ``texture`` draw samples (None for a plain one)."""
        return self.map_for(draw) if draw.own else None

    def draw(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        reflector = draw.reflector
        assert isinstance(reflector, CurvedReflector)
        if draw.mode == "plain":
            return renderer.drawer.draw_plain(renderer.scene, reflector, view)
        return self.draw_mapped(reflector, view, self.map_for(draw), draw)

    def lookup_uniforms(
        self, program: Program, reflector: CurvedReflector, view: View, draw: ReflectorDraw | None
    ) -> None:
        """Set what the lookup needs besides the map and the view (bound ``program``;
        world positions relative to ``view.origin``)."""

    def draw_mapped(
        self,
        reflector: CurvedReflector,
        view: View,
        texture: Texture2D | TextureCube,
        draw: ReflectorDraw | None = None,
    ) -> int:
        """Draw the reflector sampling ``texture`` (the map ``draw`` names) into the bound
        target; returns 1. Positions reach the shader relative to the view's origin
        (camera-relative rendering), the matrices composed in float64."""
        model = reflector.model_matrix()
        gl.glEnable(GL.GL_DEPTH_TEST)
        gl.glEnable(GL.GL_CULL_FACE)
        entry = self.entry
        program = self.program_for(view)
        program.use()
        program.set_int(entry.sampler, 0)  # a program may be shared: set what is ours
        for name, value in entry.constants:
            program.set_int(name, value)
        program.set_mat4("model", view.relative(model))
        program.set_mat4("view", view.relative_view)
        program.set_mat4("projection", view.projection)
        program.set_mat3("normal_matrix", math3d.normal_matrix(model))
        program.set_int("output_mode", self.output_mode)
        set_clip_plane(program, view)
        if program.has_uniform("orthographic"):  # "normal" ignores where the eye is
            program.set_int("orthographic", view.orthographic)
        if entry.view_ray:
            program.set_vec3("eye_world", eye_position(view.view) - view.origin)
            program.set_vec3("view_direction", view.forward)
        if entry.map_size_uniform:
            program.set_vec2("map_size", (texture.width, texture.height))  # type: ignore
        if isinstance(texture, TextureCube):
            gl.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        self.lookup_uniforms(program, reflector, view, draw)
        texture.bind(0)
        self.mesh.draw()
        return 1


class SphereMapped(CurvedPass):
    """Sphere maps (``sphere``, ``sphere-vertex``, ``sphere-texgen``, ``normal``): the
    reflector's picture as it is, or the background baked for each view's rotation
    (sphere maps live in eye space), one slot texture per bake."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        self.textures: dict[int, Texture2D] = {}

    def release(self) -> None:
        for texture in self.textures.values():
            texture.release()
        self.textures.clear()
        super().release()

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Bake (or load) the map the ``bake`` step's key names into its slot."""
        if reflector.source is not None:
            image = load_picture(reflector.source)
        else:
            rotation = np.asarray(step.key[3], dtype=np.float64).reshape(3, 3)
            image = bake_sphere_map(
                environment_of(renderer.scene.background), reflector.map_size, rotation
            )
        old = self.textures.pop(step.slot, None)
        if old is not None and (old.width, old.height) == (image.shape[1], image.shape[0]):
            old.bind(0)
            gl.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
            gl.glTexSubImage2D(
                GL.GL_TEXTURE_2D,
                0,
                0,
                0,
                old.width,
                old.height,
                GL.GL_RGB,
                GL.GL_UNSIGNED_BYTE,
                np.ascontiguousarray(image[::-1]),
            )
            gl.glGenerateMipmap(GL.GL_TEXTURE_2D)
            self.textures[step.slot] = old
            return 0
        if old is not None:
            old.release()
        what = (
            f"picture {reflector.source}"
            if reflector.source is not None
            else f"reflector {reflector.name}'s sphere map"
        )
        self.textures[step.slot] = Texture2D(
            self.shared.registry,
            image.shape[1],
            image.shape[0],
            image,
            mipmaps=True,
            clamp=True,
            what=what,
        )
        return 0

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.textures[draw.slot]


class CubeMapped(CurvedPass):
    """A static cube map: the reflector's six pictures, the background's own pictures, or
    six faces baked from the background, made once."""

    def __init__(
        self, shared: SharedResources, reflector: CurvedReflector, background: Background
    ) -> None:
        super().__init__(shared, reflector, background)
        folder = (
            reflector.source
            if reflector.source is not None
            else (background.path if background.kind == "cube_faces" else None)
        )
        if folder is not None:
            self.cube = cube_from_folder(shared.registry, folder)
        else:
            self.cube = TextureCube.from_faces(
                shared.registry,
                baked_cube(background, reflector.map_size),
                what=f"reflector {reflector.name}'s cube map",
            )

    def release(self) -> None:
        self.cube.release()
        super().release()

    def map_for(self, draw: ReflectorDraw) -> TextureCube:
        return self.cube


class LatlongMapped(CurvedPass):
    """A latitude-longitude map baked once from the background, ``2 map_size`` x
    ``map_size``: repeating across the phi seam, clamped at the poles."""

    def __init__(
        self, shared: SharedResources, reflector: CurvedReflector, background: Background
    ) -> None:
        super().__init__(shared, reflector, background)
        image = baked_latlong(background, reflector.map_size)
        self.texture = Texture2D(
            shared.registry, image.shape[1], image.shape[0], image, mipmaps=True, clamp=False
        )
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)

    def release(self) -> None:
        self.texture.release()
        super().release()

    def map_for(self, draw: ReflectorDraw) -> Texture2D:
        return self.texture
