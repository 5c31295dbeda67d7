"""How far things reach: bounding spheres and boxes of a scene's meshes, reflectors and
of the whole scene, in world units. What the planner sizes views by (a live capture sees
as far as the scene extends, and no nearer than its nearest neighbour). Numpy only; a
mesh file is read once (:func:`mirrorlab.scene.mesh.load_mesh`) and its bounds kept.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from functools import cached_property, lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from mirrorlab import culling, math3d
from mirrorlab.math3d import read_only
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Reflector, Scene

if TYPE_CHECKING:
    from mirrorlab.scene.robot import Part, PartLooks

REACH_MARGIN = 1e-3
"""A far plane set from a bounding sphere lies this share of the distance beyond it."""


@lru_cache(maxsize=64)
def _mesh_points(mesh: Path) -> np.ndarray:
    """A mesh file's vertex positions ``(n, 3)`` float64 (read-only)."""
    from mirrorlab.scene.mesh import load_mesh

    points = load_mesh(mesh).positions.astype(np.float64)
    points.flags.writeable = False
    return points


@lru_cache(maxsize=64)
def _mesh_sphere(mesh: Path) -> tuple[np.ndarray, float]:
    positions = _mesh_points(mesh)
    center = (positions.min(axis=0) + positions.max(axis=0)) / 2.0
    return center, float(np.linalg.norm(positions - center, axis=1).max())


def mesh_box(mesh: Path, model: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World min and max corners ``(3,)`` of the mesh file ``mesh`` placed by ``model``."""
    world = math3d.transform_points(model, _mesh_points(mesh))[:, :3]
    return world.min(axis=0), world.max(axis=0)


@lru_cache(maxsize=256)
def bounding_sphere(reflector: Reflector) -> tuple[np.ndarray, float]:
    """World centre ``(3,)`` (read-only) and radius of a sphere holding the reflector
    (remembered: reflectors are values, and a frame asks for it in every view)."""
    center, radius = _bounding_sphere(reflector)
    center = np.array(center, dtype=np.float64)
    center.flags.writeable = False
    return center, radius


def _bounding_sphere(reflector: Reflector) -> tuple[np.ndarray, float]:
    if isinstance(reflector, PlanarReflector):
        corners = reflector.corner_array
        center = corners.mean(axis=0)
        return center, float(np.linalg.norm(corners - center, axis=1).max())
    center, radius = _mesh_sphere(reflector.mesh)
    model = reflector.model_matrix()
    world = math3d.transform_points(model, center)[:3]
    stretch = float(np.linalg.svd(model[:3, :3], compute_uv=False).max())
    return world, radius * stretch


def reflector_box(reflector: Reflector) -> tuple[np.ndarray, np.ndarray]:
    """World min and max corners ``(3,)`` of the reflector."""
    if isinstance(reflector, PlanarReflector):
        return reflector.corner_array.min(axis=0), reflector.corner_array.max(axis=0)
    assert isinstance(reflector, CurvedReflector)
    return mesh_box(reflector.mesh, reflector.model_matrix())


@lru_cache(maxsize=64)
def _mesh_local_box(mesh: Path) -> tuple[np.ndarray, np.ndarray]:
    """A mesh file's own centre and half-size ``(3,)`` of its vertices' box (read-only)."""
    positions = _mesh_points(mesh)
    low, high = positions.min(axis=0), positions.max(axis=0)
    return read_only((low + high) / 2.0), read_only((high - low) / 2.0)


@dataclass(frozen=True, eq=False)
class ObjectBounds:
    """One object's drawable parts: their ``looks`` (:func:`mirrorlab.scene.robot.object_looks`,
    shared by every pose) and ``models`` ``(k, 4, 4)``; and, worked out when first asked
    for, each part's exact world box ``low``, ``high`` ``(k, 3)``."""

    looks: PartLooks
    models: np.ndarray

    @cached_property
    def parts(self) -> tuple[Part, ...]:
        return self.looks.parts(self.models)

    @cached_property
    def boxes(self) -> tuple[np.ndarray, np.ndarray]:
        boxes = [
            mesh_box(mesh, model)
            for mesh, model in zip(self.looks.meshes, self.models, strict=True)
        ]
        return (
            read_only(np.array([b[0] for b in boxes]).reshape(-1, 3)),
            read_only(np.array([b[1] for b in boxes]).reshape(-1, 3)),
        )


