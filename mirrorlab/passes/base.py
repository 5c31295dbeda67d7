"""What every pass shares: GL copies of meshes, pictures and programs made once per
context (:class:`SharedResources`), the per-view GL state (:func:`apply_view_state`), and
the protocol a reflector's technique follows (:class:`ReflectorPass`, and
:class:`ReportsFallback` for one that falls back to another where its own method has no
answer)."""

from __future__ import annotations

import ctypes
import functools
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.calls import FRAME_SWITCHES, gl, raw
from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import (
    Framebuffer,
    MeshBuffer,
    PackedMeshes,
    Program,
    Texture2D,
    TextureCube,
)
from mirrorlab.scene.backgrounds import cube_face_size, load_cube_faces
from mirrorlab.scene.mesh import MeshData, TextureSource, load_mesh, texture_picture

if TYPE_CHECKING:
    from mirrorlab.gl.resources import RenderTarget
    from mirrorlab.passes.scene_draw import SceneDrawer
    from mirrorlab.plan import PlannedPass, Rectangle, ReflectorDraw, ViewPlan
    from mirrorlab.scene.model import Light, Reflector, Scene
    from mirrorlab.views import View, Warp

SCRATCH_KEPT = 4
"""Scratch framebuffers kept, by size (most recently used)."""
NO_CLIP = (0.0, 0.0, 0.0, 1.0)
"""A plane every point is in front of: what the shaders get when nothing is clipped."""


