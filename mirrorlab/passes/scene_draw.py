"""Drawing the scene's objects, and reflectors as plain lit surfaces: the lit shader every
view uses.

Each view draws only the parts it can see: every part's world box lives in the scene's
bounds arrays (:class:`mirrorlab.bounds.SceneIndex`, as rows kept for each pose) and all
of them are tested against the view's clip volume in one matrix product
(:func:`mirrorlab.culling.rows_in_view` with the view's :meth:`~mirrorlab.views.View.cull_test`).
The meshes are packed into one vertex and one index buffer
(:class:`~mirrorlab.gl.resources.PackedMeshes`). What is left is drawn one of two ways,
chosen when the drawer is made, from what the context offers:

Either way each visible part's matrices go into a parts buffer, and its range of the
packed meshes into an indirect command: consecutive parts of one mesh (and texture) are
the instances of one command, the first one's place in the buffer its base instance
(``scene_packed.vert`` reads each part's matrices as per-instance attributes:
:meth:`~mirrorlab.gl.resources.PackedMeshes.carry_parts`). A view's commands and buffer
are recorded once and kept while the scene's objects and the view stay as they were (a
still frame re-sends nothing but the calls that draw), and a new pose of the same parts
is sent into the same buffer (:meth:`SceneDrawer.repose`), so that a replayed frame's
calls draw it. Then:

- ``packed`` (OpenGL 4.3): the pass is one ``glMultiDrawElementsIndirect`` for each run
  of commands that share a texture, the commands in a GL buffer.
- ``per-draw`` (any OpenGL 3.3, macOS's 4.1 among them, which has no multi-draw
  indirect and no base instance): one ``glDrawElementsInstancedBaseVertex`` a command,
  the parts' attributes pointed at its first part's place in the buffer first
  (:meth:`~mirrorlab.gl.resources.PackedMeshes.point_parts`). A thousand boxes of one
  mesh are one draw call; parts of meshes all different are a draw each.

Both draw the parts in the scene's order with the same float32 matrices (instances are
drawn in order, one after the other), so the picture is the same, pixel for pixel.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from mirrorlab import culling, math3d
from mirrorlab.bounds import ObjectArrays, SceneIndex, scene_index
from mirrorlab.draw_path import DRAW_PATHS, DrawPath
from mirrorlab.gl.calls import cached_state_epoch, gl
from mirrorlab.gl.context import gl_version, has_multi_draw
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Buffer, Program
from mirrorlab.passes.base import SharedResources, light_uniforms, set_view_uniforms
from mirrorlab.plan import Rectangle
from mirrorlab.scene.mesh import TextureSource
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Scene
from mirrorlab.scene.robot import PartLooks
from mirrorlab.views import View, Warp

FEW_PARTS = 32
"""Up to this many parts in view, none is culled for covering no pixel centre: testing
costs more than the draws it could save (culling never changes a pixel either way)."""
SPARE_BUFFERS = 4
"""Pairs of buffers of freed recorded views kept for the next ones (a frame records
one view a pass)."""


def surface_matrix(normal: np.ndarray, color, textured: bool) -> np.ndarray:
    """A part's ``part`` matrix (scene.vert, scene_packed.vert), ``(4, 4)`` float32: the
    ``(3, 3)`` normal matrix in the upper left, the RGB colour (0-1) down the last column,
    and 1 below it when the part wears its texture."""
    matrix = np.zeros((4, 4), dtype=np.float32)
    matrix[:3, :3] = normal
    matrix[:3, 3] = color
    matrix[3, 3] = 1.0 if textured else 0.0
    return matrix


Run = tuple[TextureSource | None, int, int]
"""Consecutive commands that share a texture: (texture or None, first command, count)."""
Layout = tuple[np.ndarray, tuple[Run, ...]]
"""How a view's visible parts are drawn (:func:`draw_layout`): its indirect commands
``(c, 5)`` uint32 and its runs of them."""
LAYOUTS_KEPT = 8
"""Layouts a part table keeps (a frame draws a view or two a pass)."""


@dataclass(eq=False)
class PartTable:
    """What drawing a scene index's parts takes, worked out once per index: ``columns``
    ``(n, 2, 4, 4)`` float64, each part's model and surface matrix by column, as the
    packed path's parts buffer holds them (in the table of the parts' looks, which the
    tables of their poses are made from, the model and the normal matrix are left 0);
    ``textures`` (each part's, or None), ``ranges`` ``(n, 3)`` int (first index, index
    count, base vertex in the packed meshes), and the layouts of the views drawn lately.
    Read-only."""

    columns: np.ndarray
    textures: tuple[TextureSource | None, ...]
    texture_ids: np.ndarray
    """``(n,)``: each part's position in ``worn`` (-1: none)."""
    worn: tuple[TextureSource, ...]
    """The textures the parts wear, each once."""
    ranges: np.ndarray
    mesh_ids: np.ndarray
    """``(n,)``: which mesh each part draws (equal ids, equal ranges)."""
    layouts: OrderedDict[bytes, Layout] = field(default_factory=OrderedDict)
    """The last few :func:`draw_layout` s, by the visible parts' bytes: shared by every
    pose's table of the same parts (the same dictionary), since a layout depends on the
    meshes and textures alone."""

    @cached_property
    def surfaces(self) -> np.ndarray:
        """``(n, 4, 4)`` float32: each part's :func:`surface_matrix` (its ``part``
        uniform)."""
        return math3d.read_only(self.columns[:, 1].transpose(0, 2, 1).astype(np.float32, order="C"))