@lru_cache(maxsize=64)
def _looks_boxes(looks: tuple[PartLooks, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The centres and half-sizes ``(n, 3)`` of the meshes' own boxes of every part of
    ``looks`` (read-only), in order."""
    local = [_mesh_local_box(mesh) for look in looks for mesh in look.meshes]
    return (
        read_only(np.array([c for c, _ in local]).reshape(-1, 3)),
        read_only(np.array([h for _, h in local]).reshape(-1, 3)),
    )


@dataclass(frozen=True, eq=False)
class ObjectArrays:
    """The bounds of a scene's objects: each object's ``bounds``, the parts' ``looks``
    (each object's :class:`~mirrorlab.scene.robot.PartLooks`, hashed by identity: equal
    for every pose of the same objects) and ``models`` ``(n, 4, 4)`` float64 of every
    part, in drawing order; for culling, each part's mesh box carried into the world,
    ``part_centers`` and ``part_halves`` ``(n, 3)`` (it holds the part, a little larger
    than its own box when turned); and, worked out when first asked for, the ``parts``
    themselves and each part's exact world box ``part_low``, ``part_high`` (what a
    view's reach is set by). Read-only; made once for an ``objects`` tuple."""

    objects: tuple
    bounds: tuple[ObjectBounds, ...]
    looks: tuple[PartLooks, ...]
    models: np.ndarray

    def __len__(self) -> int:
        return len(self.models)

    @cached_property
    def parts(self) -> tuple[Part, ...]:
        return tuple(part for b in self.bounds for part in b.parts)

    @cached_property
    def part_low(self) -> np.ndarray:
        return read_only(
            np.concatenate([b.boxes[0] for b in self.bounds]) if self.bounds else np.zeros((0, 3))
        )

    @cached_property
    def part_high(self) -> np.ndarray:
        return read_only(
            np.concatenate([b.boxes[1] for b in self.bounds]) if self.bounds else np.zeros((0, 3))
        )

    @cached_property
    def part_rows(self) -> np.ndarray:
        """``(n, 10)``: each part's culling box as :func:`mirrorlab.culling.box_rows` makes
        them, worked out in place (a new pose makes them every frame)."""
        centers, halves = _looks_boxes(self.looks)
        turn = self.models[:, :3, :3]
        rows = np.empty((len(turn), 10))
        np.matmul(turn, centers[:, :, None], out=rows[:, 0:3, None])
        rows[:, 0:3] += self.models[:, :3, 3]
        np.matmul(np.abs(turn), halves[:, :, None], out=rows[:, 3:6, None])  # the turned box's box
        np.abs(rows[:, 0:3], out=rows[:, 6:9])
        rows[:, 9] = 1.0
        return read_only(rows)

    @property
    def part_centers(self) -> np.ndarray:
        """``(n, 3)``: the middle of each part's culling box."""
        return self.part_rows[:, 0:3]

    @property
    def part_halves(self) -> np.ndarray:
        """``(n, 3)``: half the size of each part's culling box."""
        return self.part_rows[:, 3:6]

    @cached_property
    def digest(self) -> int:
        """A hash of the objects from each one's hash (kept by its identity): what a key
        holding them hashes by, without hashing them all again."""
        return hash(tuple(_CACHE.hash_of(item) for item in self.objects))


@dataclass(frozen=True, eq=False)
class ReflectorArrays:
    """The bounds of a scene's ``reflectors``: ``names`` (name to position), boxes
    ``reflector_low``, ``reflector_high`` ``(m, 3)``; the planar ones at positions
    ``planar`` ``(p,)`` with their corners as ``corner_rows`` ``(4, p, 4)``
    (:func:`mirrorlab.culling.quad_rows`), unit ``normals`` and ``centers`` ``(p, 3)``; the
    curved ones at ``curved`` ``(c,)`` with bounding spheres
    ``sphere_centers`` ``(c, 3)`` and ``sphere_radii`` ``(c,)``. Read-only; made once for
    a ``reflectors`` tuple (and hashed by identity: a key for what depends on them
    alone)."""

    reflectors: tuple
    names: dict[str, int]
    reflector_low: np.ndarray
    reflector_high: np.ndarray
    planar: np.ndarray
    corner_rows: np.ndarray
    normals: np.ndarray
    centers: np.ndarray
    curved: np.ndarray
    sphere_centers: np.ndarray
    sphere_radii: np.ndarray

    @cached_property
    def digest(self) -> int:
        """:attr:`ObjectArrays.digest` of the reflectors."""
        return hash(tuple(_CACHE.hash_of(item) for item in self.reflectors))


class SceneIndex:
    """The bounds of everything in a scene, kept in arrays, so that a view can be tested
    against all of them in one vectorised step (:mod:`mirrorlab.culling`): its objects'
    (:class:`ObjectArrays`, as ``index.objects_part``) and its reflectors'
    (:class:`ReflectorArrays`, ``index.reflectors_part``), whose fields it offers as its
    own (``index.parts``, ``index.planar``, ...). Read-only."""

    def __init__(self, objects_part: ObjectArrays, reflectors_part: ReflectorArrays) -> None:
        self.objects_part = objects_part
        self.reflectors_part = reflectors_part
        self.objects = objects_part.objects
        self.reflectors = reflectors_part.reflectors

    @property
    def parts(self) -> tuple[Part, ...]:
        return self.objects_part.parts

    @property
    def models(self) -> np.ndarray:
        return self.objects_part.models

    @property
    def part_low(self) -> np.ndarray:
        return self.objects_part.part_low

    @property
    def part_high(self) -> np.ndarray:
        return self.objects_part.part_high

    @property
    def part_centers(self) -> np.ndarray:
        return self.objects_part.part_centers

    @property
    def part_halves(self) -> np.ndarray:
        return self.objects_part.part_halves

    @property
    def names(self) -> dict[str, int]:
        return self.reflectors_part.names

    @property
    def reflector_low(self) -> np.ndarray:
        return self.reflectors_part.reflector_low

    @property
    def reflector_high(self) -> np.ndarray:
        return self.reflectors_part.reflector_high

    @property
    def planar(self) -> np.ndarray:
        return self.reflectors_part.planar

    @property
    def corner_rows(self) -> np.ndarray:
        return self.reflectors_part.corner_rows

    @property
    def normals(self) -> np.ndarray:
        return self.reflectors_part.normals

    @property
    def centers(self) -> np.ndarray:
        return self.reflectors_part.centers

    @property
    def curved(self) -> np.ndarray:
        return self.reflectors_part.curved

    @property
    def sphere_centers(self) -> np.ndarray:
        return self.reflectors_part.sphere_centers

    @property
    def sphere_radii(self) -> np.ndarray:
        return self.reflectors_part.sphere_radii

    def boxes(self) -> tuple[np.ndarray, np.ndarray]:
        """Every part's box, then every reflector's: low and high ``(n + m, 3)``."""
        return self._boxes

    @cached_property
    def _boxes(self) -> tuple[np.ndarray, np.ndarray]:
        objects, reflectors = self.objects_part, self.reflectors_part
        return (
            read_only(np.concatenate([objects.part_low, reflectors.reflector_low])),
            read_only(np.concatenate([objects.part_high, reflectors.reflector_high])),
        )

    @cached_property
    def sphere(self) -> tuple[np.ndarray, float]:
        """World centre ``(3,)`` and radius of a sphere holding every box (the origin and
        0 when there is none)."""
        low, high = self.boxes()
        if not len(low):
            return np.zeros(3), 0.0
        top = high.max(axis=0)
        center = (low.min(axis=0) + top) / 2.0
        return read_only(center), float(np.linalg.norm(top - center))


class _IndexCache:
    """Scene indexes by the identity of a scene's ``objects`` and ``reflectors`` tuples
    (a frame whose scene differs only in its camera finds its index at once; one whose
    objects alone changed keeps its reflectors' arrays, and the other way round), and
    each object's bounds by the object's identity (a frame in which one object moved
    works out only that one's).

    The last :attr:`KEPT` indexes used are kept, and the arrays of the last :attr:`KEPT`
    objects and reflectors tuples, each found in one dictionary lookup: a program drawing
    several scenes in turn (a renderer each, or one renderer for all) finds each one's
    again, however many objects it holds, and an animation, which makes new objects
    every frame, holds no more than that."""

    KEPT = 32

    def __init__(self) -> None:
        self.indexes: OrderedDict[tuple[int, int], SceneIndex] = OrderedDict()
        # each by its tuple's identity: (the tuple, its arrays)
        self.object_parts: OrderedDict[int, tuple[tuple, ObjectArrays]] = OrderedDict()
        self.reflector_parts: OrderedDict[int, tuple[tuple, ReflectorArrays]] = OrderedDict()
        self.objects: dict[int, tuple[object, ObjectBounds]] = {}
        self.hashes: dict[int, tuple[object, int]] = {}
        self.kept_items = 0
        """How many objects and reflectors the kept arrays hold."""

    def index(self, scene: Scene) -> SceneIndex:
        key = (id(scene.objects), id(scene.reflectors))
        index = self.indexes.get(key)
        if (
            index is not None
            and index.objects is scene.objects
            and index.reflectors is scene.reflectors
        ):
            self.indexes.move_to_end(key)
            return index
        index = SceneIndex(
            self._part(self.object_parts, scene.objects, self.object_arrays),
            self._part(self.reflector_parts, scene.reflectors, self.reflector_arrays),
        )
        self.indexes[key] = index
        if len(self.indexes) > self.KEPT:
            self.indexes.popitem(last=False)
        return index

    def _part(self, kept: OrderedDict, items: tuple, make):
        """The arrays of ``items`` (an objects or reflectors tuple) from ``kept``, or made
        by ``make`` and kept."""
        held = kept.get(id(items))
        if held is not None and held[0] is items:
            kept.move_to_end(id(items))
            return held[1]
        part = make(items)
        kept[id(items)] = (items, part)
        self.kept_items += len(items)
        if len(kept) > self.KEPT:
            _, (dropped, _) = kept.popitem(last=False)
            self.kept_items -= len(dropped)
        return part

    def hash_of(self, item) -> int:
        """``hash(item)``, worked out once while the item lives in a kept scene."""
        held = self.hashes.get(id(item))
        if held is not None and held[0] is item:
            return held[1]
        value = hash(item)
        self.hashes[id(item)] = (item, value)
        return value

    def object_bounds(self, item) -> ObjectBounds:
        held = self.objects.get(id(item))
        if held is not None and held[0] is item:
            return held[1]
        from mirrorlab.scene.robot import object_looks, object_models

        made = ObjectBounds(object_looks(item), object_models(item))
        self.objects[id(item)] = (item, made)
        return made

    def _forget(self, objects: tuple, reflectors: tuple) -> None:
        """Drop what no kept arrays hold, once more than twice what they hold is held:
        the work of a drop is paid for by as many items worked out before it."""
        if (
            len(self.objects) + len(self.hashes)
            <= 2 * (self.kept_items + len(objects) + len(reflectors)) + 512
        ):
            return
        keep = {
            id(item)
            for kept in (self.object_parts, self.reflector_parts)
            for items, _ in kept.values()
            for item in items
        }
        keep |= {id(item) for item in (*objects, *reflectors)}
        self.objects = {key: held for key, held in self.objects.items() if key in keep}
        self.hashes = {key: held for key, held in self.hashes.items() if key in keep}

    def object_arrays(self, objects: tuple) -> ObjectArrays:
        self._forget(objects, ())
        bounds = tuple([self.object_bounds(item) for item in objects])
        models = np.concatenate([b.models for b in bounds]) if bounds else np.zeros((0, 4, 4))
        return ObjectArrays(objects, bounds, tuple([b.looks for b in bounds]), read_only(models))

    def reflector_arrays(self, reflectors: tuple) -> ReflectorArrays:
        self._forget((), reflectors)
        reflector_boxes = [reflector_box(r) for r in reflectors]
        planar = [i for i, r in enumerate(reflectors) if isinstance(r, PlanarReflector)]
        curved = [i for i, r in enumerate(reflectors) if not isinstance(r, PlanarReflector)]
        spheres = [bounding_sphere(reflectors[i]) for i in curved]
        return ReflectorArrays(
            reflectors=reflectors,
            names={r.name: i for i, r in enumerate(reflectors)},
            reflector_low=read_only(np.array([b[0] for b in reflector_boxes]).reshape(-1, 3)),
            reflector_high=read_only(np.array([b[1] for b in reflector_boxes]).reshape(-1, 3)),
            planar=read_only(np.array(planar, dtype=np.intp)),
            corner_rows=read_only(
                culling.quad_rows(
                    np.array(
                        [reflectors[i].corner_array for i in planar], dtype=np.float64
                    ).reshape(-1, 4, 3)
                )
            ),
            normals=read_only(
                np.array([reflectors[i].normal for i in planar], dtype=np.float64).reshape(-1, 3)
            ),
            centers=read_only(
                np.array([reflectors[i].center for i in planar], dtype=np.float64).reshape(-1, 3)
            ),
            curved=read_only(np.array(curved, dtype=np.intp)),
            sphere_centers=read_only(
                np.array([c for c, _ in spheres], dtype=np.float64).reshape(-1, 3)
            ),
            sphere_radii=read_only(np.array([r for _, r in spheres], dtype=np.float64)),
        )


_CACHE = _IndexCache()


def hash_of(item) -> int:
    """``hash(item)``, worked out once while ``item`` lives in a kept scene (a scene's
    background and lights, hashed into every frame's content key)."""
    return _CACHE.hash_of(item)


def scene_index(scene: Scene) -> SceneIndex:
    """The :class:`SceneIndex` of ``scene`` (made once for its objects and reflectors)."""
    return _CACHE.index(scene)


def reflector_index(reflectors: tuple[Reflector, ...]) -> SceneIndex:
    """A :class:`SceneIndex` of ``reflectors`` alone (not kept)."""
    return SceneIndex(_CACHE.object_arrays(()), _CACHE.reflector_arrays(reflectors))


def scene_sphere(scene: Scene) -> tuple[np.ndarray, float]:
    """World centre ``(3,)`` and radius of a sphere holding every object and reflector of
    ``scene`` (the origin and 0 for an empty scene)."""
    return scene_index(scene).sphere


def reach(scene: Scene, eye: np.ndarray) -> float:
    """How far from ``eye`` ``(3,)`` the scene extends: the far side of its bounding
    sphere, with :data:`REACH_MARGIN` to spare (at least a tiny positive distance)."""
    center, radius = scene_sphere(scene)
    distance = float(np.linalg.norm(np.asarray(eye, dtype=np.float64) - center)) + radius
    return max(distance * (1.0 + REACH_MARGIN), 1e-9)


def boxes_but(scene: Scene, leave_out: str) -> tuple[np.ndarray, np.ndarray]:
    """The low and high corners ``(n, 3)`` of the boxes of the scene's object parts and
    reflectors, leaving out the reflector named ``leave_out`` (none when empty)."""
    index = scene_index(scene)
    low, high = index.boxes()
    if leave_out and leave_out in index.names:
        keep = np.ones(len(low), dtype=bool)
        keep[len(index.objects_part) + index.names[leave_out]] = False
        low, high = low[keep], high[keep]
    return low, high


def nearest(scene: Scene, point: np.ndarray, leave_out: str) -> float:
    """The distance from ``point`` ``(3,)`` to the nearest box of the scene's object parts
    and reflectors but ``leave_out`` (inf when there is none)."""
    point = np.asarray(point, dtype=np.float64)
    low, high = boxes_but(scene, leave_out)
    if not len(low):
        return float(np.inf)
    gaps = np.maximum(np.maximum(low - point, point - high), 0.0)
    # The nearest few by a vectorised norm, then each of those exactly as one box's own
    # distance is worked out (the near plane it sets must not move by a rounding).
    rough = np.sqrt(np.einsum("ij,ij->i", gaps, gaps))
    close = np.flatnonzero(rough <= rough.min() * (1.0 + 1e-9) + 1e-300)
    return min(float(np.linalg.norm(gaps[i])) for i in close)


def cube_depth_range(scene: Scene, reflector: CurvedReflector) -> tuple[float, float]:
    """Near and far clip distances of a live cube map's faces: far where the scene ends
    as seen from the capture centre, near half the distance to the nearest other thing
    (a face's near plane then clips nothing: a point d away lies at least d / sqrt(3)
    along a face's axis), never below a millionth of far."""
    center = reflector.center()
    far = reach(scene, center)
    near = 0.5 * nearest(scene, center, reflector.name)
    return float(min(max(near, far * 1e-6), far * 0.5)), far


ENCLOSURE_RAYS = 64
"""Directions (a Fibonacci sphere) :func:`encloses` looks along."""


@lru_cache(maxsize=1)
def _fibonacci_directions(count: int) -> np.ndarray:
    index = np.arange(count) + 0.5
    z = 1.0 - 2.0 * index / count
    angle = np.pi * (1.0 + 5.0**0.5) * index
    rho = np.sqrt(1.0 - z * z)
    directions = np.stack([rho * np.cos(angle), rho * np.sin(angle), z], axis=1)
    directions.flags.writeable = False
    return directions


def encloses(scene: Scene, point: ArrayLike, leave_out: str = "") -> bool:
    """Whether the boxes of the scene's object parts and reflectors (but ``leave_out``)
    close ``point`` in: a ray from it in each of :data:`ENCLOSURE_RAYS` directions meets
    one (a room's walls do; objects under an open sky do not). A live cube map's
    distance search reads it: enclosed, a ray the search finds no surface for meets one
    it cannot see; open, it may leave for the background."""
    low, high = boxes_but(scene, leave_out)
    if not len(low):
        return False
    directions = _fibonacci_directions(ENCLOSURE_RAYS)  # (n, 3)
    origin = np.asarray(point, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / directions[:, None, :]  # (n, 1, 3)
        near = (low[None] - origin) * inverse
        far = (high[None] - origin) * inverse
    # a direction parallel to a slab is within it everywhere (from inside) or nowhere
    parallel = np.broadcast_to(directions[:, None, :] == 0, near.shape)
    inside = np.broadcast_to((origin >= low) & (origin <= high), near.shape)
    first = np.where(parallel, np.where(inside, -np.inf, np.inf), np.minimum(near, far))
    last = np.where(parallel, np.where(inside, np.inf, -np.inf), np.maximum(near, far))
    entry = first.max(axis=2)  # (n, m)
    leave = last.min(axis=2)
    met = (leave >= np.maximum(entry, 0.0)).any(axis=1)
    return bool(met.all())
