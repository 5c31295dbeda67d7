"""Which passes a frame needs, and why: simulate only the effects the scene calls for.

:func:`plan_frame` takes a scene, the viewer, the frame size and what each reflector's
textures hold now, and returns the frame's ordered passes, each with its reason:
captures first (a capture's own sub-captures before it), then the camera pass. For every
view it also says how each reflector is drawn there (:class:`ReflectorDraw`): not at
all (out of view, facing away), as a plain surface (bounces used up), with its map, with
a capture, or, for a technique that draws inline (the stencil mirror), with the plan of
the world seen through it, drawn in place.

Where a technique's cameras are comes from its registry entry
(:attr:`mirrorlab.techniques.Technique.capture_camera`): a :data:`CaptureCamera`
function, given the reflector, the view it is seen in and what the planner offers
(:class:`CaptureContext`), returns the cameras (:class:`CaptureCameras`). The planner
plans a capture pass over them, or, for an inline technique, nests the first camera's
plan in the draw; it knows no technique by name.

The plan is lossless: a pass is skipped, and a reflector left undrawn, only where that
cannot change a pixel. Whether a reflector can show in a view is decided from its
footprint (:mod:`mirrorlab.footprint`: a planar mirror clipped against the view volume, a
curved one's bounding sphere by its projected ellipse), which errs large. The one lossy
rule, drawing a reflector that covers fewer than ``tiny_pixels`` pixels plain instead of
capturing it, is off unless asked for.

Reflections of reflections: a reflector seen in another's capture is drawn with a
texture one bounce lower, made for that capture's camera; at bounce 0 it is plain. A
reflector never appears in its own capture. Each capture key (what was drawn, from
where, at which bounce, of which scene) gets a texture slot of its own within a frame;
a slot that already holds the key from an earlier frame is reused, not drawn again.

Pure numpy; the renderer (:mod:`mirrorlab.renderer`) runs what this decides.
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Literal, NamedTuple, Protocol

import numpy as np

from mirrorlab import bounds, culling
from mirrorlab.culling import OUTSIDE_REASONS
from mirrorlab.footprint import Footprint, full_screen, polygon_footprint, sphere_footprint
from mirrorlab.scene.model import (
    FOOTPRINT_STEP,
    FOOTPRINT_TEXTURE,
    CurvedReflector,
    PlanarReflector,
    Reflector,
    Scene,
)
from mirrorlab.techniques import technique
from mirrorlab.views import View, camera_view, is_orthographic

TINY_PIXELS = 0.0
"""The default of the lossy small-reflector rule: off. Given a positive number, a
reflector whose footprint may cover fewer pixels than that is drawn plain, with no
capture, which changes those pixels (16 saves the captures of reflectors seen from very
far away)."""

DrawMode = Literal["hidden", "back", "plain", "map", "texture", "inline", "screen"]
"""``hidden``: not drawn (out of view); ``back``: only a planar mirror's backing shows;
``plain``: a lit surface; ``map``: with its map; ``texture``: with its capture;
``inline``: the world seen through it (its ``nested`` plan), drawn in place; ``screen``:
from the view's own frame as its target holds it then (a ``screen`` texture, copied at
the draw), with what the frame does not hold from its ``fallback``. The last four are
the technique's own draw (:attr:`ReflectorDraw.own`), which its registry entry places
before or after the view's objects."""
OWN_MODES = ("map", "texture", "inline", "screen")
"""The modes of :data:`DrawMode` in which a reflector is drawn by its technique's own
draw, not as a surface like any other."""


@dataclass(frozen=True, eq=False)
class ContentKey:
    """What a capture shows but the viewer (:meth:`mirrorlab.scene.model.Scene.content_key`:
    background, ambient, lights, objects, reflectors, bounces), as part of a texture's
    key: equal when the parts are, hashed by a ``digest`` worked out once (a scene of a
    thousand objects is not hashed again for every capture of every frame)."""

    parts: tuple
    digest: int

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ContentKey) and (
            self is other or (self.digest == other.digest and self.parts == other.parts)
        )

    def __hash__(self) -> int:
        return self.digest

    def __repr__(self) -> str:
        return f"ContentKey(digest={self.digest})"


def content_key(scene: Scene, index: bounds.SceneIndex) -> ContentKey:
    """``scene``'s :class:`ContentKey` (``index`` is its scene index)."""
    background, ambient, lights, objects, reflectors, bounces = scene.content_key()
    return ContentKey(
        (background, ambient, lights, objects, reflectors, bounces),
        hash(
            (
                bounds.hash_of(background),
                ambient,
                bounds.hash_of(lights),
                bounces,
                index.objects_part.digest,
                index.reflectors_part.digest,
            )
        ),
    )


