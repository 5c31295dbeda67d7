"""Which passes a frame needs, and why: simulate only the effects the scene calls for.

:func:`plan_frame` takes a scene, the viewer, the frame size and what each reflector's
textures hold now, and returns the frame's ordered passes, each with its reason:
captures first (a capture's own sub-captures before it), then the camera pass. For every
view it also says how each reflector is drawn there (:class:`ReflectorDraw`): not at
all (out of view, facing away), as a plain surface (bounces used up), with its map, with
a capture, or, for a stencil mirror, as the world seen through it.

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

from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from mirrorlab import bounds, math3d
from mirrorlab.footprint import Footprint, polygon_footprint, sphere_footprint
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Reflector, Scene
from mirrorlab.techniques import technique
from mirrorlab.views import (
    View,
    camera_view,
    cube_face_views,
    is_orthographic,
    ortho_capture_view,
    reflected_capture_view,
    stencil_view,
)

TINY_PIXELS = 0.0
"""The default of the lossy small-reflector rule: off. Given a positive number, a
reflector whose footprint may cover fewer pixels than that is drawn plain, with no
capture, which changes those pixels (16 saves the captures of reflectors seen from very
far away)."""

DrawMode = Literal["hidden", "back", "plain", "map", "texture", "stencil"]
"""``hidden``: not drawn (out of view); ``back``: only a planar mirror's backing shows;
``plain``: a lit surface; ``map``: with its map; ``texture``: with its capture;
``stencil``: the world seen through it, drawn in place."""


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

    def describe(self) -> str:
        what = self.name if self.reflector is None else (
            f"{self.name} {self.reflector} ({self.technique}, bounce {self.bounce}, "
            f"for {self.for_view})")
        return f"{'run ' if self.runs else 'skip'} {what}: {self.reason}"

    def as_dict(self) -> dict:
        return {"pass": self.name, "runs": self.runs, "reason": self.reason,
                "reflector": self.reflector, "technique": self.technique,
                "bounce": self.bounce, "for": self.for_view}


@dataclass(frozen=True)
class ReflectorDraw:
    """How ``reflector`` is drawn in one view: ``mode`` (see :data:`DrawMode`), the
    texture ``slot`` it samples, the capture ``source`` view (a reflected capture's
    camera, for its projective lookup), the ``nested`` plan of a stencil mirror's
    world, and the ``reason``."""

    reflector: Reflector
    mode: DrawMode
    reason: str
    slot: int = 0
    source: View | None = None
    nested: ViewPlan | None = None


@dataclass(frozen=True)
class ViewPlan:
    """A view and how each reflector (but the ``excluded`` one) is drawn in it."""

    view: View
    draws: tuple[ReflectorDraw, ...]
    excluded: str | None = None


@dataclass
class TextureState:
    """What the renderer's textures hold: ``(reflector, slot) -> key`` of the capture or
    bake in it. The planner reads it; the renderer records each capture it runs."""

    held: dict[tuple[str, int], tuple] = field(default_factory=dict)

    def slot_holding(self, reflector: str, key: tuple) -> int | None:
        for (name, slot), held in self.held.items():
            if name == reflector and held == key:
                return slot
        return None

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
        lines += [f"     draw {d.reflector.name} in camera: {d.mode} ({d.reason})"
                  for d in self.top.draws]
        return lines


def plan_frame(scene: Scene, size: tuple[int, int], state: TextureState | None = None,
               use_plan: bool = True, tiny_pixels: float = TINY_PIXELS,
               view: View | None = None) -> FramePlan:
    """The passes for one frame of ``scene`` seen by its camera (or ``view``) at ``size``
    (width, height) pixels, given what ``state`` says the textures hold.

    With ``use_plan`` False every pass runs: every reflector is captured at every bounce
    for every view, nothing is reused and no reflector is drawn plain for being small
    (for comparison: the frame comes out the same, pixel for pixel, unless
    ``tiny_pixels`` is positive). ``tiny_pixels`` above 0 turns on the lossy rule: a
    reflector whose footprint may cover fewer pixels than that is drawn plain.
    """
    planner = _Planner(scene, state or TextureState(), use_plan,
                       tiny_pixels if use_plan else 0.0)
    top_view = view or camera_view(scene.camera, size)
    top = planner.plan_view(top_view, scene.max_bounces, None)
    camera = PlannedPass("camera", True, "the frame itself", for_view="camera")
    return FramePlan(tuple([*planner.passes, camera]), top)


class _Planner:
    def __init__(self, scene: Scene, state: TextureState, use_plan: bool,
                 tiny_pixels: float) -> None:
        self.scene = scene
        self.state = state
        self.use_plan = use_plan
        self.tiny_pixels = tiny_pixels
        self.passes: list[PlannedPass] = []
        self.content = scene.content_key()
        self.assigned: dict[tuple[str, tuple], int] = {}  # this frame's (reflector, key) slots
        self.used: dict[str, set[int]] = {}

    def plan_view(self, view: View, bounce: int, excluded: str | None) -> ViewPlan:
        draws = []
        for reflector in self.scene.reflectors:
            if reflector.name == excluded:
                continue
            draws.append(self.draw(reflector, view, bounce))
        return ViewPlan(view, tuple(draws), excluded)

    def draw(self, reflector: Reflector, view: View, bounce: int) -> ReflectorDraw:
        entry = technique(reflector.technique)
        if self.use_plan:
            hidden = hidden_reason(reflector, view)
            if hidden:
                mode: DrawMode = "back" if hidden.startswith("seen from behind") else "hidden"
                return ReflectorDraw(reflector, mode, hidden)
        if bounce <= 0:
            return ReflectorDraw(reflector, "plain", "no bounces left: a plain surface")
        if self.tiny_pixels > 0 and entry.texture != "static":
            area = screen_area(reflector, view)
            if area < self.tiny_pixels:
                return ReflectorDraw(reflector, "plain", f"covers at most {area:.1f} pixels "
                                     f"(under {self.tiny_pixels:g}; lossy): drawn plain, no "
                                     f"capture")
        if entry.draws_inline:
            assert isinstance(reflector, PlanarReflector)
            far = self.reach(view, reflector) if view.eye is not None else None
            nested = self.plan_view(stencil_view(view, reflector, far), bounce - 1,
                                    reflector.name)
            return ReflectorDraw(reflector, "stencil", "the mirrored world, drawn in place",
                                 nested=nested)
        if entry.texture == "static":
            return ReflectorDraw(reflector, "map", "its static map")
        if entry.texture == "baked":
            assert isinstance(reflector, CurvedReflector)  # baked maps are curved techniques
            slot = self.bake(reflector, view)
            return ReflectorDraw(reflector, "map", "its sphere map for this view", slot=slot)
        slot, source = self.capture(reflector, view, bounce)
        if source is None:
            return ReflectorDraw(reflector, "plain", "no capture camera from here")
        return ReflectorDraw(reflector, "texture", "its capture", slot=slot, source=source)

    # ------------------------------------------------------------- textures

    def slot_for(self, reflector: str, key: tuple) -> tuple[int, bool]:
        """The slot for ``key`` and whether it already holds it (so nothing need run)."""
        if (reflector, key) in self.assigned:
            return self.assigned[(reflector, key)], True
        used = self.used.setdefault(reflector, set())
        held = self.state.slot_holding(reflector, key) if self.use_plan else None
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
        if held and (reflector.name, key) in self._planned_keys():
            return slot
        runs = not held
        self.passes.append(PlannedPass(
            "bake", runs, reason if runs else "the map for this view is already made",
            reflector.name, reflector.technique, 0, view.label, slot, key))
        return slot

    def _planned_keys(self) -> set[tuple[str, tuple]]:
        return {(p.reflector, p.key) for p in self.passes if p.reflector is not None}

    def reach(self, view: View, reflector: PlanarReflector) -> float:
        """How far the world seen in ``reflector`` from ``view`` extends: reflections see
        the whole scene, whatever the camera's far plane (the truth's definition)."""
        eye = view.eye
        if eye is None:
            return 0.0  # orthographic: no eye to measure from (not used)
        mirrored = math3d.transform_points(math3d.reflection_matrix(reflector.plane), eye)[:3]
        return bounds.reach(self.scene, mirrored)

    def capture(self, reflector: Reflector, view: View,
                bounce: int) -> tuple[int, View | None]:
        entry = technique(reflector.technique)
        if entry.capture_camera in ("reflected", "ortho"):
            assert isinstance(reflector, PlanarReflector)
            size = reflector.texture_size
            texture_size = (size, size) if size else view.size
            if entry.capture_camera == "reflected":
                camera = reflected_capture_view(view, reflector, texture_size,
                                                self.reach(view, reflector)
                                                if view.eye is not None else None)
                if camera is None:
                    return 0, None
                cameras = [camera]
                key: tuple = ("viewer", bounce, camera.key, self.content)
            else:
                cameras = [ortho_capture_view(reflector, texture_size)]
                key = ("fixed", bounce, texture_size, self.content)
        elif entry.capture_camera == "cube":
            assert isinstance(reflector, CurvedReflector)
            cameras = cube_face_views(reflector, bounds.cube_depth_range(self.scene, reflector))
            key = ("fixed", bounce, (reflector.map_size,), self.own_content(reflector))
        else:
            raise ValueError(f"technique {entry.name!r} has a texture of kind "
                             f"{entry.texture!r} but no capture camera")
        slot, held = self.slot_for(reflector.name, key)
        source = cameras[0]
        if held and (reflector.name, key) in self._planned_keys():
            return slot, source  # already captured earlier in this frame
        if held:
            self.passes.append(PlannedPass(
                "capture", False, "nothing it shows changed since it was captured",
                reflector.name, reflector.technique, bounce, view.label, slot, key))
            return slot, source
        plans = tuple(self.plan_view(camera, bounce - 1, reflector.name) for camera in cameras)
        reason = ("every pass runs (--no-plan)" if not self.use_plan
                  else self.what_changed(reflector.name, key))
        self.passes.append(PlannedPass("capture", True, reason, reflector.name,
                                       reflector.technique, bounce, view.label, slot, key,
                                       plans))
        return slot, source

    def own_content(self, reflector: CurvedReflector) -> tuple:
        """What a live cube map of ``reflector`` shows: the scene's content, but of the
        reflector's own parallax correction only its kind (a distance search captures
        depths too). A proxy's size or a search's steps change how the map is read, not
        what it holds."""
        if reflector.parallax is None:
            return self.content
        background, ambient, lights, objects, reflectors, bounces = self.content
        own = (replace(reflector, parallax=None), reflector.parallax.kind)
        return (background, ambient, lights, objects,
                tuple(own if r.name == reflector.name else r for r in reflectors), bounces)

    def what_changed(self, reflector: str, key: tuple) -> str:
        """Why a capture must run: what differs from the nearest capture its textures hold
        (keys are (kind, bounce, camera or size, scene content))."""
        held = [k for (name, _), k in self.state.held.items()
                if name == reflector and k[:2] == key[:2]]
        if not held:
            return "its texture is still blank"
        previous = min(held, key=lambda k: (k[2] != key[2]) + (k[3] != key[3]))
        moved, changed = previous[2] != key[2], previous[3] != key[3]
        if key[0] == "viewer":
            what = "the viewer moved" if moved else ""
        else:
            what = "its texture's size changed" if moved else ""
        if changed:
            what = f"{what} and the scene changed" if what else (
                "the scene changed since the last capture")
        return what or "its texture was used for another capture"


# --------------------------------------------------------------------------- geometry


def hidden_reason(reflector: Reflector, view: View) -> str | None:
    """Why ``reflector`` cannot show in ``view``, or None when it may: a planar mirror
    seen from behind or edge-on (only its backing can show), or a footprint
    (:func:`reflector_footprint`) that covers no pixel."""
    if isinstance(reflector, PlanarReflector):
        if view.eye is not None:
            facing = float((view.eye - reflector.center) @ reflector.normal)
        else:
            facing = float(-view.forward @ reflector.normal)
        if not facing > 0.0:
            return "seen from behind or edge-on: only its back shows"
        outside = _where_outside(reflector.corner_array, view)
        if outside is not None:  # every corner beyond one plane: exactly out of view
            return outside
        if reflector_footprint(reflector, view).empty:
            return "out of view (past a corner of the view)"
        return None
    center, radius = bounding_sphere(reflector)
    if _sphere_in_view(center, radius, view) and not reflector_footprint(
            reflector, view).empty:
        return None
    return "out of view"


def _where_outside(points: np.ndarray, view: View) -> str | None:
    """Which side of ``view`` all of ``points`` ``(n, 3)`` lie beyond, in words (None
    when no single side has them all)."""
    if view.clip_plane is not None and np.all(
            math3d.transform_points(np.eye(4), points) @ view.clip_plane <= 0.0):
        return "behind the mirror it would be seen in"
    clip = math3d.transform_points(view.view_projection, points)
    x, y, z, w = clip[:, 0], clip[:, 1], clip[:, 2], clip[:, 3]
    if not is_orthographic(view.projection) and np.all(w <= 0.0):
        return "out of view (behind the viewer)"
    for outside, where in ((x < -w, "left of"), (x > w, "right of"), (y < -w, "below"),
                           (y > w, "above"), (z < -w, "behind"), (z > w, "beyond")):
        if np.all(outside):
            what = "the viewer" if where == "behind" else "the view"
            return f"out of view ({where} {what})"
    return None


def _sphere_in_view(center: np.ndarray, radius: float, view: View) -> bool:
    if view.clip_plane is not None and float(np.append(center, 1.0) @ view.clip_plane) < -radius:
        return False
    matrix = view.view_projection
    planes = (matrix[3] + matrix[0], matrix[3] - matrix[0], matrix[3] + matrix[1],
              matrix[3] - matrix[1], matrix[3] + matrix[2], matrix[3] - matrix[2])
    point = np.append(center, 1.0)
    for plane in planes:
        length = float(np.linalg.norm(plane[:3]))
        if length > 0 and float(plane @ point) / length < -radius:
            return False
    return True


def bounding_sphere(reflector: Reflector) -> tuple[np.ndarray, float]:
    """World centre ``(3,)`` and radius of a sphere around the reflector
    (:func:`mirrorlab.bounds.bounding_sphere`)."""
    return bounds.bounding_sphere(reflector)


def reflector_footprint(reflector: Reflector, view: View) -> Footprint:
    """Where ``reflector`` can show in ``view`` (:mod:`mirrorlab.footprint`): a planar
    mirror's quad clipped against the view volume and the view's clip plane, a curved
    reflector's bounding sphere by its projected ellipse. It errs large."""
    if isinstance(reflector, PlanarReflector):
        return polygon_footprint(reflector.corner_array, view.view_projection, view.size,
                                 view.clip_plane)
    center, radius = bounding_sphere(reflector)
    return sphere_footprint(center, radius, view.view, view.projection, view.size)


def screen_area(reflector: Reflector, view: View) -> float:
    """At most how many pixels ``reflector`` covers in ``view`` (its footprint's
    :attr:`~mirrorlab.footprint.Footprint.pixels`)."""
    return reflector_footprint(reflector, view).pixels


def describe_steps(plan: FramePlan) -> list[str]:
    return plan.describe()
