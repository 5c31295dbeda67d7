"""What decides a reflection technique's error in one view, worked out without drawing:
the features the budget's predictions are made from (:mod:`mirrorlab.budget.model`).

A reflector is sampled where the viewer sees it: the primary rays through a grid of
points over its footprint on screen that meet its front (a planar mirror's quad, a
curved reflector's mesh, found by trimesh's ray caster) and are not hidden behind an
object's box, so that the samples stand for its pixels. From each sample the reflected
ray is followed
against the boxes of the scene's object parts and other reflectors
(:func:`first_hits`): what it meets first, and how far away.

Per reflector and view (:class:`ViewFeatures`):

- ``pixels``: the reflector's screen footprint (:func:`mirrorlab.plan.screen_area`);
- ``grazing``: the mean of ``1 - |n . v|`` over the samples (0 head-on, 1 edge-on);
- ``objects``: the share of reflected rays that meet an object (the rest see the
  background);
- ``offscreen``: the share of reflected rays whose first hit is outside the view, behind
  the eye or hidden from it (what a screen-space technique cannot find on the screen);
- ``near``: how close what is reflected is, against the reflector's size (the median of
  ``radius / distance`` over the rays that meet something): parallax grows with it.

Per candidate (:func:`candidate_features`), from where its texture kind looks a
reflected ray up (read from the technique's registry entry, so a new technique is
placed by its kind):

- ``wrong``: the share of samples whose lookup meets another thing than the true ray
  does (a static map sees only the background; a live cube map looks from its capture
  centre, through its parallax correction when it has one; the lab's orthographic
  capture looks along the mirror's normal; a capture from the viewer's mirror image, an
  inline mirror and a distance search see what the ray sees);
- ``shift``: where the lookup meets the same thing, how far its point lies from the true
  one, in pixels of the view (the mean over those samples, each clipped at 64);
- ``texels``: log2 of the texels of its map per pixel of the reflector on screen.

Numpy only; a few hundred rays against the scene's boxes, about a millisecond.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from mirrorlab import bounds, math3d, parallax
from mirrorlab.budget.candidates import Candidate
from mirrorlab.footprint import Footprint
from mirrorlab.scene.model import (
    BoxProxy,
    CurvedReflector,
    DistanceSearch,
    PlanarReflector,
    Reflector,
    Scene,
    SphereProxy,
)
from mirrorlab.techniques import technique
from mirrorlab.views import View

GRID = 12
"""A planar mirror is sampled on a GRID x GRID grid over its quad."""
SHIFT_CLIP = 64.0
"""A sample's shift counts at most this many pixels."""
VIEW_FEATURES = ("pixels", "grazing", "objects", "offscreen", "near")
CANDIDATE_FEATURES = ("wrong", "shift", "texels")


@dataclass(frozen=True)
class Samples:
    """Where a reflector is sampled in a view: ``points`` ``(n, 3)`` world, unit
    ``normals`` ``(n, 3)``, unit view directions ``views`` ``(n, 3)`` (eye to point),
    ``reflected`` ``(n, 3)`` unit reflected directions and ``weights`` ``(n,)`` (the
    solid angle each stands for, summing to 1)."""

    points: np.ndarray
    normals: np.ndarray
    views: np.ndarray
    reflected: np.ndarray
    weights: np.ndarray

    def __len__(self) -> int:
        return len(self.points)


@dataclass(frozen=True)
class Hits:
    """What rays meet first among the scene's boxes: ``ids`` ``(n,)`` (the box's index,
    -1 for the background) and ``points`` ``(n, 3)`` (where; for the background, a point
    far along the ray)."""

    ids: np.ndarray
    points: np.ndarray