@dataclass(frozen=True)
class PlannedPass:
    """One pass of a frame: ``name`` (``capture``, ``bake`` or ``camera``), the
    ``reflector`` it serves and its ``technique``, the ``bounce`` whose texture it makes,
    the view it is made ``for``, whether it ``runs`` and the ``reason`` in words.
    ``views`` are the capture's cameras, each with its :class:`ViewPlan`; ``slot`` the
    texture slot it fills."""

    name: str
    runs: bool
    reason: str
    reflector: str | None = None
    technique: str | None = None
    bounce: int = 0
    for_view: str = ""
    slot: int = 0
    key: tuple = ()
    views: tuple[ViewPlan, ...] = ()

    def with_key(self, key: tuple) -> PlannedPass:
        """The same pass for a texture of ``key`` (made by copying its fields: a replayed
        frame's plan is made this way every frame)."""
        made = object.__new__(PlannedPass)
        made.__dict__.update(self.__dict__, key=key)
        return made

    def describe(self) -> str:
        what = (
            self.name
            if self.reflector is None
            else (
                f"{self.name} {self.reflector} ({self.technique}, bounce {self.bounce}, "
                f"for {self.for_view})"
            )
        )
        return f"{'run ' if self.runs else 'skip'} {what}: {self.reason}"

    def as_dict(self) -> dict:
        return {
            "pass": self.name,
            "runs": self.runs,
            "reason": self.reason,
            "reflector": self.reflector,
            "technique": self.technique,
            "bounce": self.bounce,
            "for": self.for_view,
        }


@dataclass(frozen=True)
class ReflectorDraw:
    """How ``reflector`` is drawn in one view: ``mode`` (see :data:`DrawMode`), the
    texture ``slot`` it samples, the capture ``source`` view (its technique's first
    capture camera: a reflected capture's, for its projective lookup), for an inline
    draw the ``nested`` plan of the world seen through it, and the ``reason``;
    ``footprint`` where it can show in the view (:mod:`mirrorlab.footprint`; None where
    it was not needed). A technique with a probe (its entry's ``probe``) gets its
    probe's draw in the same view as ``fallback`` (None: no probe). A view that shows a
    reflector drawn from the view's own frame (``screen``) is drawn whole: its plan has
    no scissor."""

    reflector: Reflector
    mode: DrawMode
    reason: str
    slot: int = 0
    source: View | None = None
    nested: ViewPlan | None = None
    footprint: Footprint | None = field(default=None, compare=False, repr=False)
    fallback: ReflectorDraw | None = None

    @property
    def own(self) -> bool:
        """Whether the technique's own draw runs (its map, its capture or its nested view:
        :data:`OWN_MODES`), which its registry entry orders
        (:attr:`~mirrorlab.techniques.Technique.draws_after_objects`); a plain surface, a
        backing or nothing is drawn as any surface is."""
        return self.mode in OWN_MODES


Rectangle = tuple[int, int, int, int]
"""``(x, y, width, height)`` in GL window pixels (from the bottom left), for glScissor."""


class CaptureCameras(NamedTuple):
    """Where a technique looks from, for one reflector seen in one view (what a
    :data:`CaptureCamera` gives).

    ``cameras``: the views it draws, in order (one for a planar capture or an inline
    draw, six cube faces, ...); ``scissors``: for each, the part of its target whose
    pixels are ever read (None: all of it); ``where``: what of the cameras the texture
    depends on besides what the scene shows (hashable: a viewer-following camera's
    :attr:`~mirrorlab.views.View.key`, a fixed camera's texture size), part of the
    texture's key, so a capture is reused while it is the same (an inline draw makes no
    texture: None); ``content``: what the capture shows (None: the scene's
    :attr:`CaptureContext.content`)."""

    cameras: tuple[View, ...]
    scissors: tuple[Rectangle | None, ...]
    where: Hashable
    content: ContentKey | None = None


class CaptureContext(Protocol):
    """What the planner offers a technique's :data:`CaptureCamera`. A camera function
    learns where the scene's objects are only through :meth:`reach` and
    :meth:`depth_range`, which tell the planner that its plan depends on that (a plan
    that does not is reused for the next pose of the objects,
    :class:`PlanMemo`)."""

    use_plan: bool
    """False with ``--no-plan``: every pass runs and nothing is scissored."""
    content: ContentKey
    """What the scene shows (its capture content)."""

    def texture_size(
        self, reflector: PlanarReflector, view: View, footprint: Footprint | None
    ) -> tuple[int, int]:
        """The (width, height) of a planar reflector's capture texture seen in ``view``."""
        ...

    def reach(self, eye: np.ndarray) -> float:
        """How far from ``eye`` ``(3,)`` the scene extends (world units)."""
        ...

    def depth_range(self, reflector: CurvedReflector) -> tuple[float, float]:
        """Near and far clip distances of cameras at ``reflector``'s capture centre that
        see the whole scene but the reflector (world units)."""
        ...

    def own_content(self, reflector: CurvedReflector) -> ContentKey:
        """What a capture of ``reflector`` shows, its own lookup's settings left out."""
        ...


