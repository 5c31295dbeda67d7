"""Drawing the scene graph's parts: the piece both the capture and the camera pass use."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.resources import MeshBuffer, Program, Texture2D
from mirrorlab.scene.graph import SceneGraph
from mirrorlab.scene.mesh import load_model, load_texture


class LitScene(Protocol):
    """What the drawer needs of a scene: its graph and its light (the lab scene and the
    environment-mapping scenes both have them). ``light_direction`` points towards a
    directional light; ``ambient`` and ``diffuse`` weight it."""

    graph: SceneGraph
    light_direction: Sequence[float]
    ambient: float
    diffuse: float


class SceneDrawer:
    """GPU copies of the scene's meshes and textures, and the lit shader that draws them.

    Draws every node with a mesh (never the mirror) in one ``glDrawElements``
    call per node.
    """

    def __init__(self, registry: ResourceRegistry, scene: LitScene) -> None:
        self.scene = scene
        self.program = Program(registry, "scene.vert", "scene.frag")
        self.meshes: dict[str, MeshBuffer] = {}
        self.textures: dict[str, Texture2D] = {}
        for node in scene.graph.nodes():
            if node.mesh and node.mesh not in self.meshes:
                data = load_model(node.mesh)
                self.meshes[node.mesh] = MeshBuffer(registry, data.interleaved(), data.indices)
            if node.texture and node.texture not in self.textures:
                self.textures[node.texture] = Texture2D.from_image(
                    registry, load_texture(node.texture))
        self._drawn = [node for node in scene.graph.nodes() if node.mesh]
        self._matrices: list[tuple[np.ndarray, np.ndarray]] = []
        self._matrices_revision: int | None = None
        self.program.use()
        self.program.set_int("surface", 0)

    def part_matrices(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Model ``(4, 4)`` and normal ``(3, 3)`` float32 matrices of each drawn part,
        recomputed only when the scene graph's revision changes (both passes share them)."""
        revision = self.scene.graph.revision
        if revision != self._matrices_revision:
            self._matrices = []
            for node in self._drawn:
                model = node.world_matrix()
                self._matrices.append((model.astype(np.float32),
                                       math3d.normal_matrix(model).astype(np.float32)))
            self._matrices_revision = revision
        return self._matrices

    def release(self) -> None:
        """Free the program, meshes and textures."""
        for resource in (self.program, *self.meshes.values(), *self.textures.values()):
            resource.release()

    def draw(self, view_projection: np.ndarray, clip_plane: np.ndarray | None = None) -> int:
        """Draw all parts with the given ``(4, 4)`` projection @ view; returns the draw count.

        ``clip_plane`` ``(4,)`` (world space) cuts away whatever lies on its
        negative side; the caller enables ``GL_CLIP_DISTANCE0`` for it to act.
        """
        scene, program = self.scene, self.program
        program.use()
        program.set_mat4("view_projection", view_projection)
        # A plane every point is in front of, rather than none: Mesa 22.3's llvmpipe
        # clips by the shader's gl_ClipDistance even while GL_CLIP_DISTANCE0 is disabled.
        plane = (0.0, 0.0, 0.0, 1.0) if clip_plane is None else clip_plane
        program.set_vec4("clip_plane", plane)
        light = np.asarray(scene.light_direction, dtype=np.float64)
        program.set_vec3("light_direction", light / np.linalg.norm(light))
        program.set_float("ambient", scene.ambient)
        program.set_float("diffuse", scene.diffuse)
        for node, (model, normal) in zip(self._drawn, self.part_matrices(), strict=True):
            program.set_mat4("model", model)
            program.set_mat3("normal_matrix", normal)
            program.set_vec3("color", node.color)
            program.set_int("use_texture", node.texture is not None)
            if node.texture is not None:
                self.textures[node.texture].bind(0)
            self.meshes[node.mesh].draw()
        return len(self._drawn)
