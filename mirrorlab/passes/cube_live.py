"""A live cube map: six 90-degree captures of the scene from the reflector's centre, each
copied into a face with ``glCopyTexImage2D`` (the lab's capture, six times); the
reflector never appears in its own capture.

Its lookups may be corrected for surroundings that are not far away (the reflector's
``parallax``): through a box or a sphere proxy, or by a search along the reflected ray
in the distances the capture saw, for which each face's depth buffer is copied too
(``shaders/parallax.glsl``; the numpy reference is :mod:`mirrorlab.parallax`).
"""

from __future__ import annotations

import numpy as np

from mirrorlab.bounds import encloses
from mirrorlab.gl.resources import (
    DepthTextureCube,
    Program,
    RenderTarget,
    Texture2D,
    TextureCube,
)
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.envmap import CurvedPass
from mirrorlab.passes.sky import background_cube
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.model import (
    Background,
    BoxProxy,
    CurvedReflector,
    DistanceSearch,
    SphereProxy,
)
from mirrorlab.views import View, Warp

PARALLAX_CODES = {None: 0, "box": 1, "sphere": 2, "distance": 3}
"""The ``PARALLAX`` define of ``envmap_cube.frag`` for each kind of correction."""
DISTANCE_UNIT = 1
BACKGROUND_UNIT = 2
"""Texture units of a distance search's depth cube and background cube (the capture's
colour cube is on unit 0)."""


def capture_depth_range(face: View) -> tuple[float, float]:
    """The (near, far) clip distances of a live cube map's faces (one face's view), which
    a distance search reads its depths with."""
    assert face.depth_range is not None
    return face.depth_range


class LiveCubeMapped(CurvedPass):
    """The ``cube-live`` technique, one mipmapped cube per slot (and, for a distance
    search, one depth cube per slot). The planner captures it again when something it
    sees changes, not when only the viewer moves."""

    def __init__(
        self,
        shared: SharedResources,
        reflector: CurvedReflector,
        background: Background | None = None,
    ) -> None:
        super().__init__(shared, reflector, background)
        self.size = reflector.map_size
        self.cubes: dict[int, TextureCube] = {}
        self.depths: dict[int, DepthTextureCube] = {}
        self.enclosed: dict[int, bool] = {}
        """Whether the surroundings of a slot's capture close its centre in (a distance
        search's fallback, see :func:`mirrorlab.bounds.encloses`)."""
        self.background: TextureCube | None = None
        if isinstance(reflector.parallax, DistanceSearch):
            assert background is not None
            self.background = background_cube(shared, background)

    def make_program(
        self, shared: SharedResources, reflector: CurvedReflector, warp: Warp | None = None
    ) -> Program:
        kind = None if reflector.parallax is None else reflector.parallax.kind
        program = shared.program(
            self.entry.vertex_shader,
            self.entry.fragment_shader,
            warp,
            PARALLAX=PARALLAX_CODES[kind],
        )
        program.use()
        program.set_int(self.entry.sampler, 0)
        if kind == "distance":
            program.set_int("distance_map", DISTANCE_UNIT)
            program.set_int("background_map", BACKGROUND_UNIT)
        return program

    def release(self) -> None:
        for texture in (*self.cubes.values(), *self.depths.values()):
            texture.release()
        if self.background is not None:
            self.background.release()
        self.cubes.clear()
        self.depths.clear()
        self.enclosed.clear()
        super().release()

    def cube(self, slot: int) -> TextureCube:
        if slot not in self.cubes:
            self.cubes[slot] = TextureCube.blank(self.shared.registry, self.size, mipmaps=True)
        return self.cubes[slot]

    def depth(self, slot: int) -> DepthTextureCube:
        """The depth cube of ``slot`` (distance search only)."""
        if slot not in self.depths:
            self.depths[slot] = DepthTextureCube(self.shared.registry, self.size)
        return self.depths[slot]

    def update(
        self,
        step: PlannedPass,
        reflector: CurvedReflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Capture the six faces (each view's plan leaves this reflector out), and their
        depths for a distance search."""
        cube = self.cube(step.slot)
        depth = self.depth(step.slot) if isinstance(reflector.parallax, DistanceSearch) else None
        if depth is not None:
            self.enclosed[step.slot] = encloses(renderer.scene, reflector.center(), reflector.name)
        target = self.shared.scratch((self.size, self.size))
        draws = 0
        for face, plan in enumerate(step.views):
            draws += renderer.draw_view(plan, target)
            target.bind()
            cube.copy_face_from_framebuffer(face, target.size)
            if depth is not None:
                depth.copy_face_from_framebuffer(face)
        cube.generate_mipmaps()
        return draws

    def map_for(self, draw: ReflectorDraw) -> Texture2D | TextureCube:
        """The slot's cube (a subclass may resample it into a map of another kind)."""
        return self.cube(draw.slot)

    def lookup_uniforms(
        self, program: Program, reflector: CurvedReflector, view: View, draw: ReflectorDraw | None
    ) -> None:
        origin = view.origin
        if program.has_uniform("view_origin"):  # for the ray-origin output of checks
            program.set_vec3("view_origin", origin)
        parallax = reflector.parallax
        if parallax is None:
            return
        program.set_vec3("capture_center", reflector.center() - origin)
        if isinstance(parallax, BoxProxy):
            program.set_vec3("proxy_min", np.asarray(parallax.min) - origin)
            program.set_vec3("proxy_max", np.asarray(parallax.max) - origin)
        elif isinstance(parallax, SphereProxy):
            program.set_float("proxy_radius", parallax.radius)
        else:
            assert draw is not None and draw.source is not None
            program.set_int("search_steps", parallax.steps)
            program.set_int("secant_steps", parallax.secant)
            program.set_vec2("capture_depth_range", capture_depth_range(draw.source))
            program.set_float("thickness", parallax.thickness)
            program.set_int("enclosed", self.enclosed.get(draw.slot, False))
            self.depth(draw.slot).bind(DISTANCE_UNIT)
            assert self.background is not None
            self.background.bind(BACKGROUND_UNIT)