@dataclass(eq=False)
class RecordedView:
    """One view's draw, recorded: the visible parts' matrices (``parts``) and indirect
    commands (``commands``; filled on the packed path alone) in GL buffers, its
    :data:`Run` s of commands in order (``runs``), and which parts it draws (``visible``,
    positions ``(k,)``)."""

    parts: Buffer
    commands: Buffer
    commands_held: np.ndarray
    """The layout's commands the ``commands`` buffer holds (read-only: a buffer given to
    another view of the same layout is not filled again)."""
    runs: tuple[Run, ...]
    visible: np.ndarray

    @cached_property
    def drawn(self) -> frozenset[int]:
        """The positions of the parts it draws (``visible``), as a set."""
        return frozenset(self.visible.tolist())


def _few_indirect_commands(
    table: PartTable, visible: np.ndarray
) -> tuple[np.ndarray, tuple[tuple[TextureSource | None, int, int], ...]]:
    """:func:`indirect_commands` one part at a time."""
    commands: list[list[int]] = []
    runs: list[list] = []  # [texture id, first command, count]
    last_mesh = -1
    for position, part in enumerate(visible.tolist()):
        texture, mesh = int(table.texture_ids[part]), int(table.mesh_ids[part])
        if not runs or (texture >= 0 and runs[-1][0] >= 0 and texture != runs[-1][0]):
            runs.append([texture, len(commands), 0])
            last_mesh = -1
        elif texture >= 0 and runs[-1][0] < 0:
            runs[-1][0] = texture  # an untextured run takes the first texture it meets
        if mesh == last_mesh:
            commands[-1][1] += 1
            continue
        first, count, base = (int(v) for v in table.ranges[part])
        commands.append([count, 1, first, base, position])
        runs[-1][2] += 1
        last_mesh = mesh
    return (
        np.array(commands, dtype=np.uint32).reshape(-1, 5),
        tuple((table.worn[tid] if tid >= 0 else None, first, count) for tid, first, count in runs),
    )