CaptureCamera = Callable[
    [Reflector, View, Footprint | None, Rectangle | None, CaptureContext],
    CaptureCameras | None,
]
"""A technique's capture camera (its registry entry's ``capture_camera``):
``(reflector, view, footprint, scissor, context) -> CaptureCameras or None``, for
``reflector`` seen in ``view`` (``footprint``: where it shows there, None when not
worked out; ``scissor``: the part of ``view`` whose pixels matter, None: all). None
when it has no camera from there (the reflector is drawn plain). Numpy only."""


@dataclass(frozen=True, eq=False)
class ViewPlan:
    """A view and how each reflector (but the ``excluded`` one) is drawn in it.

    ``shown``: the reflectors that are drawn there (in the scene's order); ``hidden``
    the positions in the scene's reflectors of those that are not, each with a reason
    code of ``HIDDEN_REASONS``, kept as arrays so that an unseen reflector costs a plan
    nothing (:attr:`draws` spells them out on demand). ``scissor``: the part of the
    view's target whose pixels matter (a reflected capture's glass, the glass of the
    stencil mirror the view is seen through), None for all of it; what lies outside it
    need not be rasterised.
    """

    view: View
    shown: tuple[ReflectorDraw, ...]
    excluded: str | None = None
    reflectors: tuple[Reflector, ...] = ()
    hidden: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    hidden_codes: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int8))
    scissor: Rectangle | None = None

    @cached_property
    def draws(self) -> tuple[ReflectorDraw, ...]:
        """Every reflector's draw but the excluded one's, in the scene's order, the
        hidden ones as ``hidden`` draws with their reasons."""
        if not len(self.hidden):
            return self.shown
        hidden = {
            int(i): ReflectorDraw(self.reflectors[i], "hidden", HIDDEN_REASONS[int(code)])
            for i, code in zip(self.hidden, self.hidden_codes, strict=True)
        }
        shown = iter(self.shown)
        return tuple(
            hidden[i] if i in hidden else next(shown)
            for i, reflector in enumerate(self.reflectors)
            if reflector.name != self.excluded
        )


@dataclass
class TextureState:
    """What the renderer's textures hold: ``(reflector, slot) -> key`` of the capture or
    bake in it. The planner reads it; the renderer records each capture it runs."""

    held: dict[tuple[str, int], tuple] = field(default_factory=dict)

    def record(self, step: PlannedPass) -> None:
        assert step.reflector is not None
        self.held[(step.reflector, step.slot)] = step.key

    def clear(self) -> None:
        self.held.clear()


@dataclass(frozen=True)
class FramePlan:
    """The passes of one frame in the order they run, and the camera's :class:`ViewPlan`."""

    passes: tuple[PlannedPass, ...]
    top: ViewPlan

    @property
    def ran(self) -> list[PlannedPass]:
        return [p for p in self.passes if p.runs]

    @property
    def skipped(self) -> list[PlannedPass]:
        return [p for p in self.passes if not p.runs]

    def describe(self) -> list[str]:
        lines = [p.describe() for p in self.passes]
        lines += [
            f"     draw {d.reflector.name} in camera: {d.mode} ({d.reason})" for d in self.top.draws
        ]
        return lines


def plan_frame(
    scene: Scene,
    size: tuple[int, int],
    state: TextureState | None = None,
    use_plan: bool = True,
    tiny_pixels: float = TINY_PIXELS,
    view: View | None = None,
) -> FramePlan:
    """The passes for one frame of ``scene`` seen by its camera (or ``view``) at ``size``
    (width, height) pixels, given what ``state`` says the textures hold.

    With ``use_plan`` False every pass runs: every reflector is captured at every bounce
    for every view, nothing is reused, no reflector is drawn plain for being small and
    nothing is scissored (the renderer culls no object either), for comparison: the
    frame comes out the same, pixel for pixel, unless ``tiny_pixels`` is positive.
    ``tiny_pixels`` above 0 turns on the lossy rule: a reflector whose footprint may
    cover fewer pixels than that is drawn plain.
    """
    return _plan(
        _Planner(scene, state or TextureState(), use_plan, tiny_pixels if use_plan else 0.0),
        size,
        view,
    )


def _plan(planner: _Planner, size: tuple[int, int], view: View | None) -> FramePlan:
    scene = planner.scene
    top_view = view or camera_view(scene.camera, size)
    top = planner.plan_view(top_view, scene.max_bounces, None)
    camera = PlannedPass("camera", True, "the frame itself", for_view="camera")
    return FramePlan(tuple([*planner.passes, camera]), top)