class SharedResources:
    """GL objects that many passes and scenes use, made on first use and kept until
    :meth:`release`: meshes by file, textures by picture file, programs by shader pair,
    and scratch framebuffers by size."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self.registry = registry
        self._meshes: dict[Path, tuple[MeshData, MeshBuffer]] = {}
        self._textures: dict[TextureSource, Texture2D] = {}
        self._programs: dict[tuple, Program] = {}
        self._scratch: dict[tuple[int, int], Framebuffer] = {}
        self._packed: PackedMeshes | None = None
        self._ranges: dict[Path, tuple[int, int, int]] = {}

    @property
    def packed(self) -> PackedMeshes:
        """Every mesh :meth:`mesh_range` was asked for, in one vertex array."""
        if self._packed is None:
            self._packed = PackedMeshes(self.registry)
        return self._packed

    def mesh_range(self, path: Path) -> tuple[int, int, int]:
        """The mesh file ``path`` in :attr:`packed`: ``(first index, index count, base
        vertex)``, added on first use."""
        placed = self._ranges.get(path)
        if placed is None:
            data = load_mesh(path)
            placed = self._ranges[path] = self.packed.add(data.interleaved(), data.indices)
        return placed

    def mesh(self, path: Path) -> MeshBuffer:
        return self.mesh_data(path)[1]

    def mesh_data(self, path: Path) -> tuple[MeshData, MeshBuffer]:
        if path not in self._meshes:
            data = load_mesh(path)
            self._meshes[path] = (data, MeshBuffer(self.registry, data.interleaved(), data.indices))
        return self._meshes[path]

    def texture(self, source: TextureSource) -> Texture2D:
        """A mipmapped, repeating texture of the picture file (or glTF mesh's texture)
        ``source``."""
        if source not in self._textures:
            what = (
                f"picture {source}"
                if isinstance(source, Path)
                else f"base colour texture of {source.mesh}"
            )
            self._textures[source] = Texture2D.from_image(
                self.registry, texture_picture(source), what=what
            )
        return self._textures[source]

    def program(
        self, vertex: str, fragment: str, warp: Warp | None = None, **defines: str | int
    ) -> Program:
        """The program of the shader pair with ``defines``, made on first use. A program
        that draws a warped view (:class:`~mirrorlab.views.Warp`) is made for its ``warp``:
        the warp's shader stands in for ``warp.glsl``. A pass that draws in any view asks
        for its program with that view's ``warp``."""
        key = (vertex, fragment, tuple(sorted(defines.items())), warp)
        if key not in self._programs:
            includes = None if warp is None else {"warp.glsl": warp.shader}
            self._programs[key] = Program(self.registry, vertex, fragment, defines, includes)
        return self._programs[key]

    def scratch(self, size: tuple[int, int]) -> Framebuffer:
        """A colour + depth/stencil framebuffer of ``size`` to draw a capture into. The
        last :data:`SCRATCH_KEPT` sizes used are kept (a window being resized would
        otherwise leave one behind for every size it passed through)."""
        framebuffer = self._scratch.pop(size, None)
        if framebuffer is None:
            framebuffer = Framebuffer(self.registry, *size)
        self._scratch[size] = framebuffer  # now the most recently used
        while len(self._scratch) > SCRATCH_KEPT:
            oldest = next(iter(self._scratch))
            self._scratch.pop(oldest).release()
        return framebuffer

    def release(self) -> None:
        for _, mesh in self._meshes.values():
            mesh.release()
        for resource in (
            *self._textures.values(),
            *self._programs.values(),
            *self._scratch.values(),
        ):
            resource.release()
        if self._packed is not None:
            self._packed.release()
            self._packed = None
        self._ranges.clear()
        self._meshes.clear()
        self._textures.clear()
        self._programs.clear()
        self._scratch.clear()


def cube_from_folder(registry: ResourceRegistry, folder: Path) -> TextureCube:
    """A mipmapped cube map of the six pictures in ``folder``. Its storage is made from
    the first face's header before any picture is decoded: a size the GL cannot
    allocate fails at once, not after reading six large pictures."""
    cube = TextureCube.blank(
        registry, cube_face_size(folder), mipmaps=True, what=f"cube face {folder}/px.png"
    )
    try:
        cube.upload(load_cube_faces(folder))
    except BaseException:
        cube.release()
        raise
    return cube


def set_view_uniforms(program: Program, view: View) -> None:
    """``view_projection`` and ``clip_plane`` of ``view`` on the bound ``program``, both for
    positions relative to the view's origin (camera-relative rendering: the shader's
    ``model`` matrices are :meth:`View.relative`, so float32 never holds a large world
    position; see :attr:`View.origin`)."""
    program.set_mat4("view_projection", view.uniforms[0])
    set_clip_plane(program, view)


def set_clip_plane(program: Program, view: View) -> None:
    """``clip_plane`` of ``view`` on the bound ``program``, for origin-relative positions."""
    plane = view.uniforms[1]
    program.set_vec4("clip_plane", NO_CLIP if plane is None else plane)


def apply_view_state(view: View, stencil_level: int) -> None:
    """Winding, clipping and stencil test for drawing ``view`` at ``stencil_level`` (0: the
    whole target; k > 0: only where a stencil mirror k levels deep marked it)."""
    gl.glFrontFace(GL.GL_CW if view.mirrored else GL.GL_CCW)
    if view.clip_plane is None and view.warp is None:  # a warp may cut by the distance
        gl.glDisable(GL.GL_CLIP_DISTANCE0)
    else:
        gl.glEnable(GL.GL_CLIP_DISTANCE0)
    if stencil_level == 0:
        gl.glDisable(GL.GL_STENCIL_TEST)
    else:
        gl.glEnable(GL.GL_STENCIL_TEST)
        gl.glStencilFunc(GL.GL_EQUAL, stencil_level, 0xFF)
        gl.glStencilOp(GL.GL_KEEP, GL.GL_KEEP, GL.GL_KEEP)
    gl.glEnable(GL.GL_DEPTH_TEST)
    gl.glDepthFunc(GL.GL_LESS)
    gl.glEnable(GL.GL_CULL_FACE)
    gl.glCullFace(GL.GL_BACK)


_VALUES = (
    "GL_FRONT_FACE",
    "GL_CULL_FACE_MODE",
    "GL_DEPTH_FUNC",
    "GL_DEPTH_WRITEMASK",
    "GL_STENCIL_WRITEMASK",
    "GL_STENCIL_FUNC",
    "GL_STENCIL_REF",
    "GL_STENCIL_VALUE_MASK",
    "GL_STENCIL_FAIL",
    "GL_STENCIL_PASS_DEPTH_FAIL",
    "GL_STENCIL_PASS_DEPTH_PASS",
    "GL_CURRENT_PROGRAM",
    "GL_VERTEX_ARRAY_BINDING",
    "GL_ACTIVE_TEXTURE",
    "GL_DRAW_FRAMEBUFFER_BINDING",
    "GL_READ_FRAMEBUFFER_BINDING",
)


_SWITCH_ENUMS = tuple((name, getattr(GL, name)) for name in FRAME_SWITCHES)
_VALUE_ENUMS = tuple((name, getattr(GL, name)) for name in _VALUES)
_BOX_ENUMS = tuple((name, getattr(GL, name)) for name in ("GL_VIEWPORT", "GL_SCISSOR_BOX"))


_INTS = (ctypes.c_int * 4)()
_BOOLS = (ctypes.c_ubyte * 4)()
_FLOATS = (ctypes.c_float * 4)()


def gl_state() -> dict[str, object]:
    """The GL state a frame changes: switches, winding, depth and stencil settings, masks,
    bindings, viewport, scissor box and clear colour (to restore it, and for tests). Read
    through the raw entry points (:data:`mirrorlab.gl.calls.raw`): a frame reads it
    every time."""
    state: dict[str, object] = {name: bool(raw.glIsEnabled(enum)) for name, enum in _SWITCH_ENUMS}
    ints = _INTS
    for name, enum in _VALUE_ENUMS:
        raw.glGetIntegerv(enum, ints)
        state[name] = int(ints[0])
    raw.glGetBooleanv(GL.GL_COLOR_WRITEMASK, _BOOLS)
    state["GL_COLOR_WRITEMASK"] = tuple(bool(v) for v in _BOOLS)
    for name, enum in _BOX_ENUMS:
        raw.glGetIntegerv(enum, ints)
        state[name] = tuple(int(v) for v in ints)
    raw.glGetFloatv(GL.GL_COLOR_CLEAR_VALUE, _FLOATS)
    state["GL_COLOR_CLEAR_VALUE"] = tuple(round(float(v), 6) for v in _FLOATS)
    return state


def restore_state(state: dict[str, object]) -> None:
    """Put back what :func:`gl_state` read: leave GL as a frame found it."""
    for name, enum in _SWITCH_ENUMS:
        (raw.glEnable if state[name] else raw.glDisable)(enum)
    raw.glFrontFace(state["GL_FRONT_FACE"])
    raw.glCullFace(state["GL_CULL_FACE_MODE"])
    raw.glDepthFunc(state["GL_DEPTH_FUNC"])
    raw.glDepthMask(bool(state["GL_DEPTH_WRITEMASK"]))
    raw.glStencilMask(state["GL_STENCIL_WRITEMASK"])
    raw.glStencilFunc(
        state["GL_STENCIL_FUNC"], state["GL_STENCIL_REF"], state["GL_STENCIL_VALUE_MASK"]
    )
    raw.glStencilOp(
        state["GL_STENCIL_FAIL"],
        state["GL_STENCIL_PASS_DEPTH_FAIL"],
        state["GL_STENCIL_PASS_DEPTH_PASS"],
    )
    raw.glColorMask(*state["GL_COLOR_WRITEMASK"])  # type: ignore[misc]
    raw.glUseProgram(state["GL_CURRENT_PROGRAM"])
    raw.glBindVertexArray(state["GL_VERTEX_ARRAY_BINDING"])
    raw.glActiveTexture(state["GL_ACTIVE_TEXTURE"])
    raw.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, state["GL_DRAW_FRAMEBUFFER_BINDING"])
    raw.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, state["GL_READ_FRAMEBUFFER_BINDING"])
    raw.glViewport(*state["GL_VIEWPORT"])  # type: ignore[misc]
    raw.glScissor(*state["GL_SCISSOR_BOX"])  # type: ignore[misc]
    raw.glClearColor(*state["GL_COLOR_CLEAR_VALUE"])  # type: ignore[misc]


