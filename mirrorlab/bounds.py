"""How far things reach: bounding spheres and boxes of a scene's meshes, reflectors and
of the whole scene, in world units. What the planner sizes views by (a live capture sees
as far as the scene extends, and no nearer than its nearest neighbour). Numpy only; a
mesh file is read once (:func:`mirrorlab.scene.mesh.load_mesh`) and its bounds kept.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Reflector, Scene

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


@lru_cache(maxsize=32)
def _boxes(objects: tuple, reflectors: tuple) -> tuple[tuple[str, np.ndarray, np.ndarray], ...]:
    from mirrorlab.scene.robot import scene_parts

    scene = Scene(name="bounds", objects=objects, reflectors=reflectors)
    boxes = [("", *mesh_box(part.mesh, part.model)) for part in scene_parts(scene)]
    boxes += [(r.name, *reflector_box(r)) for r in reflectors]
    return tuple(boxes)


def scene_boxes(scene: Scene) -> tuple[tuple[str, np.ndarray, np.ndarray], ...]:
    """``(reflector name or "", min (3,), max (3,))`` of every object part and reflector."""
    return _boxes(scene.objects, scene.reflectors)


def scene_sphere(scene: Scene) -> tuple[np.ndarray, float]:
    """World centre ``(3,)`` and radius of a sphere holding every object and reflector of
    ``scene`` (the origin and 0 for an empty scene)."""
    boxes = scene_boxes(scene)
    if not boxes:
        return np.zeros(3), 0.0
    low = np.min([b[1] for b in boxes], axis=0)
    high = np.max([b[2] for b in boxes], axis=0)
    center = (low + high) / 2.0
    return center, float(np.linalg.norm(high - center))


def reach(scene: Scene, eye: np.ndarray) -> float:
    """How far from ``eye`` ``(3,)`` the scene extends: the far side of its bounding
    sphere, with :data:`REACH_MARGIN` to spare (at least a tiny positive distance)."""
    center, radius = scene_sphere(scene)
    distance = float(np.linalg.norm(np.asarray(eye, dtype=np.float64) - center)) + radius
    return max(distance * (1.0 + REACH_MARGIN), 1e-9)


def nearest(scene: Scene, point: np.ndarray, leave_out: str) -> float:
    """The distance from ``point`` ``(3,)`` to the nearest box of the scene's object parts
    and reflectors but ``leave_out`` (inf when there is none)."""
    point = np.asarray(point, dtype=np.float64)
    best = np.inf
    for name, low, high in scene_boxes(scene):
        if name == leave_out and name:
            continue
        gap = np.maximum(np.maximum(low - point, point - high), 0.0)
        best = min(best, float(np.linalg.norm(gap)))
    return best


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
    angle = np.pi * (1.0 + 5.0 ** 0.5) * index
    rho = np.sqrt(1.0 - z * z)
    directions = np.stack([rho * np.cos(angle), rho * np.sin(angle), z], axis=1)
    directions.flags.writeable = False
    return directions


def encloses(scene: Scene, point: np.ndarray, leave_out: str = "") -> bool:
    """Whether the boxes of the scene's object parts and reflectors (but ``leave_out``)
    close ``point`` in: a ray from it in each of :data:`ENCLOSURE_RAYS` directions meets
    one (a room's walls do; objects under an open sky do not). A live cube map's
    distance search reads it: enclosed, a ray the search finds no surface for meets one
    it cannot see; open, it may leave for the background."""
    boxes = [(low, high) for name, low, high in scene_boxes(scene)
             if not (name and name == leave_out)]
    if not boxes:
        return False
    low = np.array([b[0] for b in boxes])  # (m, 3)
    high = np.array([b[1] for b in boxes])
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
