"""The one renderer: draws any scene, every reflector with its own technique, by running
the frame's plan (:mod:`mirrorlab.plan`).

A :class:`SceneRenderer` is handed a context's resource registry and, each frame, a
target to draw into; it never creates a context or a window (:class:`mirrorlab.Renderer`
does that for headless use, the demo for its window). It keeps GL objects across
frames and scenes: shared meshes, pictures and programs, and one pass per reflector,
made only when a scene has a reflector that needs it and released when no scene
being drawn has it any more.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import nullcontext
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.bounds import ObjectArrays, scene_index
from mirrorlab.draw_path import DrawPath
from mirrorlab.gl.calls import (
    Call,
    for_replay,
    forget_cached_state,
    gl,
    known_state,
    recording,
    replay,
)
from mirrorlab.gl.context import ResourceRegistry, gl_pass, gl_version, require_gl_version
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import RenderTarget, Texture2D, TextureCube
from mirrorlab.passes.base import (
    ReflectorPass,
    ReportsFallback,
    SharedResources,
    apply_view_state,
    gl_state,
    restore_state,
)
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.passes.sky import SkyPass
from mirrorlab.plan import (
    TINY_PIXELS,
    FramePlan,
    PlanMemo,
    Rectangle,
    ReflectorDraw,
    TextureState,
    ViewPlan,
    plan_frame,
)
from mirrorlab.scene.model import (
    Background,
    CurvedReflector,
    DistanceSearch,
    PlanarReflector,
    Reflector,
    Scene,
    Transform,
)
from mirrorlab.techniques import RENDERER_GL_VERSION, technique
from mirrorlab.views import View

if TYPE_CHECKING:
    from mirrorlab.budget.chooser import BudgetChooser, BudgetFrame


@dataclass
class FrameStats:
    """What the last frame did: its plan (passes run and skipped, with reasons), the
    number of draw calls (a multi-draw counts one), the wall time of the frame's GL calls
    in milliseconds (without waiting for the GPU to finish; the budget's choice
    included), and ``parts_drawn``: the object parts drawn, summed over every view of the
    frame (what culling left); under a budget, ``budget``: what it chose and predicted
    (:class:`mirrorlab.budget.chooser.BudgetFrame`)."""

    plan: FramePlan
    draw_calls: int
    milliseconds: float = 0.0
    passes_run: list[str] = field(default_factory=list)
    parts_drawn: int = 0
    budget: BudgetFrame | None = None

    @property
    def ran(self) -> list[str]:
        """``name`` or ``name:reflector`` of every pass that ran, in order."""
        return [p.name if p.reflector is None else f"{p.name}:{p.reflector}" for p in self.plan.ran]

    @property
    def skipped(self) -> list[str]:
        return [
            p.name if p.reflector is None else f"{p.name}:{p.reflector}" for p in self.plan.skipped
        ]


@dataclass(eq=False)
class RecordedFrame:
    """A frame's GL calls from its first pass to its end, made ready to be made again
    (:func:`~mirrorlab.gl.calls.for_replay`), for the frames after it planned the same
    way: what it was drawn into and with (``key``: target, size and options), the GL
    state it started from (``found``), the ``objects``
    (:class:`~mirrorlab.bounds.ObjectArrays`) it drew, the ``views`` it drew them in
    (each with its scissor, as the drawer recorded them) and whether they were culled
    (``cull``), whether its calls draw another pose of those objects once the parts'
    data is sent again (``follows_pose``), and its ``stats``."""

    key: tuple
    found: dict[str, object]
    objects: ObjectArrays
    views: tuple[tuple[View, Rectangle | None], ...]
    cull: bool
    follows_pose: bool
    calls: list
    stats: FrameStats

    def arrays(self) -> list[np.ndarray]:
        """Every numpy array its recorded calls hold (as arguments, however nested): what
        the replay rule (:class:`~mirrorlab.passes.base.ReflectorPass`) says must not
        change while the frame is kept."""
        found: list[np.ndarray] = []
        pending: list[object] = list(self.calls)
        while pending:
            item = pending.pop()
            if isinstance(item, np.ndarray):
                found.append(item)
            elif isinstance(item, (tuple, list)):
                pending.extend(item)
            elif isinstance(item, dict):
                pending.extend(item.values())
        return found


def _drawn_views(plan: FramePlan) -> Iterator[tuple[View, Rectangle | None]]:
    """Each view (with its scissor) the frame of ``plan`` draws the scene's objects in:
    the captures' cameras, the camera's view, and the views nested in any of them (the
    worlds seen in stencil mirrors)."""
    pending = [
        view for step in plan.passes if step.runs and step.name != "camera" for view in step.views
    ]
    pending.append(plan.top)
    while pending:
        view_plan = pending.pop()
        yield view_plan.view, view_plan.scissor
        pending += [draw.nested for draw in view_plan.shown if draw.nested is not None]


def _pass_key(reflector: Reflector, background: Background) -> tuple:
    """What a reflector's pass is made from: everything but where it is (it may move every
    frame; a planar pass places its quad at each draw) and the sizes of a curved one's
    parallax correction (read at each draw; the kind chooses the shader), and the
    background for the maps baked from it; for a technique with a probe, its probe's
    pass key too (the pass makes its probe's pass)."""
    entry = technique(reflector.technique)
    if entry.probe:
        probe = entry.probe_function()(reflector)
        own = _own_pass_key(reflector, background)
        return (own, None if probe is None else _pass_key(probe, background))
    return _own_pass_key(reflector, background)


def _own_pass_key(reflector: Reflector, background: Background) -> tuple:
    if isinstance(reflector, PlanarReflector):
        return (reflector.technique, reflector.capture, None)
    if isinstance(reflector, CurvedReflector):
        parallax = reflector.parallax
        still = replace(reflector, transform=Transform(), parallax=None)
        # a distance search looks up the rays that meet nothing in the background itself
        baked = technique(reflector.technique).texture in ("static", "baked") or isinstance(
            parallax, DistanceSearch
        )
        return (still, None if parallax is None else parallax.kind, background if baked else None)
    return (reflector, None, None)


class SceneRenderer:
    """Runs frame plans: captures and bakes first, then the camera's view. ``draw_path``
    chooses how objects are drawn (:mod:`mirrorlab.passes.scene_draw`): ``auto`` (one
    multi-draw a pass where the context offers it, else a draw call a part),
    ``packed`` or ``per-draw``; the frames are the same.

    A frame leaves GL as it found it: it reads the GL state it changes first and puts it
    back after. ``own_context`` True says nothing but this renderer makes GL calls in its
    context (:class:`mirrorlab.Renderer`'s headless one): the state is then read once, at
    the first frame, and every frame drawn anew puts that back, so none reads it again;
    a replayed frame leaves out the calls that set state to the value the recorded frame
    found it at, so it counts on the last frame's state."""

    def __init__(
        self, registry: ResourceRegistry, draw_path: DrawPath = "auto", own_context: bool = False
    ) -> None:
        self._gl_version = gl_version()
        self.registry = registry
        self.shared = SharedResources(registry)
        self.drawer = SceneDrawer(self.shared, draw_path)
        self.state = TextureState()
        self._scene: Scene | None = None
        self._passes: dict[str, tuple[tuple, ReflectorPass]] = {}
        self._sky: SkyPass | None = None
        self.last_frame: FrameStats | None = None
        self.memo = PlanMemo()
        self._recorded: RecordedFrame | None = None  # the last frame, to draw again
        self._scissor: Rectangle | None = None  # the scissor rectangle set, None: off
        self._cull = True  # whether this frame's views cull objects (not with use_plan off)
        self.own_context = own_context
        self._home: dict[str, object] | None = None  # the state every frame leaves (own_context)
        self.budget_chooser: BudgetChooser | None = None
        """What chooses the reflectors' techniques of a scene with a budget (made at the
        first such frame; set one to choose with another calibration)."""

    @property
    def scene(self) -> Scene:
        """The scene of the frame being drawn (or drawn last)."""
        if self._scene is None:
            raise RuntimeError("the renderer has drawn no scene yet")
        return self._scene

    # ------------------------------------------------------------- passes

    def _pass(self, reflector: Reflector) -> ReflectorPass:
        key = _pass_key(reflector, self.scene.background)
        held = self._passes.get(reflector.name)
        if held is not None and held[0] == key:
            return held[1]
        if held is not None:
            self._drop(reflector.name)
        cls = technique(reflector.technique).load()
        made = cls(self.shared, reflector, self.scene.background)
        self._passes[reflector.name] = (key, made)
        return made

    def _drop(self, name: str) -> None:
        _, old = self._passes.pop(name)
        old.release()
        for held in [k for k in self.state.held if k[0] == name]:
            del self.state.held[held]

    def _sky_for(self, background: Background) -> SkyPass | None:
        if not background.is_environment:
            if self._sky is not None:
                self._sky.release()
                self._sky = None
            return None
        if self._sky is None or self._sky.background != background:
            if self._sky is not None:
                self._sky.release()
            self._sky = SkyPass(self.shared, background)
        return self._sky

    def _same_passes(self, scene: Scene) -> bool:
        """Whether ``scene`` has the reflectors and background of the scene drawn last."""
        return (
            self._scene is not None
            and scene.reflectors is self._scene.reflectors
            and scene.background == self._scene.background
        )

    def _stale_passes(self, scene: Scene) -> list[str]:
        """The reflectors whose passes drawing ``scene`` drops (gone, or made otherwise:
        another technique, say), and with them what their textures held."""
        if self._same_passes(scene):
            return []
        names = {r.name: r for r in scene.reflectors}
        return [
            name
            for name, (key, _) in self._passes.items()
            if name not in names or key != _pass_key(names[name], scene.background)
        ]

    def _use_scene(self, scene: Scene) -> None:
        if self._same_passes(scene):
            self._scene = scene  # the same reflectors: the same passes
            return
        for reflector in scene.reflectors:
            entry = technique(reflector.technique)
            if self._gl_version < entry.gl_version:
                require_gl_version(entry.gl_version, f"technique {entry.name!r}")
        if self._gl_version < RENDERER_GL_VERSION:
            require_gl_version(RENDERER_GL_VERSION, "mirrorlab's renderer (GLSL 3.30)")
        stale = self._stale_passes(scene)
        self._scene = scene
        self._scissor = None
        gl.glDisable(GL.GL_SCISSOR_TEST)  # a pass made for a new scene draws unscissored
        for name in stale:
            self._drop(name)
        with gl_pass("background"):
            self._sky_for(scene.background)

    # ------------------------------------------------------------- frames

    def plan(
        self,
        scene: Scene,
        size: tuple[int, int],
        use_plan: bool = True,
        tiny_pixels: float = TINY_PIXELS,
        view: View | None = None,
    ) -> FramePlan:
        """The plan the next frame of ``scene`` at ``size`` would run (nothing is drawn):
        from what the textures hold but those of the passes drawing it drops."""
        stale = self._stale_passes(scene)
        state = self.state
        if stale:
            state = TextureState({k: v for k, v in state.held.items() if k[0] not in stale})
        return plan_frame(scene, size, state, use_plan, tiny_pixels, view)

    def render(
        self,
        scene: Scene,
        target: RenderTarget,
        use_plan: bool = True,
        tiny_pixels: float = TINY_PIXELS,
        view: View | None = None,
    ) -> FrameStats:
        """Draw one frame of ``scene`` (as seen by its camera, or ``view``) into ``target``.

        ``use_plan`` False runs every pass (see :func:`~mirrorlab.plan.plan_frame`),
        scissors nothing and draws every object in every view, culling none; the frame is
        the same either way. ``tiny_pixels`` above 0 turns on the lossy rule that
        draws a reflector covering fewer pixels than that plain (off by default).

        A frame planned as the last one was (:class:`~mirrorlab.plan.PlanMemo`: a still
        scene, or one whose objects alone moved) into the same target from the same GL
        state is drawn by making the last frame's GL calls again, the objects' new
        places sent first, when the views see the same parts of them.
        """
        start = time.perf_counter()
        size = (int(target.size[0]), int(target.size[1]))
        chosen: BudgetFrame | None = None
        if scene.budget is not None:
            scene, chosen = self.choose(scene, size)
        if not self.own_context:
            found = gl_state()
        elif self._home is None:
            found = self._home = gl_state()
        else:
            found = self._home  # what the last frame left
        self._use_scene(scene)
        if view is not None:
            self.memo.clear()
            plan = plan_frame(scene, size, self.state, use_plan, tiny_pixels, view)
        else:
            plan = self.memo.plan(scene, size, self.state, use_plan, tiny_pixels)
        recorded = self._recorded
        self._recorded = None
        key = (target, size, use_plan, tiny_pixels)
        if (
            recorded is not None
            and self.memo.reused
            and recorded.key == key
            and (recorded.found is found or recorded.found == found)
            and self._replay(recorded, scene, plan, start)
        ):
            self._recorded = recorded
            assert self.last_frame is not None
            self.last_frame.budget = chosen
            return self.last_frame
        # Recording costs a wrapper around each call: only a frame planned as the last
        # one was, which the next one may be too, pays it.
        recorded_calls: list[Call] | None = [] if view is None and self.memo.reused else None
        stats = self._run(scene, plan, target, found, start, use_plan, recorded_calls)
        stats.budget = chosen
        if recorded_calls is not None:
            views = tuple(_drawn_views(plan))
            objects = scene_index(scene).objects_part
            self._recorded = RecordedFrame(
                key,
                found,
                objects,
                views,
                use_plan,
                self.drawer.follows_pose(objects, views, use_plan),
                for_replay(recorded_calls, known_state(found)),
                stats,
            )
        return stats

    def choose(self, scene: Scene, size: tuple[int, int]) -> tuple[Scene, BudgetFrame]:
        """``scene`` (which has a budget) with each reflector set to what the budget
        chooses for this frame at ``size`` (:mod:`mirrorlab.budget`), and the choice; the
        choice is kept for the next frames (steady choices)."""
        if self.budget_chooser is None:
            from mirrorlab.budget.chooser import BudgetChooser

            self.budget_chooser = BudgetChooser()
        return self.budget_chooser.choose(scene, size)

    def _replay(self, recorded: RecordedFrame, scene: Scene, plan: FramePlan, start: float) -> bool:
        """Draw ``recorded``'s frame again for ``scene``, whose ``plan`` is the one it was
        drawn with but for what its captures show: False (nothing drawn) when the objects
        moved and its views see other parts of them, or its calls cannot follow them."""
        index = scene_index(scene)
        objects = index.objects_part
        if objects is not recorded.objects:
            if not recorded.follows_pose or not self.drawer.repose(
                recorded.objects, index, recorded.views, recorded.cull
            ):
                return False
            recorded.objects = objects
        try:
            with gl_pass("frame (replayed)"):
                replay(recorded.calls)
        except BaseException:
            self.state.clear()
            self.memo.clear()
            forget_cached_state()  # the calls may have stopped partway
            raise
        for step in plan.passes:
            if step.runs and step.name != "camera":
                self.state.record(step)
        stats = recorded.stats
        self.last_frame = FrameStats(
            plan,
            stats.draw_calls,
            (time.perf_counter() - start) * 1e3,
            stats.passes_run,
            stats.parts_drawn,
        )
        return True

    def _run(
        self,
        scene: Scene,
        plan: FramePlan,
        target: RenderTarget,
        found: dict[str, object],
        start: float,
        use_plan: bool,
        recorded_calls: list[Call] | None = None,
    ) -> FrameStats:
        """Run the frame's plan: with a list ``recorded_calls``, record into it the GL
        calls made through mirrorlab's layer (:mod:`mirrorlab.gl.calls`) from the first
        pass on (the views' data, sent before, is not in them)."""
        self._scissor = None
        self._cull = use_plan
        self.drawer.parts_drawn = 0
        draws = 0
        index = scene_index(scene)
        try:
            self.drawer.prepare(scene, _drawn_views(plan), use_plan)
            with nullcontext() if recorded_calls is None else recording(recorded_calls):
                try:
                    gl.glDisable(GL.GL_SCISSOR_TEST)  # from the caller's state
                    for step in plan.passes:
                        if not step.runs or step.name == "camera":
                            continue
                        assert step.reflector is not None
                        reflector = index.reflectors[index.names[step.reflector]]
                        with gl_pass(f"{step.name}:{step.reflector}"):
                            draws += self._pass(reflector).update(step, reflector, self, target)
                        self.state.record(step)
                    with gl_pass("camera"):
                        draws += self.draw_view(plan.top, target)
                finally:
                    restore_state(found)
        except BaseException:
            # What a failed pass left half made cannot be trusted by the next frame.
            self.state.clear()
            self.memo.clear()
            forget_cached_state()
            raise
        finally:
            self.drawer.end_frame()
        self.last_frame = FrameStats(
            plan, draws, (time.perf_counter() - start) * 1e3, parts_drawn=self.drawer.parts_drawn
        )
        return self.last_frame

    def draw_view(
        self,
        plan: ViewPlan,
        target: RenderTarget,
        stencil_level: int = 0,
        cleared: Rectangle | None = None,
    ) -> int:
        """Draw ``plan``'s view into ``target``: the whole target at ``stencil_level`` 0
        (cleared first: all of it, or the pixel rectangle ``cleared`` alone, which must
        hold the view's scissor), else only where a stencil mirror marked that level.
        Returns the number of draw calls."""
        scene = self.scene
        view = plan.view
        outer = self._scissor
        if stencil_level == 0:
            target.bind()
            gl.glViewport(0, 0, *view.size)
            gl.glStencilMask(0xFF)
            gl.glClearColor(*scene.background.color, 1.0)
            gl.glClearStencil(0)
            self._set_scissor(cleared)  # whatever is drawn, all of it is cleared
            gl.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT | GL.GL_STENCIL_BUFFER_BIT)
        # Only the pixels that matter are rasterised (a capture's glass, a stencil
        # mirror's): a scissor cannot change a pixel the plan says is ever seen.
        self._set_scissor(plan.scissor)
        try:
            return self._draw_view(plan, target, stencil_level)
        finally:
            self._set_scissor(outer)

    def _draw_view(self, plan: ViewPlan, target: RenderTarget, stencil_level: int) -> int:
        scene = self.scene
        view = plan.view
        apply_view_state(view, stencil_level)
        draws = 0
        sky = self._sky_for(scene.background)
        if sky is not None:
            draws += sky.run(view)
            apply_view_state(view, stencil_level)
        # The reflectors before the objects: an object's pixels behind a mirror then fail
        # the depth test before they are shaded, not after (the camera pass of the lab
        # scene took a sixth less). Opaque surfaces under GL_LESS give the same pixels in
        # any order, but for a depth tie between a reflector and an object. A technique
        # whose entry says so draws after them (a stencil mirror marks only what the
        # objects leave showing).
        later = []
        for draw in plan.shown:
            if draw.own and technique(draw.reflector.technique).draws_after_objects:
                later.append(draw)
                continue
            draws += self._pass(draw.reflector).draw(draw, view, self, target, stencil_level)
        if len(later) < len(plan.shown):
            apply_view_state(view, stencil_level)
        draws += self.drawer.draw(scene, view, plan.scissor, cull=self._cull)
        for draw in later:
            draws += self._pass(draw.reflector).draw(draw, view, self, target, stencil_level)
        return draws

    def _set_scissor(self, rectangle: Rectangle | None) -> None:
        if rectangle == self._scissor:
            return
        if rectangle is None:
            gl.glDisable(GL.GL_SCISSOR_TEST)
        else:
            gl.glEnable(GL.GL_SCISSOR_TEST)
            gl.glScissor(*rectangle)
        self._scissor = rectangle

    def release(self) -> None:
        """Free every GL object the renderer made. Call with its context current."""
        self._recorded = None
        for name in list(self._passes):
            self._drop(name)
        if self._sky is not None:
            self._sky.release()
            self._sky = None
        self.drawer.release()
        self.shared.release()
        self.state.clear()
        self.memo.clear()
        self._home = None

    @property
    def recorded_frame(self) -> RecordedFrame | None:
        """The frame the next one may be drawn again from (None: none is kept)."""
        return self._recorded

    def shown_texture(self, draw: ReflectorDraw) -> Texture2D | TextureCube | None:
        """The texture the last frame's ``draw`` sampled (its pass's
        :meth:`~mirrorlab.passes.base.ReflectorPass.shown_texture`), for a viewer to look
        at; None where it sampled none. Looking changes nothing: the frame is still
        replayed."""
        held = self._passes.get(draw.reflector.name)
        return None if held is None else held[1].shown_texture(draw)

    def drawn_pass(self, draw: ReflectorDraw) -> ReflectorPass | None:
        """The pass that drew ``draw`` (one of the last frame's draws), for a reader of
        what it made; None where the renderer holds none for that reflector. Looking
        changes nothing: the frame is still replayed."""
        held = self._passes.get(draw.reflector.name)
        return None if held is None else held[1]

    def fallback_mask(self) -> np.ndarray | None:
        """Which pixels of the last frame the reflectors' techniques filled from their
        fallback (their probe) instead of their own method: ``(h, w)`` bool over the
        frame, row 0 at the top, the union over the reflectors drawn in the frame's own
        view whose pass reports it
        (:class:`~mirrorlab.passes.base.ReportsFallback`). None where no reflector drawn
        there has a fallback (every shipped technique but those that fall back). Looking
        changes nothing: the frame is still replayed."""
        if self.last_frame is None:
            return None
        top = self.last_frame.plan.top
        union: np.ndarray | None = None
        for draw in top.draws:
            held = self._passes.get(draw.reflector.name)
            if held is None or not isinstance(held[1], ReportsFallback):
                continue
            mask = held[1].fallback_mask(draw, top.view)
            if mask is not None:
                union = mask.copy() if union is None else union | mask
        return union

    def pass_for(self, name: str) -> ReflectorPass:
        """The pass of the current scene's reflector ``name`` (for checks and the demo).
        What a caller may change in it, the next frame draws: it is not replayed."""
        self._recorded = None
        return self._pass(self.scene.reflector(name))