class ViewDrawer(Protocol):
    """What a pass may ask of the renderer: draw a planned view into a target, at a stencil
    level; the scene being drawn; the GL objects passes share; and the scene drawer, which
    draws a reflector as a plain lit surface (:meth:`SceneDrawer.draw_plain`)."""

    shared: SharedResources
    drawer: SceneDrawer

    @property
    def scene(self) -> Scene: ...

    def draw_view(
        self,
        plan: ViewPlan,
        target: RenderTarget,
        stencil_level: int = 0,
        cleared: Rectangle | None = None,
    ) -> int: ...


class ReflectorPass(Protocol):
    """A reflector's technique: made for one reflector (its geometry may move between
    frames, so each call gets the current one through ``step`` or ``draw``), it keeps
    the reflector's textures up to date and draws the reflector into a view. It is made
    as ``cls(shared, reflector, background)`` from its registry entry's ``pass_class``;
    where its cameras are and when it draws come from that entry too
    (:mod:`mirrorlab.techniques`), not from the pass.

    The replay rule: the GL calls of a frame may be recorded and made again, with the
    arguments they were given, for the frames after it that are planned the same way
    (:class:`mirrorlab.renderer.RecordedFrame`). So an array a pass hands GL must not
    change afterwards while that frame is kept: hand GL fresh or read-only arrays. A
    replayed frame is then the frame the pass would draw anew, pixel for pixel.
    """

    def update(
        self,
        step: PlannedPass,
        reflector: Reflector,
        renderer: ViewDrawer,
        frame_target: RenderTarget,
    ) -> int:
        """Make the texture ``step`` asks for (a capture or a bake) in ``step.slot``;
        ``frame_target`` may be drawn into first (nothing of the frame is there yet).
        Returns the number of draw calls."""
        ...

    def draw(
        self,
        draw: ReflectorDraw,
        view: View,
        renderer: ViewDrawer,
        target: RenderTarget,
        stencil_level: int,
    ) -> int:
        """Draw the reflector into the bound ``target`` as ``draw`` says; returns the number
        of draw calls."""
        ...

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | TextureCube | None:
        """The texture ``draw`` (one of this pass's draws in the last frame) samples: its
        capture or its map, for a viewer to look at; None where it samples none (a plain
        surface, its backing, an inline draw)."""
        ...

    def release(self) -> None:
        """Free every GL object this pass made (not the shared ones)."""
        ...


