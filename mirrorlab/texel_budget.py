"""The same texel budget for every map: the numpy half of the study (``bench/texel_budget.py``
adds FLIP on the chrome sphere).

Each map of directions (:data:`MAPS`) is laid out as mirrorlab's shader reads it
(:mod:`mirrorlab.envmap`): the cube's six faces; the octahedral square with its one-texel
border; the dual paraboloid's two squares with their margin around the discs; the
latitude-longitude map twice as wide as high; the sphere map's one square (a view's
eye space taken as the world's). For a budget of texels (level 0, borders and margins
counted, every texel stored), :func:`layout_for_budget` gives each map its size, and
then:

- :func:`lookup_error`: the angle between a direction and the direction the map gives
  back for it, over directions spread uniformly over the sphere: with nearest
  filtering, the centre of the texel it falls in; with bilinear filtering, the four
  nearest texel centres' directions weighted as the filter weights their colours (how
  far off a smooth environment is read back), each as mean, 95th percentile and worst;
- :func:`texel_solid_angles`: every texel's solid angle (its area on the sphere of
  directions), from the map's Jacobian at 2 x 2 points of the texel; the largest over
  the smallest is the map's texel solid-angle ratio (over the texels a lookup can land
  in: the disc's for the paraboloid and the sphere map, the interior's for the
  octahedral map).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mirrorlab import envmap

MAPS = ("cube", "octahedral", "paraboloid", "latlong", "sphere")
"""The maps compared, by the name of their static technique."""

Directions = np.ndarray
"""``(n, 3)`` float64 unit vectors."""


@dataclass(frozen=True)
class Layout:
    """A map's texels: ``kind`` (one of :data:`MAPS`) and ``size`` (the technique's
    ``map_size``: a cube face's edge, the octahedral square's, a paraboloid half's edge,
    the latitude-longitude map's height, the sphere map's edge)."""

    kind: str
    size: int

    @property
    def texels(self) -> int:
        """How many texels level 0 stores."""
        n = self.size
        return {"cube": 6, "octahedral": 1, "paraboloid": 2, "latlong": 2, "sphere": 1}[
            self.kind
        ] * (n * n)


def layout_for_budget(kind: str, budget: float) -> Layout:
    """The largest map of ``kind`` whose level 0 holds no more than ``budget`` texels."""
    per_square = {"cube": 6, "octahedral": 1, "paraboloid": 2, "latlong": 2, "sphere": 1}
    if kind not in per_square:
        raise ValueError(f"unknown map {kind!r}; expected one of {', '.join(MAPS)}")
    size = int(np.floor(np.sqrt(budget / per_square[kind]) + 1e-9))
    if size < 4:
        raise ValueError(f"a budget of {budget} texels is too small for a {kind} map")
    return Layout(kind, size)


# --------------------------------------------------------------------------- texel grids


def _grid_directions(layout: Layout, i: np.ndarray, j: np.ndarray, face: np.ndarray):
    """The directions ``(..., 3)`` at texel positions ``i`` (column, fractional: a centre
    at ``k + 0.5``), ``j`` (row from the bottom) of ``face`` (the cube's face, the
    paraboloid's side, else 0)."""
    n = layout.size
    if layout.kind == "cube":
        return envmap.cube_face_direction(face, i / n, j / n)
    if layout.kind == "octahedral":
        interior = n - 2
        return envmap.octahedral_map_inverse((i - 1) / interior, (j - 1) / interior)
    if layout.kind == "paraboloid":
        return envmap.paraboloid_map_inverse(face, i / n, j / n)
    if layout.kind == "latlong":
        return envmap.latlong_map_inverse(i / (2 * n), j / n)
    return envmap.sphere_map_inverse(i / n, j / n)


def _positions(layout: Layout, r: Directions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each direction ``r`` is looked up: texel-space ``(i, j, face)`` as
    :func:`_grid_directions` takes them."""
    n = layout.size
    zero = np.zeros(len(r), dtype=np.int64)
    if layout.kind == "cube":
        face, s, t = envmap.cube_map(r)
        return s * n, t * n, face
    if layout.kind == "octahedral":
        s, t = envmap.octahedral_map(r)
        return 1 + s * (n - 2), 1 + t * (n - 2), zero
    if layout.kind == "paraboloid":
        side, s, t = envmap.paraboloid_map(r)
        return s * n, t * n, side
    if layout.kind == "latlong":
        s, t = envmap.latlong_map(r)
        return s * 2 * n, t * n, zero
    s, t = envmap.sphere_map(r)
    return s * n, t * n, zero


def _width(layout: Layout) -> int:
    return 2 * layout.size if layout.kind == "latlong" else layout.size


def _angles(a: Directions, b: Directions) -> np.ndarray:
    """Angles in degrees between unit rows, accurate for small ones."""
    cross = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(cross, np.sum(a * b, axis=-1)))


def uniform_directions(count: int, seed: int = 0) -> Directions:
    """``count`` directions spread uniformly over the sphere (normalised Gaussians)."""
    v = np.random.default_rng(seed).normal(size=(count, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def nearest_lookup(layout: Layout, r: Directions) -> Directions:
    """The direction of the centre of the texel each of ``r`` falls in."""
    i, j, face = _positions(layout, r)
    width = _width(layout)
    ci = np.clip(np.floor(i), 0, width - 1) + 0.5
    cj = np.clip(np.floor(j), 0, layout.size - 1) + 0.5
    if layout.kind == "latlong":
        ci = np.floor(i) % width + 0.5
    return _grid_directions(layout, ci, cj, face)


def bilinear_lookup(layout: Layout, r: Directions) -> Directions:
    """What a bilinear filter gives back for each of ``r`` when each texel holds its
    centre's direction: the four nearest centres' directions, weighted as GL weights
    them (clamped to the edge of a face or square, wrapped around the
    latitude-longitude map's seam; the octahedral border holds what lies across its
    edges), normalised."""
    i, j, face = _positions(layout, r)
    width = _width(layout)
    fi, fj = i - 0.5, j - 0.5
    i0, j0 = np.floor(fi), np.floor(fj)
    wi, wj = fi - i0, fj - j0
    total = np.zeros_like(r)
    for di in (0, 1):
        for dj in (0, 1):
            weight = (wi if di else 1 - wi) * (wj if dj else 1 - wj)
            ci, cj = i0 + di, j0 + dj
            if layout.kind == "latlong":
                ci = ci % width
            else:
                ci = np.clip(ci, 0, width - 1)
            cj = np.clip(cj, 0, layout.size - 1)
            total += weight[:, None] * _grid_directions(layout, ci + 0.5, cj + 0.5, face)
    return total / np.linalg.norm(total, axis=-1, keepdims=True)


@dataclass(frozen=True)
class AngularError:
    """Angles in degrees: ``mean``, ``p95`` and ``worst`` of the nearest texel's
    direction, and ``bilinear_mean``, ``bilinear_worst`` of the bilinear filter's."""

    mean: float
    p95: float
    worst: float
    bilinear_mean: float
    bilinear_worst: float


def lookup_error(layout: Layout, directions: Directions, chunk: int = 200_000) -> AngularError:
    """:class:`AngularError` of ``layout`` over ``directions`` (``(n, 3)`` unit)."""
    nearest, bilinear = [], []
    for start in range(0, len(directions), chunk):
        r = directions[start : start + chunk]
        nearest.append(_angles(r, nearest_lookup(layout, r)))
        bilinear.append(_angles(r, bilinear_lookup(layout, r)))
    near, blend = np.concatenate(nearest), np.concatenate(bilinear)
    return AngularError(
        float(near.mean()),
        float(np.percentile(near, 95)),
        float(near.max()),
        float(blend.mean()),
        float(blend.max()),
    )


# --------------------------------------------------------------------------- solid angles


def _faces(layout: Layout) -> tuple[int, ...]:
    return {"cube": tuple(range(6)), "paraboloid": (0, 1)}.get(layout.kind, (0,))


def texel_solid_angles(layout: Layout) -> np.ndarray:
    """The solid angle (steradians) of every texel a lookup can land in, flat: the area
    on the unit sphere of the directions the texel stands for, from the cross product of
    the map's derivatives at 2 x 2 points of the texel (the map's Jacobian, by central
    differences). Only the texels wholly inside what a lookup reaches count: not the
    octahedral border, and of the paraboloid and the sphere map only the texels wholly
    inside the disc (the rim's texels, partly outside it, hold part of a texel's worth
    of directions). The octahedral and cube texels' sum is 4 pi."""
    n = layout.size
    width = _width(layout)
    h = 1e-4
    quarter = (0.25, 0.75)
    found = []
    for face in _faces(layout):
        ii, jj = np.meshgrid(np.arange(width, dtype=np.float64), np.arange(n, dtype=np.float64))
        area = np.zeros_like(ii)
        for a in quarter:
            for b in quarter:
                x, y = ii + a, jj + b
                f = np.full(x.shape, face)
                dx = _grid_directions(layout, x + h, y, f) - _grid_directions(layout, x - h, y, f)
                dy = _grid_directions(layout, x, y + h, f) - _grid_directions(layout, x, y - h, f)
                area += np.linalg.norm(np.cross(dx, dy), axis=-1) / (4 * h * h) / 4
        keep = np.ones(area.shape, dtype=bool)
        # the corner of the texel furthest from the square's centre
        far_i = np.maximum(np.abs(ii / n - 0.5), np.abs((ii + 1) / n - 0.5))
        far_j = np.maximum(np.abs(jj / n - 0.5), np.abs((jj + 1) / n - 0.5))
        if layout.kind == "octahedral":
            keep = (ii >= 1) & (ii <= n - 2) & (jj >= 1) & (jj <= n - 2)
        elif layout.kind == "paraboloid":
            keep = np.hypot(far_i, far_j) <= 0.5 / envmap.PARABOLOID_EXTENT
        elif layout.kind == "sphere":
            keep = np.hypot(far_i, far_j) <= 0.5
        found.append(area[keep])
    return np.concatenate(found)


def solid_angle_ratio(layout: Layout) -> float:
    """The largest texel solid angle over the smallest (:func:`texel_solid_angles`)."""
    angles = texel_solid_angles(layout)
    return float(angles.max() / angles.min())


def used_share(layout: Layout) -> float:
    """The share of the stored texels a lookup can land in."""
    return len(texel_solid_angles(layout)) / layout.texels


def largest_texel(layout: Layout) -> float:
    """The largest texel solid angle (steradians): the map's coarsest texel."""
    return float(texel_solid_angles(layout).max())


def matching_budget(
    kind: str, target: float, low: int = 4, high: int = 16384, measure: Callable = largest_texel
) -> Layout:
    """The smallest map of ``kind`` whose :func:`largest_texel` (or ``measure``) is at most
    ``target``: bisection over the size."""
    while low < high:
        middle = (low + high) // 2
        if measure(Layout(kind, middle)) <= target:
            high = middle
        else:
            low = middle + 1
    return Layout(kind, low)