def _plan_fields(scene: Scene) -> tuple:
    """What of ``scene`` but its objects a plan is made from."""
    return (
        scene.camera,
        scene.background,
        scene.ambient,
        scene.lights,
        scene.reflectors,
        scene.max_bounces,
    )


def _shows_content(key: tuple) -> bool:
    """Whether a texture's ``key`` is a capture's that ends with the content it shows."""
    return len(key) == 4 and isinstance(key[3], ContentKey)


def _held_as_seen(state: TextureState, content: ContentKey) -> tuple:
    """What ``state`` holds as a planner sees it for a scene of ``content``: the keys
    of the textures, a capture's content given only as whether it is ``content``
    (the planner compares what it shows with that alone)."""
    return tuple(
        (slot, (*key[:3], key[3] == content) if _shows_content(key) else key)
        for slot, key in state.held.items()
    )


class _Planned(NamedTuple):
    inputs: tuple
    content: ContentKey
    plan: FramePlan
    placed: tuple | None
    """The objects whose places the plan looked at (None: it looked at none but, maybe,
    how far they reach)."""
    reach: tuple | None
    """The scene's bounding sphere, as :func:`_reach_key` gives it, where the plan
    looked at how far the scene reaches (None: it did not)."""


def _reach_key(index: bounds.SceneIndex) -> tuple:
    center, radius = index.sphere
    return center.tobytes(), radius


class PlanMemo:
    """Plans frames (:func:`plan_frame`, of a scene seen by its camera), keeping the last
    plan with what it was made from. A plan depends on the scene's objects only through
    what its captures show (their content, in the capture keys) and where they are: how
    far the scene reaches, for a view that sees all of it (a ``reflected`` or
    ``stencil`` mirror's), and the nearest one's distance too for a live cube map. So a
    frame whose scene differs from the last one's in its objects alone, with its
    textures holding the same (the last frame's captures, of other content), gets the
    last plan with the new content put into its capture keys, when that plan looked at
    no object's place, or at how far the scene reaches and it reaches as far as before,
    or the objects are the same: the plan the planner would make, without making it (an
    animated robot's frames are planned once, a still scene's too). :attr:`reused` says
    whether the last plan came that way."""

    def __init__(self) -> None:
        self._last: _Planned | None = None
        self.reused = False

    def plan(
        self,
        scene: Scene,
        size: tuple[int, int],
        state: TextureState,
        use_plan: bool = True,
        tiny_pixels: float = TINY_PIXELS,
    ) -> FramePlan:
        """The plan of a frame of ``scene`` at ``size``, given ``state``: the same as
        :func:`plan_frame`'s."""
        index = bounds.scene_index(scene)
        content = content_key(scene, index)
        inputs = (size, use_plan, tiny_pixels, _plan_fields(scene), _held_as_seen(state, content))
        last = self._last
        if (
            last is not None
            and last.inputs == inputs
            and (
                last.placed == scene.objects
                if last.placed is not None
                else last.reach is None or last.reach == _reach_key(index)
            )
        ):
            plan = (
                last.plan
                if last.content == content
                else _with_content(last.plan, last.content, content)
            )
            self._last = _Planned(inputs, content, plan, last.placed, last.reach)
            self.reused = True
            return plan
        planner = _Planner(scene, state, use_plan, tiny_pixels if use_plan else 0.0, content)
        plan = _plan(planner, size, None)
        self._last = _Planned(
            inputs,
            content,
            plan,
            scene.objects if planner.geometry else None,
            _reach_key(index) if planner.reach_used else None,
        )
        self.reused = False
        return plan

    def clear(self) -> None:
        """Forget the last plan."""
        self._last = None
        self.reused = False


def _with_content(plan: FramePlan, old: ContentKey, new: ContentKey) -> FramePlan:
    """``plan`` with the content ``new`` in place of ``old`` in its capture keys."""
    return FramePlan(
        tuple(
            step.with_key((*step.key[:3], new))
            if _shows_content(step.key) and step.key[3] == old
            else step
            for step in plan.passes
        ),
        plan.top,
    )


