"""The stencil reflection: the mirrored scene drawn straight into the frame, masked by the
stencil to the visible part of the mirror, with no texture in between."""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program
from mirrorlab.passes.camera import mirror_vertices
from mirrorlab.passes.reflected import mirror_plane
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.scene.robot import LabScene


class StencilReflectionPass:
    """Runs after the scene has been drawn from the viewer into the bound target (which
    needs a stencil buffer; mirrorlab's targets have 8 bits):

    1. the mirror's visible front writes 1 into the stencil (no colour, no depth);
    2. there, colour is reset to the background and depth to the far plane;
    3. the scene is drawn again through ``view_projection @ reflection``, with
       front faces turned clockwise (a reflection flips winding), clipped to
       the mirror's reflecting side, and only where the stencil holds 1.

    :meth:`draw_backing` draws the mirror's back face, the only part seen from behind.
    """

    name = "stencil-reflection"

    def __init__(self, registry: ResourceRegistry, scene: LabScene, drawer: SceneDrawer) -> None:
        self.scene = scene
        self.drawer = drawer
        self.program = Program(registry, "flat.vert", "flat.frag")
        self.quad = MeshBuffer(registry, *mirror_vertices(scene.mirror))
        self.plane = mirror_plane(scene.mirror)
        self.reflection = math3d.reflection_matrix(self.plane)

    def release(self) -> None:
        """Free the mask program and quad (not the shared drawer)."""
        self.program.release()
        self.quad.release()

    def _flat_quad(self, view_projection: np.ndarray, color, far_depth: bool) -> None:
        self.program.use()
        self.program.set_mat4("view_projection", view_projection)
        self.program.set_vec3("color", color)
        self.program.set_int("far_depth", far_depth)
        self.quad.draw()

    def draw_backing(self, view_projection: np.ndarray) -> int:
        """The mirror's back face in its backing colour; returns the draw count (1)."""
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glCullFace(GL.GL_FRONT)
        self._flat_quad(view_projection, self.scene.mirror_backing, far_depth=False)
        GL.glCullFace(GL.GL_BACK)
        return 1

    def run(self, view_projection: np.ndarray) -> int:
        """Draw the reflection into the bound target; returns the number of draw calls."""
        scene = self.scene
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glEnable(GL.GL_STENCIL_TEST)
        GL.glStencilMask(0xFF)
        GL.glStencilFunc(GL.GL_ALWAYS, 1, 0xFF)
        GL.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_REPLACE)
        GL.glColorMask(GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE, GL.GL_FALSE)
        GL.glDepthMask(GL.GL_FALSE)
        self._flat_quad(view_projection, scene.background, far_depth=False)

        GL.glColorMask(GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE, GL.GL_TRUE)
        GL.glDepthMask(GL.GL_TRUE)
        GL.glStencilFunc(GL.GL_EQUAL, 1, 0xFF)
        GL.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_KEEP)
        GL.glDepthFunc(GL.GL_ALWAYS)
        self._flat_quad(view_projection, scene.background, far_depth=True)
        GL.glDepthFunc(GL.GL_LESS)

        GL.glEnable(GL.GL_CLIP_DISTANCE0)
        GL.glFrontFace(GL.GL_CW)
        draws = self.drawer.draw(view_projection @ self.reflection, clip_plane=self.plane)
        GL.glFrontFace(GL.GL_CCW)
        GL.glDisable(GL.GL_CLIP_DISTANCE0)
        GL.glDisable(GL.GL_STENCIL_TEST)
        return draws + 2