def texture_runs(ids: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs of consecutive parts that can share one bound texture, from each part's
    texture id ``(k,)`` (-1: wears none, so it joins any run): ``(id, first, count)``,
    -1 only when no part of the run wears one."""
    if not len(ids):
        return []
    worn = np.flatnonzero(ids >= 0)
    if not len(worn):
        return [(-1, 0, len(ids))]
    # a part without a texture takes the last texture before it (or the first one)
    last = np.maximum.accumulate(np.where(ids >= 0, np.arange(len(ids)), -1))
    filled = np.where(last >= 0, ids[np.maximum(last, 0)], ids[worn[0]])
    starts = np.flatnonzero(np.concatenate([[True], filled[1:] != filled[:-1]]))
    ends = np.concatenate([starts[1:], [len(ids)]])
    return [(int(filled[a]), int(a), int(b - a)) for a, b in zip(starts, ends, strict=True)]


class SceneDrawer:
    """Draws the parts of a scene's objects a view can see (never its reflectors) with
    Lambert lighting, by ``draw_path`` (see the module's docstring); and a reflector as a
    plain surface."""

    def __init__(self, shared: SharedResources, draw_path: DrawPath = "auto") -> None:
        if draw_path not in DRAW_PATHS:
            raise ValueError(f"draw_path must be one of {', '.join(DRAW_PATHS)}, got {draw_path!r}")
        if draw_path == "auto":
            draw_path = "packed" if has_multi_draw() else "per-draw"
        elif draw_path == "packed" and not has_multi_draw():
            raise ValueError(
                "draw_path 'packed' needs OpenGL 4.3; this context has "
                f"{'.'.join(map(str, gl_version()))}"
            )
        self.draw_path: DrawPath = draw_path
        self.shared = shared
        shared.packed.carry_parts()
        # by light count and warp
        self._programs: dict[tuple[int, Warp | None], tuple[Program, Program]] = {}
        self._tables: OrderedDict[ObjectArrays, PartTable] = OrderedDict()
        self._looks: OrderedDict[tuple[PartLooks, ...], PartTable] = OrderedDict()
        # the recorded views: those drawn in the frame being drawn or the
        # last one (a still frame draws them again; any other is freed by end_frame)
        self._recorded: dict[tuple, RecordedView] = {}
        self._used: set[tuple] = set()
        self._spare: list[tuple[Buffer, Buffer, np.ndarray | None]] = []
        """Buffers of freed recorded views, filled again by the next views recorded (a
        moving viewer records a view or two every frame: no GL buffer is made or deleted
        for them)."""
        self.parts_drawn = 0
        """Parts drawn since it was last set to 0 (the renderer does, each frame)."""
        self._lit: dict[Program, tuple] = {}
        """The lights and ambient light each lit program was last given, and the
        :func:`~mirrorlab.gl.calls.cached_state_epoch` then (a recording sets them
        again)."""
        self._offsets: tuple[Sequence, np.ndarray] | None = None

    # ------------------------------------------------------------- parts

    def _table(self, index: SceneIndex) -> PartTable:
        """The :class:`PartTable` of ``index``'s objects (kept for the last few). Only the
        normal matrices depend on where the parts are: the rest is kept by the parts'
        looks (:attr:`~mirrorlab.bounds.ObjectArrays.looks`), so a new pose of the same
        parts works out those alone."""
        objects = index.objects_part
        table = self._tables.get(objects)
        if table is not None:
            self._tables.move_to_end(objects)
            return table
        held = self._looks.get(objects.looks)
        if held is None:
            held = self._looks[objects.looks] = self._look_table(objects.looks)
            while len(self._looks) > 4:
                self._looks.popitem(last=False)
        else:
            self._looks.move_to_end(objects.looks)
        models = objects.models
        columns = held.columns.copy()
        if len(models):
            columns[:, 0] = models.transpose(0, 2, 1)  # GLSL's are by column
            columns[:, 1, :3, :3] = np.linalg.inv(models[:, :3, :3])  # the normal matrix's
        table = PartTable(
            columns,
            held.textures,
            held.texture_ids,
            held.worn,
            held.ranges,
            held.mesh_ids,
            held.layouts,
        )
        self._tables[objects] = table
        while len(self._tables) > 4:
            self._tables.popitem(last=False)
        return table

    def _look_table(self, looks: tuple[PartLooks, ...]) -> PartTable:
        """A :class:`PartTable` of the parts of ``looks``, its normal matrices not filled
        in."""
        meshes = [mesh for look in looks for mesh in look.meshes]
        colors = [color for look in looks for color in look.colors]
        textures = tuple(texture for look in looks for texture in look.textures)
        count = len(meshes)
        columns = np.zeros((count, 2, 4, 4))
        if count:  # the surface matrix's colour and texture switch, by column
            columns[:, 1, 3, :3] = colors
            columns[:, 1, 3, 3] = [texture is not None for texture in textures]
        worn = tuple(dict.fromkeys(t for t in textures if t is not None))
        unique = {t: i for i, t in enumerate(worn)}
        ranges = np.array(
            [self.shared.mesh_range(mesh) for mesh in meshes], dtype=np.int64
        ).reshape(-1, 3)
        mesh_ids = {mesh: i for i, mesh in enumerate(dict.fromkeys(meshes))}
        return PartTable(
            columns,
            textures,
            np.array(
                [unique.get(t, -1) if t is not None else -1 for t in textures], dtype=np.int64
            ),
            worn,
            ranges,
            np.array([mesh_ids[mesh] for mesh in meshes], dtype=np.int64),
        )

    @staticmethod
    def visible(index: SceneIndex, view: View, scissor: Rectangle | None = None) -> np.ndarray:
        """Positions ``(k,)`` of the parts of ``index`` that may show in ``view`` (within
        ``scissor``, when given): boxes within its clip volume, then of those, the ones
        that may colour a pixel (:func:`mirrorlab.culling.boxes_cover_pixels`)."""
        inside = culling.rows_in_view(
            index.objects_part.part_rows, view.cull_test(scissor)
        ).nonzero()[0]
        if len(inside) <= FEW_PARTS:
            return inside  # too few for the pixel test to pay for itself
        covering = culling.boxes_cover_pixels(
            index.part_centers[inside],
            index.part_halves[inside],
            view.view_projection,
            view.size,
            scissor,
        )
        return inside[covering]

    @staticmethod
    def relative_columns(table: PartTable, visible: np.ndarray, view: View) -> np.ndarray:
        """``(k, 2, 4, 4)`` float32: the ``visible`` parts' model and surface matrices by
        column (the packed path's parts buffer), the models relative to the view's origin,
        composed in float64 (camera-relative rendering). When the view sees every part,
        they are not copied first."""
        columns = table.columns if len(visible) == len(table.columns) else table.columns[visible]
        return (columns - view.column_offset).astype(np.float32)

    # ------------------------------------------------------------- drawing

    def programs(self, scene: Scene, warp: Warp | None = None) -> tuple[Program, Program]:
        """The lit programs for ``scene``'s number of lights (each count has its own,
        ``LIGHT_COUNT`` defined in lighting.glsl) in views of ``warp``: one drawing a
        surface by uniforms (a plain reflector), and one drawing parts from a parts
        buffer (the objects)."""
        count = len(scene.lights)
        held = self._programs.get((count, warp))
        if held is None:
            held = self._programs[(count, warp)] = (
                self.shared.program("scene.vert", "scene.frag", warp, LIGHT_COUNT=count),
                self.shared.program("scene_packed.vert", "scene.frag", warp, LIGHT_COUNT=count),
            )
            for program in held:  # the texture unit is set once, when made
                program.use()
                program.set_int("texture_map", 0)
        return held

    def begin(self, scene: Scene, view: View, packed: bool = False) -> Program:
        """Bind the lit program for ``scene`` (the one reading a parts buffer with
        ``packed``) and set ``view``'s and the lights' uniforms on it."""
        by_uniforms, from_buffer = self.programs(scene, view.warp)
        program = from_buffer if packed else by_uniforms
        program.use()
        set_view_uniforms(program, view)
        lights = (scene.lights, scene.ambient, cached_state_epoch())
        if self._lit.get(program) != lights:  # only this drawer lights its programs
            light_uniforms(program, scene)
            self._lit[program] = lights
        return program

    def draw(
        self, scene: Scene, view: View, scissor: Rectangle | None = None, cull: bool = True
    ) -> int:
        """Draw the objects into the bound target (what can show within ``scissor``, the
        part of it that matters, when given; every part, with ``cull`` False); returns the
        number of draw calls."""
        index = scene_index(scene)
        if not len(index.objects_part):
            return 0
        return self._draw_recorded(scene, view, index, self._table(index), scissor, cull)

    def _draw_recorded(
        self,
        scene: Scene,
        view: View,
        index: SceneIndex,
        table: PartTable,
        scissor: Rectangle | None,
        cull: bool,
    ) -> int:
        """Draw ``view`` 's recorded draw of ``index`` (recorded now when it has none) by
        the drawer's path; returns the number of draw calls."""
        recorded = self._record(index, view, table, scissor, cull)
        self.parts_drawn += len(recorded.visible)
        if not recorded.runs:
            return 0
        packed = self.shared.packed
        packed.bind()
        packed.bind_parts(recorded.parts.name)
        self.begin(scene, view, packed=True)
        if self.draw_path == "packed":
            return self._multi_draw(recorded)
        return self._draw_instanced(recorded)

    def _multi_draw(self, recorded: RecordedView) -> int:
        """Each run of ``recorded`` 's commands one multi-draw; returns the runs' count."""
        packed = self.shared.packed
        gl.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, recorded.commands.name)
        for texture, first, count in recorded.runs:
            if texture is not None:
                self.shared.texture(texture).bind(0)
            packed.multi_draw(first, count)
        gl.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        return len(recorded.runs)

    def _draw_instanced(self, recorded: RecordedView) -> int:
        """Each of ``recorded`` 's commands one instanced draw (no base instance: the
        parts' attributes are pointed at its first part); returns the commands' count."""
        packed = self.shared.packed
        commands = recorded.commands_held
        for texture, first, count in recorded.runs:
            if texture is not None:
                self.shared.texture(texture).bind(0)
            for index_count, instances, first_index, base_vertex, first_part in commands[
                first : first + count
            ].tolist():
                packed.point_parts(first_part)
                packed.draw_instanced(first_index, index_count, base_vertex, instances)
        return len(commands)

    def prepare(
        self, scene: Scene, views: Iterable[tuple[View, Rectangle | None]], cull: bool = True
    ) -> None:
        """Record the draws of the ``views`` (each with its scissor) a
        frame is about to draw: culling and the parts' data of every view are worked out
        in one stretch, before the frame's first pass makes Python wait for the
        rasteriser (after which its caches are cold). A view recorded already is left."""
        index = scene_index(scene)
        if not len(index.objects_part):
            return
        table = self._table(index)
        for view, scissor in views:
            self._record(index, view, table, scissor, cull)

    def _record(
        self, index: SceneIndex, view: View, table: PartTable, scissor: Rectangle | None, cull: bool
    ) -> RecordedView:
        """``view``'s recorded draw of ``index`` (made when it has none)."""
        key = (*_view_key(index, view, scissor), cull)
        self._used.add(key)
        recorded = self._recorded.get(key)
        if recorded is not None:
            return recorded
        visible = self.visible(index, view, scissor) if cull else np.arange(len(index.objects_part))
        data = self.relative_columns(table, visible, view)
        commands, runs = draw_layout(table, visible)
        parts, commands_buffer, held = self._spare_for(commands)
        recorded = RecordedView(parts, commands_buffer, commands, runs, visible)
        recorded.parts.upload(GL.GL_ARRAY_BUFFER, data)
        if held is not commands and self.draw_path == "packed":  # per-draw: commands_held
            recorded.commands.upload(GL.GL_DRAW_INDIRECT_BUFFER, commands)
            gl.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
        self._recorded[key] = recorded
        return recorded

    def follows_pose(
        self, objects: ObjectArrays, views: Iterable[tuple[View, Rectangle | None]], cull: bool
    ) -> bool:
        """Whether the calls that drew ``objects`` in ``views`` (each with its scissor, as
        recorded by :meth:`prepare`) draw another pose of the same parts as well once
        :meth:`repose` has sent its data: every part's matrices are in the recorded
        views' buffers."""
        return all(
            (objects, view.draw_key, scissor, cull) in self._recorded for view, scissor in views
        )

    def repose(
        self,
        objects: ObjectArrays,
        index: SceneIndex,
        views: Sequence[tuple[View, Rectangle | None]],
        cull: bool,
    ) -> bool:
        """Send the new pose of ``objects`` that ``index`` holds into the buffers of their
        recorded ``views`` (each with its scissor), which then hold it: the same calls
        draw it (:meth:`follows_pose`). False, and nothing sent, when the new pose is of
        other parts, or a part might show in a view that did not draw it.

        A view keeps drawing the parts it drew: one that left it is clipped away, which
        changes no pixel. Whether a part might now show where it was not drawn is known
        without a test when every part that moved is one the views drew already (the
        parts of an object that is not the same object as before moved; those of the
        same object did not), and at most :data:`FEW_PARTS` moved: testing would cost
        more than drawing a part that left. Otherwise each view must see exactly the
        parts it saw (culled anew), so that what is unseen stays undrawn."""
        posed = index.objects_part
        if posed.looks != objects.looks:
            return False
        keys = [(objects, view.draw_key, scissor, cull) for view, scissor in views]
        recorded_views = []
        for key in keys:
            recorded = self._recorded.get(key)
            if recorded is None:
                return False
            recorded_views.append(recorded)
        if cull and not _still_drawn(objects, posed, recorded_views):
            for (view, scissor), recorded in zip(views, recorded_views, strict=True):
                if self.visible(index, view, scissor).tobytes() != recorded.visible.tobytes():
                    return False
        columns = self._table(index).columns
        # every view's parts data in one go, composed in float64 as relative_columns does
        data = (columns - self._column_offsets(views)).astype(np.float32)
        for position, (key, recorded) in enumerate(zip(keys, recorded_views, strict=True)):
            drawn = (
                data[position]
                if len(recorded.visible) == len(columns)
                else data[position][recorded.visible]
            )
            recorded.parts.upload(GL.GL_ARRAY_BUFFER, drawn)
            del self._recorded[key]
            new_key = (posed, *key[1:])
            earlier = self._recorded.get(new_key)
            if earlier is not None:  # the new pose's own record of the view, made earlier
                self._free(earlier)
            self._recorded[new_key] = recorded
        return True

    def _column_offsets(self, views: Sequence[tuple[View, Rectangle | None]]) -> np.ndarray:
        """``(v, 1, 2, 4, 4)``: each view's :attr:`~mirrorlab.views.View.column_offset`, kept
        for the last sequence of views asked for (a replayed frame's, the same each
        frame)."""
        held = self._offsets
        if held is None or held[0] is not views:
            held = self._offsets = (
                views,
                math3d.read_only(np.array([view.column_offset for view, _ in views])[:, None]),
            )
        return held[1]

    def _spare_for(self, commands: np.ndarray) -> tuple[Buffer, Buffer, np.ndarray | None]:
        """A pair of buffers for a view to record, and the commands the second holds:
        the spare pair that holds ``commands`` already if there is one, else the last
        spare, else a new pair."""
        for position, (_, _, held) in enumerate(self._spare):
            if held is commands:
                return self._spare.pop(position)
        if self._spare:
            return self._spare.pop()
        return Buffer(self.shared.registry), Buffer(self.shared.registry), None

    def end_frame(self) -> None:
        """Free the recorded views the frame just drawn did not draw, their buffers kept
        (up to :data:`SPARE_BUFFERS` pairs) for the views recorded next: what a frame
        holds in GL is what it shows and a few spares, however many views came before (a
        resized window, a moving camera)."""
        for key in [k for k in self._recorded if k not in self._used]:
            self._free(self._recorded.pop(key))
        self._used.clear()

    def _free(self, recorded: RecordedView) -> None:
        """Keep a freed recorded view's buffers as spares (a few), else release them."""
        if len(self._spare) < SPARE_BUFFERS:
            self._spare.append((recorded.parts, recorded.commands, recorded.commands_held))
        else:
            recorded.parts.release()
            recorded.commands.release()

    def draw_plain(
        self,
        scene: Scene,
        reflector: CurvedReflector | PlanarReflector,
        view: View,
        quad=None,
        quad_model: np.ndarray | None = None,
    ) -> int:
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
        program.set_mat4(
            "part", surface_matrix(math3d.normal_matrix(model), reflector.color, textured=False)
        )
        gl.glEnable(GL.GL_CULL_FACE)
        mesh.draw()
        return 1

    def release(self) -> None:
        """Free the recorded views' buffers (the programs and meshes are shared)."""
        for recorded in self._recorded.values():
            recorded.parts.release()
            recorded.commands.release()
        for parts, commands, _ in self._spare:
            parts.release()
            commands.release()
        self._recorded.clear()
        self._spare.clear()
        self._used.clear()
        self._tables.clear()
        self._looks.clear()
        self._programs.clear()  # the shared resources own them
        self._lit.clear()
        self._offsets = None


def _still_drawn(before: ObjectArrays, after: ObjectArrays, views: list[RecordedView]) -> bool:
    """Whether every part of ``after`` that is not where it was in ``before`` (of the same
    parts: its object is not the same object) is one that each of ``views`` draws, and
    at most :data:`FEW_PARTS` moved."""
    moved: list[int] = []
    start = 0
    for old, new, look in zip(before.objects, after.objects, after.looks, strict=True):
        count = len(look)
        if old is not new:
            moved += range(start, start + count)
            if len(moved) > FEW_PARTS:
                return False
        start += count
    for recorded in views:
        if not recorded.drawn.issuperset(moved):
            return False
    return True


def _view_key(index: SceneIndex, view: View, scissor: Rectangle | None) -> tuple:
    """Equal for the same scene index seen through the same view (its
    :attr:`~mirrorlab.views.View.draw_key`) and scissor."""
    return (index.objects_part, view.draw_key, scissor)


def draw_layout(table: PartTable, visible: np.ndarray) -> Layout:
    """How the ``visible`` parts ``(k,)`` of ``table`` are drawn, in order: the indirect
    commands ``(c, 5)`` uint32 and their :data:`Run` s (:func:`indirect_commands`). Kept
    by the table for the last few sets of parts (read-only): a moving part makes a new
    pose every frame, with its layout unchanged."""
    key = visible.tobytes()
    held = table.layouts.get(key)
    if held is not None:
        table.layouts.move_to_end(key)
        return held
    commands, runs = indirect_commands(table, visible)
    layout = table.layouts[key] = (math3d.read_only(commands), runs)
    while len(table.layouts) > LAYOUTS_KEPT:
        table.layouts.popitem(last=False)
    return layout


def indirect_commands(
    table: PartTable, visible: np.ndarray
) -> tuple[np.ndarray, tuple[tuple[TextureSource | None, int, int], ...]]:
    """The indirect commands ``(c, 5)`` uint32 that draw the ``visible`` parts of
    ``table`` in order (part k of them being instance k of the whole: its data is entry k
    of the parts buffer), and the runs of commands that share a texture, each (texture
    or None, first command, count). Consecutive parts of one mesh within a run are one
    command of as many instances: instances are drawn in order, one after the other,
    so the picture is that of a draw each. (A few parts are put together one by one:
    numpy's calls would cost more; the result is the same.)"""
    if len(visible) <= FEW_PARTS:
        return _few_indirect_commands(table, visible)
    runs = texture_runs(table.texture_ids[visible])
    meshes = table.mesh_ids[visible]
    starts = np.zeros(len(visible), dtype=bool)
    starts[0] = True
    starts[1:] = meshes[1:] != meshes[:-1]
    starts[[first for _, first, _ in runs]] = True
    first_part = np.flatnonzero(starts)
    instances = np.diff(np.append(first_part, len(visible)))
    ranges = table.ranges[visible[first_part]]
    commands = np.zeros((len(first_part), 5), dtype=np.uint32)
    commands[:, 0] = ranges[:, 1]  # index count
    commands[:, 1] = instances
    commands[:, 2] = ranges[:, 0]  # first index
    commands[:, 3] = ranges[:, 2]  # base vertex
    commands[:, 4] = first_part  # base instance: where the parts' data starts
    command_of = np.searchsorted(first_part, [first for _, first, _ in runs])
    ends = np.append(command_of[1:], len(first_part))
    return commands, tuple(
        (table.worn[tid] if tid >= 0 else None, int(a), int(b - a))
        for (tid, _, _), a, b in zip(runs, command_of, ends, strict=True)
    )