@dataclass(frozen=True)
class ViewFeatures:
    """A reflector seen in one view (see the module's text): ``pixels``, ``grazing``,
    ``objects``, ``offscreen``, ``near``; and what the candidate features are made from:
    the ``samples``, the true rays' ``hits``, the scene's boxes (``low``, ``high``
    ``(m, 3)``, the reflector's own left out), the ``view``, the reflector's ``radius``
    and its footprint's ``diameter`` in pixels, whether the background is an
    ``environment`` (varies with direction) and how ``far`` the background lies."""

    pixels: float
    grazing: float
    objects: float
    offscreen: float
    near: float
    samples: Samples
    hits: Hits
    low: np.ndarray
    high: np.ndarray
    view: View
    radius: float
    diameter: float
    environment: bool
    far: float

    def vector(self) -> np.ndarray:
        """``(5,)``: log2 of ``pixels``, then the other view features in order."""
        return np.array(
            [
                math.log2(max(self.pixels, 1.0)),
                self.grazing,
                self.objects,
                self.offscreen,
                self.near,
            ]
        )


def view_features(
    scene: Scene, reflector: Reflector, view: View, footprint: Footprint
) -> ViewFeatures | None:
    """The features of ``reflector`` in ``scene`` seen in ``view`` (its ``footprint``
    there); None when no sample of it faces the eye inside the view."""
    low, high = bounds.boxes_but(scene, reflector.name)
    samples = sample_reflector(reflector, view, footprint, low, high)
    if samples is None:
        return None
    center, radius = bounds.bounding_sphere(reflector)
    far = 4.0 * bounds.reach(scene, center) + 1.0
    hits = first_hits(samples.points, samples.reflected, low, high, far)
    met = hits.ids >= 0
    w = samples.weights
    objects = min(float(w[met].sum()), 1.0)
    distance = np.linalg.norm(hits.points - samples.points, axis=1)
    near = (
        float(np.median(np.minimum(radius / np.maximum(distance[met], 1e-12), 4.0)))
        if met.any()
        else 0.0
    )
    offscreen = min(float(w[_off_screen(hits, met, view, low, high)].sum()), 1.0)
    grazing = float(w @ (1.0 - np.abs(np.einsum("ij,ij->i", samples.normals, samples.views))))
    return ViewFeatures(
        pixels=float(footprint.pixels),
        grazing=grazing,
        objects=objects,
        offscreen=offscreen,
        near=near,
        samples=samples,
        hits=hits,
        low=low,
        high=high,
        view=view,
        radius=radius,
        diameter=2.0 * math.sqrt(max(footprint.area, 1.0) / math.pi),
        environment=scene.background.is_environment,
        far=far,
    )


def candidate_features(
    features: ViewFeatures, reflector: Reflector, candidate: Candidate
) -> np.ndarray:
    """``(3,)``: ``wrong``, ``shift`` and ``texels`` of ``candidate`` drawing
    ``reflector`` (as posed) in the view of ``features``."""
    drawn = candidate.apply(reflector)
    wrong, shift = lookup_error(features, drawn)
    return np.array([wrong, shift, texels_of(features, drawn)])


# --------------------------------------------------------------------------- sampling