@runtime_checkable
class ReportsFallback(Protocol):
    """What a pass adds to :class:`ReflectorPass` when its technique has a fallback (a
    probe it draws where its own method finds no answer, as screen-space reflections do
    for rays that leave the screen): which pixels of a view it filled that way. The
    accuracy sweep reports the share of a reflector's pixels that fell back (its ``miss
    share``) for every technique whose pass has this method; the others have none."""

    def fallback_mask(self, draw: ReflectorDraw, view: View) -> np.ndarray | None:
        """``(h, w)`` bool over ``view``'s target (``view.size``), row 0 at the top as a
        read-back frame is: True where the last frame's ``draw`` (one of this pass's draws
        in ``view``) showed its fallback instead of its own method's answer. None where it
        drew nothing in ``view``. Called after the frame, with its context current (it
        may read GL back); it changes nothing that is drawn."""
        ...


@functools.lru_cache(maxsize=32)
def _light_arrays(lights: tuple[Light, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions and colour times intensity, ``(k, 3)`` float32 each for the ``k``
    lights, worked out once per set of lights."""
    directions = np.zeros((4, 3), dtype=np.float32)
    colors = np.zeros((4, 3), dtype=np.float32)
    for i, light in enumerate(lights):
        direction = np.asarray(light.direction, dtype=np.float64)
        directions[i] = direction / np.linalg.norm(direction)
        colors[i] = np.asarray(light.color, dtype=np.float64) * light.intensity
    return math3d.read_only(directions[: len(lights)]), math3d.read_only(colors[: len(lights)])


def light_uniforms(program: Program, scene: Scene) -> None:
    """The scene's lights on the bound ``program``, built with ``LIGHT_COUNT`` defined as
    their number (see lighting.glsl)."""
    count = len(scene.lights)
    if count:  # with none, the arrays are not read, so not in the program
        directions, colors = _light_arrays(tuple(scene.lights))
        program.set_vec3_array("light_directions", directions)
        program.set_vec3_array("light_colors", colors)
    program.set_float("ambient", scene.ambient)
