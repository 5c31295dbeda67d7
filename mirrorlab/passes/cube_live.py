"""A live cube map: six 90-degree captures of the scene from the reflector's centre, each
copied into a face with ``glCopyTexImage2D`` (the lab's capture, six times); the
reflector never appears in its own capture."""

from __future__ import annotations

from mirrorlab.gl.resources import RenderTarget, TextureCube
from mirrorlab.passes.base import SharedResources, ViewDrawer
from mirrorlab.passes.envmap import CurvedPass
from mirrorlab.plan import PlannedPass, ReflectorDraw
from mirrorlab.scene.model import Background, CurvedReflector


class LiveCubeMapped(CurvedPass):
    """The ``cube-live`` technique, one mipmapped cube per slot. The planner captures it
    again when something it sees changes, not when only the viewer moves."""

    def __init__(self, shared: SharedResources, reflector: CurvedReflector,
                 background: Background | None = None) -> None:
        super().__init__(shared, reflector, background)
        self.size = reflector.map_size
        self.cubes: dict[int, TextureCube] = {}

    def release(self) -> None:
        for cube in self.cubes.values():
            cube.release()
        self.cubes.clear()
        super().release()

    def cube(self, slot: int) -> TextureCube:
        if slot not in self.cubes:
            self.cubes[slot] = TextureCube.blank(self.shared.registry, self.size, mipmaps=True)
        return self.cubes[slot]

    def update(self, step: PlannedPass, reflector: CurvedReflector, renderer: ViewDrawer,
               frame_target: RenderTarget) -> int:
        """Capture the six faces (each view's plan leaves this reflector out)."""
        cube = self.cube(step.slot)
        target = self.shared.scratch((self.size, self.size))
        draws = 0
        for face, plan in enumerate(step.views):
            draws += renderer.draw_view(plan, target)
            target.bind()
            cube.copy_face_from_framebuffer(face, target.size)
        cube.generate_mipmaps()
        return draws

    def map_for(self, draw: ReflectorDraw) -> TextureCube:
        return self.cube(draw.slot)
