"""Drawing the environment-mapped object (the scene's reflector) with one of the
techniques: sphere map per fragment, per vertex, or by fixed-function GL_SPHERE_MAP
texgen; cube map (static or live); latitude-longitude map; "demo style" normal map.

The pass only draws; the maps it samples are made and kept up to date by the
renderer (:mod:`mirrorlab.envmap_renderer`).
"""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import (
    FixedFunctionMesh,
    MeshBuffer,
    Program,
    Texture2D,
    TextureCube,
)
from mirrorlab.scene.envscenes import Reflector, check_method
from mirrorlab.scene.mesh import load_model

SPHERE_METHODS = ("sphere", "sphere-vertex", "sphere-texgen")
CUBE_METHODS = ("cube", "cube-live")

_FRAGMENT_SHADERS = {
    "sphere": "envmap_sphere.frag", "sphere-vertex": "envmap_sphere.frag",
    "cube": "envmap_cube.frag", "cube-live": "envmap_cube.frag",
    "latlong": "envmap_latlong.frag", "normal": "envmap_normal.frag",
}
_SAMPLERS = {
    "envmap_sphere.frag": "sphere_map_texture", "envmap_cube.frag": "cube_map_texture",
    "envmap_latlong.frag": "latlong_texture", "envmap_normal.frag": "normal_map_texture",
}

OUTPUT_COLOR = 0
OUTPUT_COORDINATES = 1
"""What the shader paths write: the colour, or (for checks) the lookup coordinates: (s, t, 0)
for sphere, latlong and normal maps, the unit direction for cube maps."""


class EnvmapPass:
    """Draws ``reflector`` environment-mapped by ``method`` (see :data:`ENVMAP_METHODS`)
    into the bound target, depth-tested against what is already there.

    ``texture`` is what the method samples: a :class:`Texture2D` sphere map for the
    sphere methods and ``normal``, a :class:`TextureCube` for the cube methods, a
    :class:`Texture2D` latitude-longitude map (repeating in s) for ``latlong``. It can
    be swapped between frames (:attr:`texture`).
    """

    name = "envmap"

    def __init__(self, registry: ResourceRegistry, reflector: Reflector, method: str,
                 texture: Texture2D | TextureCube) -> None:
        self.method = check_method(method)
        self.reflector = reflector
        self.texture = texture
        data = load_model(reflector.mesh)
        self.mesh = MeshBuffer(registry, data.interleaved(), data.indices)
        self.program: Program | None = None
        self.fixed_mesh: FixedFunctionMesh | None = None
        if method == "sphere-texgen":
            self.fixed_mesh = FixedFunctionMesh(registry, self.mesh)
        else:
            fragment = _FRAGMENT_SHADERS[method]
            self.program = Program(registry, "envmap.vert", fragment)
            self.program.use()
            self.program.set_int(_SAMPLERS[fragment], 0)
            if fragment == "envmap_sphere.frag":
                self.program.set_int("per_vertex", method == "sphere-vertex")

    def release(self) -> None:
        """Free the mesh and program (not the texture, which the renderer owns)."""
        if self.fixed_mesh is not None:
            self.fixed_mesh.release()
        if self.program is not None:
            self.program.release()
        self.mesh.release()

    def run(self, view: np.ndarray, projection: np.ndarray,
            output: int = OUTPUT_COLOR) -> int:
        """Draw the reflector with world-to-eye ``view`` (rigid) and ``projection`` ``(4, 4)``
        into the bound target; returns the number of draw calls (1). ``output`` chooses
        colour or lookup coordinates (not for ``sphere-texgen``, which has no shader)."""
        model = self.reflector.model_matrix()
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glEnable(GL.GL_CULL_FACE)
        if self.method == "sphere-texgen":
            if output != OUTPUT_COLOR:
                raise ValueError("sphere-texgen is fixed-function: it can only output colour")
            self._draw_texgen(view @ model, projection)
            return 1
        assert self.program is not None
        program = self.program
        program.use()
        program.set_mat4("model", model)
        program.set_mat4("view", view)
        program.set_mat4("projection", projection)
        program.set_mat3("normal_matrix", math3d.normal_matrix(model))
        program.set_int("output_mode", output)
        if self.method in CUBE_METHODS or self.method == "latlong":
            program.set_vec3("eye_world", camera_position(view))
        if self.method == "normal":
            size = (self.texture.width, self.texture.height)  # type: ignore[union-attr]
            program.set_vec2("map_size", size)
        if self.method in CUBE_METHODS:
            GL.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        self.texture.bind(0)
        self.mesh.draw()
        return 1

    def _draw_texgen(self, model_view: np.ndarray, projection: np.ndarray) -> None:
        """The textbook's way: no shader, GL_SPHERE_MAP texgen for s and t, the sphere map
        replacing the fragment colour. GL_NORMALIZE makes the eye-space normals unit, as
        the numpy reference assumes."""
        assert self.fixed_mesh is not None
        GL.glUseProgram(0)
        GL.glMatrixMode(GL.GL_PROJECTION)
        GL.glLoadMatrixd(np.ascontiguousarray(projection.T, dtype=np.float64))
        GL.glMatrixMode(GL.GL_MODELVIEW)
        GL.glLoadMatrixd(np.ascontiguousarray(model_view.T, dtype=np.float64))
        GL.glDisable(GL.GL_LIGHTING)
        GL.glEnable(GL.GL_NORMALIZE)
        self.texture.bind(0)
        GL.glEnable(GL.GL_TEXTURE_2D)
        GL.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, GL.GL_REPLACE)
        for coordinate in (GL.GL_S, GL.GL_T):
            GL.glTexGeni(coordinate, GL.GL_TEXTURE_GEN_MODE, GL.GL_SPHERE_MAP)
        GL.glEnable(GL.GL_TEXTURE_GEN_S)
        GL.glEnable(GL.GL_TEXTURE_GEN_T)
        self.fixed_mesh.draw()
        GL.glDisable(GL.GL_TEXTURE_GEN_S)
        GL.glDisable(GL.GL_TEXTURE_GEN_T)
        GL.glDisable(GL.GL_TEXTURE_2D)
        GL.glDisable(GL.GL_NORMALIZE)
        GL.glLoadIdentity()
        GL.glMatrixMode(GL.GL_PROJECTION)
        GL.glLoadIdentity()
        GL.glMatrixMode(GL.GL_MODELVIEW)


def camera_position(view: np.ndarray) -> np.ndarray:
    """The eye's world position ``(3,)`` from a rigid world-to-eye ``view`` ``(4, 4)``."""
    view = np.asarray(view, dtype=np.float64)
    return -view[:3, :3].T @ view[:3, 3]