def sample_reflector(
    reflector: Reflector, view: View, footprint: Footprint, low=None, high=None
) -> Samples | None:
    """The samples of ``reflector`` seen in ``view``: the primary rays through a
    :data:`GRID` x :data:`GRID` grid of points over its ``footprint``'s rectangle that
    meet its front (a planar mirror's quad, a curved reflector's mesh), and are not
    hidden behind one of the boxes ``low``-``high``; None when none is."""
    rectangle = footprint.bounds
    if view.eye is None or rectangle is None:
        return None
    x, y, width, height = rectangle
    steps = (np.arange(GRID) + 0.5) / GRID
    px, py = np.meshgrid(x + steps * width, y + steps * height, indexing="ij")
    ndc = np.column_stack(
        [2.0 * px.ravel() / view.size[0] - 1.0, 2.0 * py.ravel() / view.size[1] - 1.0]
    )
    inverse = np.linalg.inv(view.view_projection)
    far = math3d.transform_points(inverse, np.column_stack([ndc, np.ones(len(ndc))]))
    eye = np.asarray(view.eye, dtype=np.float64)
    directions = far[:, :3] / far[:, 3:4] - eye
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    if isinstance(reflector, PlanarReflector):
        found = _quad_hits(reflector, eye, directions)
    else:
        assert isinstance(reflector, CurvedReflector)
        found = _mesh_hits(reflector, eye, directions)
    if found is None:
        return None
    points, normals, rays = found
    if low is not None and high is not None and len(low):
        distance = np.linalg.norm(points - eye, axis=1)
        before = first_hits(np.broadcast_to(eye, rays.shape), rays, low, high, np.inf)
        ahead = np.linalg.norm(before.points - eye, axis=1)
        seen = (before.ids < 0) | (ahead >= distance * (1.0 - 1e-6))
        points, normals, rays = points[seen], normals[seen], rays[seen]
        if not len(points):
            return None
    reflected = rays - 2.0 * np.einsum("ij,ij->i", normals, rays)[:, None] * normals
    weights = np.full(len(points), 1.0 / len(points))
    return Samples(points, normals, rays, reflected, weights)


