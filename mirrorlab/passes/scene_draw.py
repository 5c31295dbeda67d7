"""Drawing the scene's objects, and reflectors as plain lit surfaces: the lit shader every
view uses."""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Program
from mirrorlab.passes.base import SharedResources, light_uniforms, set_view_uniforms
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Scene
from mirrorlab.scene.robot import Part, scene_parts
from mirrorlab.views import View


def surface_matrix(normal: np.ndarray, color, textured: bool) -> np.ndarray:
    """A part's ``part`` uniform (scene.vert, scene.frag), ``(4, 4)`` float32: the ``(3, 3)``
    normal matrix in the upper left, the RGB colour (0-1) down the last column, and 1 below
    it when the part wears its texture. One uniform call a part instead of three."""
    matrix = np.zeros((4, 4), dtype=np.float32)
    matrix[:3, :3] = normal
    matrix[:3, 3] = color
    matrix[3, 3] = 1.0 if textured else 0.0
    return matrix


class SceneDrawer:
    """Draws every part of a scene's objects (never its reflectors) with Lambert lighting,
    one ``glDrawElements`` call per part; and a reflector as a plain surface."""

    def __init__(self, shared: SharedResources) -> None:
        self.shared = shared
        self.program: Program = shared.program("scene.vert", "scene.frag")
        self.program.use()
        self.program.set_int("surface", 0)
        self._parts_of: Scene | None = None
        self._parts: list[tuple[Part, np.ndarray]] = []
        self._models = np.zeros((0, 4, 4))
        self._normals: dict[bytes, np.ndarray] = {}

    def _prepared(self, scene: Scene) -> tuple[list[tuple[Part, np.ndarray]], np.ndarray]:
        """Each part with its :func:`surface_matrix`, and every part's float64 model matrix
        ``(n, 4, 4)``, worked out once per scene (and a part's normal matrix once while
        its model stays: when the robot moves a joint, the parts before it stay where
        they were)."""
        if scene is not self._parts_of:
            normals = {}
            self._parts = []
            for part in scene_parts(scene):
                key = part.model.tobytes()
                normal = self._normals.get(key)
                if normal is None:
                    normal = math3d.normal_matrix(part.model)
                normals[key] = normal
                self._parts.append((part, surface_matrix(normal, part.color,
                                                         part.texture is not None)))
            self._models = np.array([part.model for part, _ in self._parts],
                                    dtype=np.float64).reshape(-1, 4, 4)
            self._normals = normals
            self._parts_of = scene
        return self._parts, self._models

    def begin(self, scene: Scene, view: View) -> Program:
        program = self.program
        program.use()
        set_view_uniforms(program, view)
        light_uniforms(program, scene)
        return program

    def draw(self, scene: Scene, view: View) -> int:
        """Draw the objects into the bound target; returns the number of draw calls."""
        program = self.begin(scene, view)
        parts, models = self._prepared(scene)
        # Camera-relative: each model moved to the view's origin in float64, then float32.
        relative = models.copy()
        relative[:, :3, 3] -= view.origin
        relative = relative.astype(np.float32)
        for (part, surface), model in zip(parts, relative, strict=True):
            program.set_mat4("model", model)
            program.set_mat4("part", surface)
            if part.texture is not None:
                self.shared.texture(part.texture).bind(0)
            self.shared.mesh(part.mesh).draw()
        return len(parts)

    def draw_plain(self, scene: Scene, reflector: CurvedReflector | PlanarReflector,
                   view: View, quad=None, quad_model: np.ndarray | None = None) -> int:
        """The reflector as a lit surface in its plain colour: a curved one's mesh, or a
        planar one's front (``quad``, its mesh buffer, placed by ``quad_model``). Returns
        the draw count (1)."""
        program = self.begin(scene, view)
        if isinstance(reflector, CurvedReflector):
            model = reflector.model_matrix()
            mesh = self.shared.mesh(reflector.mesh)
        else:
            model = np.eye(4) if quad_model is None else quad_model
            mesh = quad
        program.set_mat4("model", view.relative(model))
        program.set_mat4("part", surface_matrix(math3d.normal_matrix(model), reflector.color,
                                                textured=False))
        GL.glEnable(GL.GL_CULL_FACE)
        mesh.draw()
        return 1
