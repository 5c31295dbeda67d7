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


class SceneDrawer:
    """Draws every part of a scene's objects (never its reflectors) with Lambert lighting,
    one ``glDrawElements`` call per part; and a reflector as a plain surface."""

    def __init__(self, shared: SharedResources) -> None:
        self.shared = shared
        self.program: Program = shared.program("scene.vert", "scene.frag")
        self.program.use()
        self.program.set_int("surface", 0)
        self._parts_of: Scene | None = None
        self._parts: list[tuple[Part, np.ndarray, np.ndarray]] = []
        self._normals: dict[bytes, np.ndarray] = {}

    def _prepared(self, scene: Scene) -> list[tuple[Part, np.ndarray, np.ndarray]]:
        """Each part with its float32 model and normal matrices, worked out once per scene
        (and a part's normal matrix once while its model stays: when the robot moves a
        joint, the parts before it stay where they were)."""
        if scene is not self._parts_of:
            normals = {}
            self._parts = []
            for part in scene_parts(scene):
                key = part.model.tobytes()
                normal = self._normals.get(key)
                if normal is None:
                    normal = math3d.normal_matrix(part.model).astype(np.float32)
                normals[key] = normal
                self._parts.append((part, part.model.astype(np.float32), normal))
            self._normals = normals
            self._parts_of = scene
        return self._parts

    def begin(self, scene: Scene, view: View) -> Program:
        program = self.program
        program.use()
        set_view_uniforms(program, view)
        light_uniforms(program, scene)
        return program

    def draw(self, scene: Scene, view: View) -> int:
        """Draw the objects into the bound target; returns the number of draw calls."""
        program = self.begin(scene, view)
        parts = self._prepared(scene)
        for part, model, normal in parts:
            program.set_mat4("model", model)
            program.set_mat3("normal_matrix", normal)
            program.set_vec3("color", part.color)
            program.set_int("use_texture", part.texture is not None)
            if part.texture is not None:
                self.shared.texture(part.texture).bind(0)
            self.shared.mesh(part.mesh).draw()
        return len(parts)

    def draw_plain(self, scene: Scene, reflector: CurvedReflector | PlanarReflector,
                   view: View, quad=None) -> int:
        """The reflector as a lit surface in its plain colour: a curved one's mesh, or a
        planar one's front (``quad``, its mesh buffer). Returns the draw count (1)."""
        program = self.begin(scene, view)
        if isinstance(reflector, CurvedReflector):
            model = reflector.model_matrix()
            mesh = self.shared.mesh(reflector.mesh)
        else:
            model = np.eye(4)
            mesh = quad
        program.set_mat4("model", model)
        program.set_mat3("normal_matrix", math3d.normal_matrix(model))
        program.set_vec3("color", reflector.color)
        program.set_int("use_texture", False)
        GL.glEnable(GL.GL_CULL_FACE)
        mesh.draw()
        return 1