def _quad_hits(
    reflector: PlanarReflector, eye: np.ndarray, directions: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Where rays from ``eye`` meet the front of the mirror's quad."""
    normal = reflector.normal
    facing = directions @ normal
    height = (eye - reflector.center) @ normal
    if not height > 0:
        return None  # the eye is behind the mirror or in its plane
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -height / facing
    ok = (facing < 0) & np.isfinite(t) & (t > 0)
    points = eye + np.where(ok, t, 0.0)[:, None] * directions
    corners = reflector.corner_array
    inside = ok.copy()
    for i in range(4):  # counter-clockwise from the front: inside is left of each edge
        edge = corners[(i + 1) % 4] - corners[i]
        inside &= np.cross(edge, points - corners[i]) @ normal >= 0
    if not inside.any():
        return None
    return (
        points[inside],
        np.broadcast_to(normal, (int(inside.sum()), 3)).copy(),
        directions[inside],
    )


@functools.lru_cache(maxsize=32)
def _mesh_intersector(mesh):
    """The mesh file's triangles in its own frame, with a ray intersector and its vertex
    normals (kept)."""
    import trimesh

    from mirrorlab.scene.mesh import load_mesh

    data = load_mesh(mesh)
    shape = trimesh.Trimesh(
        data.positions.astype(np.float64), data.indices.astype(np.int64), process=False
    )
    return shape, data.normals.astype(np.float64)


def _mesh_hits(
    reflector: CurvedReflector, eye: np.ndarray, directions: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Where rays from ``eye`` first meet the front of the curved reflector's mesh, with
    the mesh's interpolated normals there."""
    shape, vertex_normals = _mesh_intersector(reflector.mesh)
    model = reflector.model_matrix()
    to_local = np.linalg.inv(model)
    origin = math3d.transform_points(to_local, eye)[:3]
    local = directions @ to_local[:3, :3].T
    origins = np.broadcast_to(origin, local.shape)
    triangles = shape.ray.intersects_first(np.ascontiguousarray(origins), local)
    met = triangles >= 0
    if not met.any():
        return None
    faces = shape.faces[triangles[met]]
    corners = shape.vertices[faces]  # (k, 3, 3)
    local_met = local[met]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("ij,ij->i", corners[:, 0] - origin, face_normals) / np.einsum(
            "ij,ij->i", local_met, face_normals
        )
    hits = origin + t[:, None] * local_met
    weights = _barycentric(corners, hits)
    normals = np.einsum("ij,ijk->ik", weights, vertex_normals[faces])
    world_points = math3d.transform_points(model, hits)[:, :3]
    world_normals = normals @ to_local[:3, :3]  # the inverse transpose, on rows
    world_normals /= np.maximum(np.linalg.norm(world_normals, axis=1), 1e-300)[:, None]
    rays = directions[met]
    front = (np.einsum("ij,ij->i", world_normals, rays) < 0) & np.isfinite(t)
    if not front.any():
        return None
    return world_points[front], world_normals[front], rays[front]


def _barycentric(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(k, 3)`` barycentric weights of ``points`` ``(k, 3)`` in ``triangles`` ``(k, 3, 3)``."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    v0, v1, v2 = b - a, c - a, points - a
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    denominator = d00 * d11 - d01 * d01
    safe = np.where(np.abs(denominator) > 0, denominator, 1.0)
    v = (d11 * d20 - d01 * d21) / safe
    w = (d00 * d21 - d01 * d20) / safe
    return np.clip(np.column_stack([1.0 - v - w, v, w]), 0.0, 1.0)


# --------------------------------------------------------------------------- rays


def first_hits(
    origins: np.ndarray, directions: np.ndarray, low: np.ndarray, high: np.ndarray, far: float
) -> Hits:
    """What each ray (``origins``, unit ``directions``, ``(n, 3)``) meets first among the
    boxes ``low``-``high`` ``(m, 3)``: a box the ray starts inside is passed (a sample
    point lies on a surface, not in a solid), and the background lies ``far`` away."""
    count = len(origins)
    if not len(low):
        return Hits(np.full(count, -1), origins + far * directions)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / directions[:, None, :]
        near_t = (low[None] - origins[:, None, :]) * inverse
        far_t = (high[None] - origins[:, None, :]) * inverse
    parallel = np.broadcast_to(directions[:, None, :] == 0, near_t.shape)
    within = (origins[:, None, :] >= low[None]) & (origins[:, None, :] <= high[None])
    first = np.where(parallel, np.where(within, -np.inf, np.inf), np.minimum(near_t, far_t))
    last = np.where(parallel, np.where(within, np.inf, -np.inf), np.maximum(near_t, far_t))
    entry = first.max(axis=2)
    leave = last.min(axis=2)
    met = (leave >= entry) & (entry > 1e-9 * far)
    t = np.where(met, entry, np.inf)
    ids = np.argmin(t, axis=1)
    best = t[np.arange(count), ids]
    ids = np.where(np.isfinite(best), ids, -1)
    reach = np.where(ids >= 0, best, far)
    return Hits(ids, origins + reach[:, None] * directions)


def _off_screen(hits: Hits, met: np.ndarray, view: View, low, high) -> np.ndarray:
    """Which true hits a screen-space lookup cannot find: outside the view, behind the eye,
    or behind another box seen from the eye."""
    clip = math3d.transform_points(view.view_projection, hits.points)
    w = clip[:, 3]
    outside = ~(
        (w > 0) & (np.abs(clip[:, 0]) <= w) & (np.abs(clip[:, 1]) <= w) & (np.abs(clip[:, 2]) <= w)
    )
    hidden = np.zeros(len(met), dtype=bool)
    seen = met & ~outside
    if seen.any():
        eye = np.asarray(view.eye, dtype=np.float64)
        to_hit = hits.points[seen] - eye
        distance = np.linalg.norm(to_hit, axis=1)
        units = to_hit / np.maximum(distance, 1e-300)[:, None]
        before = first_hits(np.broadcast_to(eye, units.shape), units, low, high, np.inf)
        ahead = np.linalg.norm(before.points - eye, axis=1)
        hidden[seen] = (
            (before.ids >= 0) & (before.ids != hits.ids[seen]) & (ahead < distance * (1.0 - 1e-6))
        )
    return outside | hidden


# --------------------------------------------------------------------------- lookups


def lookup_error(features: ViewFeatures, drawn: Reflector) -> tuple[float, float]:
    """``wrong`` and ``shift`` of ``drawn`` (a candidate applied to the reflector; see
    the module's text)."""
    entry = technique(drawn.technique)
    samples, hits = features.samples, features.hits
    w = samples.weights
    if entry.texture in ("static", "baked"):
        return min(float(w[hits.ids >= 0].sum()), 1.0), 0.0
    if entry.texture == "fixed" and isinstance(drawn, PlanarReflector):
        origins, directions = samples.points, samples.normals
    elif entry.texture == "fixed" and isinstance(drawn, CurvedReflector):
        center = drawn.center()
        proxy = drawn.parallax
        if isinstance(proxy, DistanceSearch):
            return 0.0, 0.0
        if isinstance(proxy, BoxProxy):
            directions = parallax.box_lookup(
                samples.points, samples.reflected, center, np.array(proxy.min), np.array(proxy.max)
            )
        elif isinstance(proxy, SphereProxy):
            directions = parallax.sphere_lookup(
                samples.points, samples.reflected, center, proxy.radius
            )
        else:
            directions = samples.reflected
        directions = np.asarray(directions, dtype=np.float64)
        origins = np.broadcast_to(center, directions.shape)
    else:
        return 0.0, 0.0  # what the reflected ray sees (a capture from the mirror image, ...)
    looked = first_hits(
        np.ascontiguousarray(origins), directions, features.low, features.high, features.far
    )
    differ = looked.ids != hits.ids
    same = ~differ
    pixel = _pixel_angle(features.view)
    shift = np.zeros(len(w))
    both = same & (hits.ids >= 0)
    if both.any():
        true = hits.points[both] - samples.points[both]
        seen = looked.points[both] - samples.points[both]
        shift[both] = _angle(true, seen) / pixel
    sky = same & (hits.ids < 0)
    if sky.any() and features.environment:
        shift[sky] = _angle(samples.reflected[sky], directions[sky]) / pixel
    shift = np.minimum(shift, SHIFT_CLIP)
    kept = w[same].sum()
    wrong = min(float(w[differ].sum()), 1.0)
    return wrong, float(w[same] @ shift[same] / kept) if kept > 0 else 0.0


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles in radians between rows of ``a`` and ``b``, stable for small angles."""
    cross = np.linalg.norm(np.cross(a, b), axis=1)
    dot = np.einsum("ij,ij->i", a, b)
    return np.arctan2(cross, dot)


def _pixel_angle(view: View) -> float:
    """The angle one pixel of ``view`` spans at its centre (radians)."""
    focal = float(view.projection[1, 1])
    return 2.0 / (focal * view.size[1]) if focal > 0 else 1e-3


def texels_of(features: ViewFeatures, drawn: Reflector) -> float:
    """log2 texels of ``drawn``'s map per pixel of the reflector on screen (0 where it
    has no map, or one the size of the view or its footprint)."""
    entry = technique(drawn.technique)
    if entry.texture == "inline":
        return 0.0
    view = features.view
    if isinstance(drawn, PlanarReflector):
        size = drawn.texture_size
        if not isinstance(size, int):
            return 0.0
        if entry.own_camera:  # the texture spans the mirror
            return math.log2(size / max(math.sqrt(features.pixels), 1.0))
        return math.log2(size / max(view.size))  # the texture spans the view
    assert isinstance(drawn, CurvedReflector)
    return math.log2(drawn.map_size / max(features.diameter, 1.0))


def texture_texels(reflector: Reflector, size: tuple[int, int], pixels: float) -> float:
    """The texels a reflector's texture holds (what its capture rasterises, or its bake
    computes): a planar capture's side squared (the view's pixels when it has none, its
    footprint's ``pixels`` when sized to it), a curved map's side squared; 0 for none."""
    from mirrorlab.scene.model import FOOTPRINT_TEXTURE

    entry = technique(reflector.technique)
    if entry.texture == "inline":
        return 0.0
    if isinstance(reflector, PlanarReflector):
        side = reflector.texture_size
        if side == FOOTPRINT_TEXTURE:
            return float(pixels)
        if side is None:
            return float(size[0] * size[1])
        return float(side) ** 2
    assert isinstance(reflector, CurvedReflector)
    return float(reflector.map_size) ** 2