class _Planner:
    def __init__(
        self,
        scene: Scene,
        state: TextureState,
        use_plan: bool,
        tiny_pixels: float,
        content: ContentKey | None = None,
    ) -> None:
        self.scene = scene
        self.state = state
        self.held: dict[str, list[tuple[int, tuple]]] = {}  # state.held by reflector
        for (name, slot), key in state.held.items():
            self.held.setdefault(name, []).append((slot, key))
        self.use_plan = use_plan
        self.tiny_pixels = tiny_pixels
        self.passes: list[PlannedPass] = []
        self.planned: set[tuple[str, tuple]] = set()  # (reflector, key) of every pass so far
        self.index = bounds.scene_index(scene)
        self.content = content if content is not None else content_key(scene, self.index)
        self.geometry = False
        """Whether the plan looked at where the objects are, beyond how far the scene
        reaches (:attr:`reach_used`)."""
        self.reach_used = False
        """Whether the plan looked at how far the scene reaches (its bounding sphere)."""
        self.assigned: dict[tuple[str, tuple], int] = {}  # this frame's (reflector, key) slots
        self.used: dict[str, set[int]] = {}

    def plan_view(
        self, view: View, bounce: int, excluded: str | None, scissor: Rectangle | None = None
    ) -> ViewPlan:
        """How each reflector (but ``excluded``) is drawn in ``view``: which may show is
        decided for all at once (:func:`visibility`); only those are planned one by
        one."""
        index = self.index
        reflectors = index.reflectors
        if self.use_plan:
            codes, footprints = visibility(index, view, excluded, scissor)
            if scissor is not None and any(
                technique(reflectors[i].technique).texture == "screen"
                for i in (codes <= BACK).nonzero()[0].tolist()
            ):
                # a reflector that reads the view's own frame reads all of it: the view
                # is drawn whole
                scissor = None
                codes, footprints = visibility(index, view, excluded, None)
        else:
            codes, footprints = np.zeros(len(reflectors), dtype=np.int8), {}
            if excluded is not None and excluded in index.names:
                codes[index.names[excluded]] = EXCLUDED
        shown = []
        for i in (codes <= BACK).nonzero()[0].tolist():
            reflector = reflectors[i]
            footprint = footprints.get(i)
            if codes[i] == BACK:
                shown.append(ReflectorDraw(reflector, "back", BACK_REASON, footprint=footprint))
            else:
                shown.append(self.draw(reflector, view, bounce, footprint, scissor))
        hidden = (codes > EXCLUDED).nonzero()[0]
        return ViewPlan(view, tuple(shown), excluded, reflectors, hidden, codes[hidden], scissor)

    def draw(
        self,
        reflector: Reflector,
        view: View,
        bounce: int,
        footprint: Footprint | None = None,
        scissor: Rectangle | None = None,
    ) -> ReflectorDraw:
        """How ``reflector``, which may show in ``view`` (its ``footprint`` there when
        known), is drawn there."""
        entry = technique(reflector.technique)
        if bounce <= 0:
            return ReflectorDraw(
                reflector, "plain", "no bounces left: a plain surface", footprint=footprint
            )
        if self.tiny_pixels > 0 and entry.texture != "static":
            area = (footprint or reflector_footprint(reflector, view)).pixels
            if area < self.tiny_pixels:
                return ReflectorDraw(
                    reflector,
                    "plain",
                    f"covers at most {area:.1f} pixels "
                    f"(under {self.tiny_pixels:g}; lossy): drawn plain, no "
                    f"capture",
                    footprint=footprint,
                )
        if entry.texture == "static":
            return ReflectorDraw(reflector, "map", "its static map", footprint=footprint)
        if entry.texture == "baked":
            assert isinstance(reflector, CurvedReflector)  # baked maps are curved techniques
            slot = self.bake(reflector, view)
            return ReflectorDraw(
                reflector, "map", "its sphere map for this view", slot=slot, footprint=footprint
            )
        fallback = None
        if entry.probe:
            probe = entry.probe_function()(reflector)
            if probe is not None:
                fallback = self.draw(probe, view, bounce, footprint, scissor)
        if entry.texture == "screen":
            return ReflectorDraw(
                reflector,
                "screen",
                "the view's own frame, what it does not hold from "
                + ("its probe" if fallback is not None else "the background colour"),
                footprint=footprint,
                fallback=fallback,
            )
        found = entry.capture_function()(reflector, view, footprint, scissor, self)
        if found is None:
            return ReflectorDraw(
                reflector, "plain", "no capture camera from here", footprint=footprint
            )
        source = found.cameras[0]
        if entry.draws_inline:
            nested = self.plan_view(source, bounce - 1, reflector.name, found.scissors[0])
            return ReflectorDraw(
                reflector,
                "inline",
                "the world seen in it, drawn in place",
                nested=nested,
                footprint=footprint,
            )
        slot = self.capture(reflector, view, bounce, found, entry.texture)
        return ReflectorDraw(
            reflector,
            "texture",
            "its capture",
            slot=slot,
            source=source,
            footprint=footprint,
            fallback=fallback,
        )

    # ------------------------------------------------------------- textures

    def slot_for(self, reflector: str, key: tuple) -> tuple[int, bool]:
        """The slot for ``key`` and whether it already holds it (so nothing need run)."""
        if (reflector, key) in self.assigned:
            return self.assigned[(reflector, key)], True
        used = self.used.setdefault(reflector, set())
        held = None
        if self.use_plan:
            held = next((slot for slot, k in self.held.get(reflector, ()) if k == key), None)
        if held is not None and held not in used:
            slot, fresh = held, True
        else:
            slot = next(i for i in range(len(used) + 1) if i not in used)
            fresh = False
        used.add(slot)
        self.assigned[(reflector, key)] = slot
        return slot, fresh

    def bake(self, reflector: CurvedReflector, view: View) -> int:
        if reflector.source is not None:
            key: tuple = ("picture", str(reflector.source), reflector.map_size)
            reason = "the picture is the map, as it is"
        else:
            rotation = tuple(np.round(np.asarray(view.view)[:3, :3], 12).ravel())
            key = ("bake", self.scene.background, reflector.map_size, rotation)
            reason = "the view turned (sphere maps live in eye space)"
        slot, held = self.slot_for(reflector.name, key)
        if held and (reflector.name, key) in self.planned:
            return slot
        runs = not held
        self.add(
            PlannedPass(
                "bake",
                runs,
                reason if runs else "the map for this view is already made",
                reflector.name,
                reflector.technique,
                0,
                view.label,
                slot,
                key,
            )
        )
        return slot

    def reach(self, eye: np.ndarray) -> float:
        """How far from ``eye`` ``(3,)`` the scene extends (:func:`bounds.reach`):
        reflections see the whole scene, whatever the camera's far plane (the truth's
        definition). The plan then depends on it."""
        self.reach_used = True
        return bounds.reach(self.scene, eye)

    def depth_range(self, reflector: CurvedReflector) -> tuple[float, float]:
        """Near and far clip distances of cameras at ``reflector``'s capture centre
        (:func:`bounds.cube_depth_range`). The plan then depends on where the objects
        are."""
        self.geometry = True
        return bounds.cube_depth_range(self.scene, reflector)

    def capture(
        self,
        reflector: Reflector,
        view: View,
        bounce: int,
        found: CaptureCameras,
        texture: str | None,
    ) -> int:
        """Plan the capture of ``reflector`` (seen in ``view``) at ``bounce`` from the
        cameras ``found`` (its technique's, whose texture is of kind ``texture``); its
        slot."""
        key = (
            texture,
            bounce,
            found.where,
            self.content if found.content is None else found.content,
        )
        slot, held = self.slot_for(reflector.name, key)
        if held and (reflector.name, key) in self.planned:
            return slot  # already captured earlier in this frame
        if held:
            self.add(
                PlannedPass(
                    "capture",
                    False,
                    "nothing it shows changed since it was captured",
                    reflector.name,
                    reflector.technique,
                    bounce,
                    view.label,
                    slot,
                    key,
                )
            )
            return slot
        plans = tuple(
            self.plan_view(camera, bounce - 1, reflector.name, scissor)
            for camera, scissor in zip(found.cameras, found.scissors, strict=True)
        )
        reason = (
            "every pass runs (--no-plan)"
            if not self.use_plan
            else self.what_changed(reflector.name, key)
        )
        self.add(
            PlannedPass(
                "capture",
                True,
                reason,
                reflector.name,
                reflector.technique,
                bounce,
                view.label,
                slot,
                key,
                plans,
            )
        )
        return slot

    def texture_size(
        self, reflector: PlanarReflector, view: View, footprint: Footprint | None
    ) -> tuple[int, int]:
        """The (width, height) of ``reflector``'s capture texture seen in ``view``: its
        ``texture_size`` square, the view's size when it gives none, or with
        ``"footprint"`` the size of the pixel rectangle its glass covers in ``view``,
        rounded up to a multiple of :data:`~mirrorlab.scene.model.FOOTPRINT_STEP`."""
        size = reflector.texture_size
        if size == FOOTPRINT_TEXTURE:
            rectangle = (footprint or reflector_footprint(reflector, view)).bounds
            if rectangle is None:
                return view.size
            step = FOOTPRINT_STEP
            return (-(-rectangle[2] // step) * step, -(-rectangle[3] // step) * step)
        return (size, size) if isinstance(size, int) else view.size

    def add(self, step: PlannedPass) -> None:
        self.passes.append(step)
        if step.reflector is not None:
            self.planned.add((step.reflector, step.key))

    def own_content(self, reflector: CurvedReflector) -> ContentKey:
        """What a live cube map of ``reflector`` shows: the scene's content, but of the
        reflector's own parallax correction only its kind (a distance search captures
        depths too). A proxy's size or a search's steps change how the map is read, not
        what it holds."""
        if reflector.parallax is None:
            return self.content
        background, ambient, lights, objects, reflectors, bounces = self.content.parts
        own = (replace(reflector, parallax=None), reflector.parallax.kind)
        mine = tuple(own if r.name == reflector.name else r for r in reflectors)
        return ContentKey(
            (background, ambient, lights, objects, mine, bounces),
            hash(
                (background, ambient, lights, bounces, self.index.objects_part.digest, hash(mine))
            ),
        )

    def what_changed(self, reflector: str, key: tuple) -> str:
        """Why a capture must run: what differs from the nearest capture its textures hold
        (keys are (kind, bounce, camera or size, scene content))."""
        held = [k for _, k in self.held.get(reflector, ()) if k[:2] == key[:2]]
        if not held:
            return "its texture is still blank"
        previous = min(held, key=lambda k: (k[2] != key[2]) + (k[3] != key[3]))
        moved, changed = previous[2] != key[2], previous[3] != key[3]
        if key[0] == "viewer":
            what = "the viewer moved" if moved else ""
        else:
            what = "its texture's size changed" if moved else ""
        if changed:
            what = (
                f"{what} and the scene changed"
                if what
                else ("the scene changed since the last capture")
            )
        return what or "its texture was used for another capture"


# --------------------------------------------------------------------------- geometry


BACK_REASON = "seen from behind or edge-on: only its back shows"
SHOWN, BACK, EXCLUDED = 0, 1, 2
"""Codes of :func:`visibility`: may show (plan it), only its back shows (draw the
backing), left out of this view (the reflector whose capture it is); the codes above
these are the reasons it cannot show, :data:`HIDDEN_REASONS`."""
CORNER = EXCLUDED + len(OUTSIDE_REASONS)
CURVED_OUT = CORNER + 1
SCISSORED = CURVED_OUT + 1
HIDDEN_REASONS = (
    "",
    BACK_REASON,
    "",
    *OUTSIDE_REASONS[1:],
    "out of view (past a corner of the view)",
    "out of view",
    "outside the part of the view that is ever seen (its scissor)",
)
"""The reason for each code of :func:`visibility`."""


_VISIBILITY: OrderedDict[tuple, tuple[np.ndarray, dict[int, Footprint]]] = OrderedDict()
VISIBILITY_KEPT = 256
"""Views whose :func:`visibility` is remembered (a still view of still reflectors, or a
capture that follows nothing that moved, is not worked out again)."""


def visibility(
    index: bounds.SceneIndex,
    view: View,
    excluded: str | None = None,
    scissor: Rectangle | None = None,
) -> tuple[np.ndarray, dict[int, Footprint]]:
    """Whether each reflector of ``index`` can show in ``view``: a code for each
    (``(m,)`` int8: :data:`SHOWN`, :data:`BACK`, :data:`EXCLUDED` or a reason of
    :data:`HIDDEN_REASONS`) and the footprint (:func:`reflector_footprint`) of each that
    can, by position.

    In one vectorised step for all: a planar mirror with every corner beyond one side of
    the view, or a curved reflector whose bounding sphere lies beyond one, cannot show;
    a planar mirror the viewer is behind (or edge-on to) shows only its back. Only what
    is left, what reaches into the view, has its footprint worked out one by one (a
    footprint that covers no pixel hides it too). With a ``scissor`` (the part of the
    view's target that matters), the view's sides are the scissor's, and a footprint
    outside it hides a reflector as well. It errs large: a reflector is hidden only where
    drawing it could not change a pixel that matters. The answer is remembered for the
    same reflectors seen through the same view (read-only).
    """
    # the view's draw key holds its matrices, size, clip plane and origin (its eye, when
    # it has one)
    key = (index.reflectors_part, view.draw_key, view.eye is None, excluded, scissor)
    known = _VISIBILITY.get(key)
    if known is not None:
        _VISIBILITY.move_to_end(key)
        return known
    found = _visibility(index, view, excluded, scissor)
    found[0].flags.writeable = False
    _VISIBILITY[key] = found
    while len(_VISIBILITY) > VISIBILITY_KEPT:
        _VISIBILITY.popitem(last=False)
    return found


def _visibility(
    index: bounds.SceneIndex, view: View, excluded: str | None, scissor: Rectangle | None
) -> tuple[np.ndarray, dict[int, Footprint]]:
    codes = np.zeros(len(index.reflectors), dtype=np.int8)
    orthographic = is_orthographic(view.projection)
    sides = (
        (-1.0, 1.0, -1.0, 1.0) if scissor is None else culling.scissor_bounds(view.size, scissor)
    )
    if len(index.planar):
        outside = culling.rows_outside(
            index.corner_rows, view.view_projection, view.clip_plane, orthographic, sides
        )
        front = culling.facing(index.centers, index.normals, view.eye, view.forward)
        codes[index.planar] = np.where(
            outside > 0, outside + EXCLUDED, np.where(front, SHOWN, BACK)
        )
    if len(index.curved):
        inside = culling.spheres_in_view(
            index.sphere_centers, index.sphere_radii, view.view_projection, view.clip_plane
        )
        if scissor is not None:
            inside &= culling.boxes_in_view(
                index.sphere_centers,
                np.repeat(index.sphere_radii[:, None], 3, axis=1),
                culling.scissor_planes(view.view_projection, view.size, scissor),
            )
        codes[index.curved[~inside]] = CURVED_OUT
    if excluded is not None and excluded in index.names:
        codes[index.names[excluded]] = EXCLUDED
    footprints: dict[int, Footprint] = {}
    for i in np.flatnonzero(codes <= BACK):
        reflector = index.reflectors[i]
        footprint = reflector_footprint(reflector, view)
        if footprint.empty:
            codes[i] = CORNER if isinstance(reflector, PlanarReflector) else CURVED_OUT
        elif scissor is not None and not _overlaps(footprint.bounds, scissor):
            codes[i] = SCISSORED
        else:
            footprints[int(i)] = footprint
    return codes, footprints


def hidden_reason(reflector: Reflector, view: View) -> str | None:
    """Why ``reflector`` cannot show in ``view`` (or, for a planar mirror seen from behind
    or edge-on, why only its backing shows), or None when it may: :func:`visibility` for
    this one reflector."""
    codes, _ = visibility(bounds.reflector_index((reflector,)), view)
    return HIDDEN_REASONS[int(codes[0])] or None


def bounding_sphere(reflector: Reflector) -> tuple[np.ndarray, float]:
    """World centre ``(3,)`` and radius of a sphere around the reflector
    (:func:`mirrorlab.bounds.bounding_sphere`)."""
    return bounds.bounding_sphere(reflector)


def reflector_footprint(reflector: Reflector, view: View) -> Footprint:
    """Where ``reflector`` can show in ``view`` (:mod:`mirrorlab.footprint`): a planar
    mirror's quad clipped against the view volume and the view's clip plane, a curved
    reflector's bounding sphere by its projected ellipse; in a warped view, whose
    projection is not a matrix, the whole target. It errs large."""
    if view.warp is not None:
        return full_screen(view.size)
    if isinstance(reflector, PlanarReflector):
        return polygon_footprint(
            reflector.corner_array, view.view_projection, view.size, view.clip_plane
        )
    center, radius = bounding_sphere(reflector)
    return sphere_footprint(center, radius, view.view, view.projection, view.size)


GLASS_MARGIN = 2
"""Pixels a reflected capture's scissor reaches beyond its glass's footprint: the
lookup's bilinear taps reach one texel past the point sampled, and one more for the
rounding of the projective coordinates."""


@functools.lru_cache(maxsize=64)
def glass_scissor(reflector: PlanarReflector, capture: View) -> Rectangle | None:
    """The part of a reflected capture ``capture`` that its mirror ever samples: the
    glass's footprint in the capture, clipped to its sides only (the glass lies on the
    capture's oblique near plane), grown by :data:`GLASS_MARGIN`. None (all of it) when
    the glass has no footprint there. Kept for the last few captures (a still viewer's
    capture view is the same object every frame)."""
    footprint = polygon_footprint(
        reflector.corner_array, capture.view_projection, capture.size, depth=False
    )
    return footprint.rectangle(GLASS_MARGIN)


def _overlaps(first: Rectangle | None, second: Rectangle) -> bool:
    if first is None:
        return False
    overlap = intersect(first, second)
    return overlap is not None and overlap[2] > 0 and overlap[3] > 0


def bounding(first: Rectangle | None, second: Rectangle | None) -> Rectangle | None:
    """The smallest pixel rectangle holding both (None stands for everything)."""
    if first is None or second is None:
        return None
    x0, y0 = min(first[0], second[0]), min(first[1], second[1])
    x1 = max(first[0] + first[2], second[0] + second[2])
    y1 = max(first[1] + first[3], second[1] + second[3])
    return x0, y0, x1 - x0, y1 - y0


def intersect(first: Rectangle | None, second: Rectangle | None) -> Rectangle | None:
    """The overlap of two pixel rectangles (None stands for everything); an empty overlap
    is a rectangle of no width."""
    if first is None:
        return second
    if second is None:
        return first
    x0, y0 = max(first[0], second[0]), max(first[1], second[1])
    x1 = min(first[0] + first[2], second[0] + second[2])
    y1 = min(first[1] + first[3], second[1] + second[3])
    return x0, y0, max(x1 - x0, 0), max(y1 - y0, 0)


def screen_area(reflector: Reflector, view: View) -> float:
    """At most how many pixels ``reflector`` covers in ``view`` (its footprint's
    :attr:`~mirrorlab.footprint.Footprint.pixels`)."""
    return reflector_footprint(reflector, view).pixels
