"""Parallax-corrected cube-map lookups in numpy: the references the ``cube-live`` shader's
proxy paths (``shaders/parallax.glsl``) are checked against.

A cube map captured from a point ``center`` treats everything it saw as infinitely far
away: a surface point ``origin`` looks it up along its reflected ray ``direction`` as if
the ray started at ``center``. A proxy says where the surroundings really are: the
ray is followed from ``origin`` to where it meets them, and the map is looked up
towards that point from ``center``.

- :func:`box_lookup`: the surroundings are an axis-aligned box (a room).
- :func:`sphere_lookup`: a sphere of a given radius around ``center``.
- :func:`distance_lookup`: the capture also kept how far away each texel's surface
  is; the ray is searched for the point whose distance from ``center`` meets the
  stored one (a linear search, then secant steps), as in distance-impostor ray
  tracing on the GPU.

Arrays are ``(..., 3)`` world-space points and directions, broadcast against each
other; every function returns unit lookup directions ``(..., 3)`` in the common float
dtype of its inputs. The numerics promise: for any finite input the result is finite.
Where the correction has no answer (the ray starts outside the proxy, the proxy is
empty, the surface point is behind what the capture saw) the lookup falls back to the
plain one, the unit ``direction``; a zero ``direction`` gives zero. Rays parallel to a
box face are handled without dividing by zero. Numpy only.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mirrorlab.envmap import cube_map

InverseDistance = Callable[[np.ndarray], np.ndarray]
"""What a distance capture holds: unit directions ``(n, 3)`` from the capture centre ->
``(n,)`` the inverse of the distance to the first surface that way (0: nothing, the
background at infinity)."""

PARALLEL = 1e-20
"""A direction component at most this large counts as zero: the ray runs parallel to
that pair of box faces (the shader uses the same threshold)."""
REFINE_STEPS = 4
"""A distance search looks at a step in which the ray crosses the stored surface again in
this many smaller steps (the shader's REFINE_STEPS)."""
AT_CENTER = 1e-6
"""How close (world units) a surface point may come to the capture centre before the
distance search gives up on it: there the plain lookup is exact anyway."""


def _floats(*arrays) -> list[np.ndarray]:
    converted = [np.asarray(a) for a in arrays]
    converted = [
        a
        if np.issubdtype(a.dtype, np.floating) and a.dtype != np.float16
        else a.astype(np.float32 if a.dtype == np.float16 else np.float64)
        for a in converted
    ]
    dtype = np.result_type(*converted)
    return [a.astype(dtype, copy=False) for a in converted]


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``v`` scaled to unit length (largest component divided out first, so tiny and huge
    vectors normalise) and a mask of the non-zero rows; zero rows stay zero."""
    scale = np.max(np.abs(v), axis=-1, keepdims=True)
    nonzero = scale > 0
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        w = v / np.where(nonzero, scale, 1)
        w = w / np.where(nonzero, np.sqrt(np.sum(w * w, axis=-1, keepdims=True)), 1)
    return w, nonzero[..., 0]


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=-1)


def _prepare(origin, direction, center, *more):
    arrays = _floats(origin, direction, center, *more)
    for name, array in zip(("origin", "direction", "center"), arrays, strict=False):
        if array.ndim == 0 or array.shape[-1] != 3:
            raise ValueError(f"{name} must have shape (..., 3), got {array.shape}")
    return np.broadcast_arrays(*arrays)


def _towards(hit_from_center: np.ndarray, plain: np.ndarray, use: np.ndarray) -> np.ndarray:
    """The unit direction of ``hit_from_center`` where ``use`` and it is non-zero, else
    ``plain``."""
    look, nonzero = _unit(np.where(use[..., None], hit_from_center, 0))
    return np.where((use & nonzero)[..., None], look, plain)


def box_exit(origin, direction, box_min, box_max) -> np.ndarray:
    """How far along ``direction`` (unit, ``(..., 3)``) a ray from ``origin`` inside the box
    leaves it: ``(...)`` (the nearest of the three far faces; a component within
    :data:`PARALLEL` of zero never reaches its faces). Meaningful only for origins inside
    the box; finite for unit directions."""
    origin, direction, box_min, box_max = _floats(origin, direction, box_min, box_max)
    huge = np.finfo(origin.dtype).max
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ahead = np.where(direction > 0, box_max - origin, box_min - origin)
        steps = np.where(
            np.abs(direction) > PARALLEL,
            ahead / np.where(np.abs(direction) > PARALLEL, direction, 1),
            huge,
        )
    return np.min(np.maximum(steps, 0), axis=-1)


def box_lookup(origin, direction, center, box_min, box_max) -> np.ndarray:
    """The lookup direction ``(..., 3)`` for a box proxy: where the ray from ``origin``
    along ``direction`` leaves the axis-aligned box ``box_min`` - ``box_max`` (world
    corners, ``(..., 3)``), seen from the capture ``center``.

    Falls back to the plain direction when ``origin`` is outside the box (faces
    included in the inside), when the box is empty (a ``min`` not below its ``max``) and
    when the exit point is the centre itself.
    """
    origin, direction, center, box_min, box_max = _prepare(
        origin, direction, center, box_min, box_max
    )
    plain, moving = _unit(direction)
    inside = moving & (
        np.all(origin >= box_min, axis=-1)
        & np.all(origin <= box_max, axis=-1)
        & np.all(box_min < box_max, axis=-1)
    )
    distance = box_exit(
        np.where(inside[..., None], origin, 0),
        plain,
        np.where(inside[..., None], box_min, -1),
        np.where(inside[..., None], box_max, 1),
    )
    hit = origin + distance[..., None] * plain
    with np.errstate(invalid="ignore", over="ignore"):
        return _towards(hit - center, plain, inside & np.all(np.isfinite(hit - center), -1))


def sphere_lookup(origin, direction, center, radius) -> np.ndarray:
    """The lookup direction ``(..., 3)`` for a sphere proxy of ``radius`` ``(...)`` around
    the capture ``center``: where the ray from ``origin`` along ``direction`` leaves the
    sphere, seen from the centre.

    Falls back to the plain direction when ``origin`` is outside the sphere (or the
    radius is not positive). The exit distance is ``-b + sqrt(b^2 - q)`` with
    ``b = (origin - center) . direction`` and ``q = |origin - center|^2 - radius^2 <= 0``,
    written as ``-q / (b + sqrt(b^2 - q))`` when ``b > 0``, so neither form cancels.
    """
    origin, direction, center = _prepare(origin, direction, center)
    (radius,) = _floats(radius)
    radius = radius.astype(origin.dtype, copy=False)
    plain, moving = _unit(direction)
    offset = origin - center
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        q = _dot(offset, offset) - radius * radius
        inside = moving & (radius > 0) & (q <= 0)
        b = _dot(offset, plain)
        root = np.sqrt(np.maximum(b * b - q, 0))
        denominator = b + root
        leaving = np.where(b > 0, -q / np.where(denominator > 0, denominator, 1), root - b)
        distance = np.where(inside, np.maximum(leaving, 0), 0)
        hit_from_center = offset + distance[..., None] * plain
    return _towards(hit_from_center, plain, inside & np.all(np.isfinite(hit_from_center), axis=-1))


def distance_lookup(
    origin,
    direction,
    center,
    inverse_distance: InverseDistance,
    steps: int = 8,
    secant: int = 2,
    thickness: float = 0.1,
    enclosed: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """The lookup direction ``(..., 3)`` found by searching the ray for the surface the
    capture saw, from the capture's ``inverse_distance`` (see :data:`InverseDistance`), and
    ``(...)`` True where the lookup is to be made in the background rather than the
    capture (the search found no surface, and the capture saw nothing along the plain
    direction either).

    With ``x = origin - center`` and ``s = |x|``, the ray's points are visited as
    ``center + l(t) / (1 - t)`` with ``l(t) = (1 - t) x + t s direction`` for ``t`` in
    [0, 1]: ``t = 0`` is the origin, ``t = 1`` the ray's end at infinity, and the lookup
    direction ``l(t)`` sweeps evenly from ``x`` to ``direction``. The point is in front of
    the captured surface while ``H(t) = s (1 - t) / |l(t)| - s w(l(t))`` is positive
    (``w`` the stored inverse distance). A linear search takes ``steps`` equal steps of
    ``t``; wherever ``H`` turns from positive to not, ``secant`` regula-falsi steps narrow
    the crossing (each secant point written from the bracket's far end, so that a
    crossing at ``H = 0`` exactly, the background at ``t = 1``, stays there). The stored
    distances are a height field seen from the centre, so a ray that passes behind an
    object (from the centre's view) crosses its surface without meeting it: a crossing
    counts as a hit only when its secant point is short of infinity and the last point
    probed lies within ``thickness`` (relative to its distance from the centre) of the
    stored surface (with no secant steps, every crossing short of infinity is a hit);
    else the search goes on. A step that ends behind the stored surface is looked at
    again in :data:`REFINE_STEPS` smaller ones and each crossing found there judged in
    turn: one step may hide the ray passing behind an object, coming out past its
    silhouette and meeting the wall behind it, which the steps' own points never show. A hit is the
    secant point of its last bracket. A ray with no hit passed behind what the capture
    saw, or met what it could not see: where the surroundings close the centre in
    (``enclosed``: a room, :func:`mirrorlab.bounds.encloses`) it falls back to the plain
    lookup, the plain direction in the capture (in the background where the capture saw
    nothing that way either), and otherwise leaves for the background.

    Falls back to the plain direction (in the capture) when the origin is at the centre
    (within :data:`AT_CENTER`, where the plain lookup is exact) or already behind the
    captured surface (``H(0) <= 0``: the capture does not see the origin's
    surroundings).
    """
    if int(steps) != steps or steps < 1:
        raise ValueError(f"steps must be a whole number of at least 1, got {steps!r}")
    if int(secant) != secant or secant < 0:
        raise ValueError(f"secant must be a whole number of at least 0, got {secant!r}")
    if not thickness > 0:
        raise ValueError(f"thickness must be a positive number, got {thickness!r}")
    origin, direction, center = _prepare(origin, direction, center)
    plain, moving = _unit(direction)
    offset = origin - center
    with np.errstate(over="ignore", invalid="ignore"):
        size = np.sqrt(_dot(offset, offset))
    usable = moving & np.isfinite(size) & (size > AT_CENTER)
    size = np.where(usable, size, 1)
    offset = np.where(usable[..., None], offset, 0)
    shape = size.shape
    dtype = size.dtype

    def towards(t: np.ndarray) -> np.ndarray:
        return (1 - t)[..., None] * offset + (t * size)[..., None] * plain

    def probe(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """H and the relative depth mismatch at ``t`` (both ``shape``)."""
        look = towards(t)
        length = np.sqrt(_dot(look, look))
        unit, _ = _unit(look)
        unit = np.where((length > AT_CENTER * size)[..., None], unit, plain)
        inverse = np.asarray(inverse_distance(unit.reshape(-1, 3)), dtype=dtype).reshape(shape)
        length = np.maximum(length, AT_CENTER * size)
        with np.errstate(divide="ignore", invalid="ignore"):
            mismatch = np.where(
                t < 1,
                length * inverse / np.where(t < 1, 1 - t, 1) - 1,
                np.where(inverse > 0, np.inf, 0),
            )
        return size * (1 - t) / length - size * inverse, mismatch

    h_before, _ = probe(np.zeros(shape, dtype))
    done = ~(usable & (h_before > 0))
    found = np.zeros(shape, bool)
    hit = np.zeros(shape, dtype)
    t_before = np.zeros(shape, dtype)
    for k in range(1, int(steps) + 1):
        t_after = np.full(shape, k / steps, dtype)
        h_after, _ = probe(t_after)
        crossing = ~done & (h_after <= 0)
        if crossing.any():
            # a step that ends behind the stored surface, again in REFINE_STEPS smaller
            # ones, each crossing there narrowed and judged in turn (a step may hide the
            # ray passing behind an object, coming out past its silhouette and meeting
            # the wall behind it)
            sub_before, sh_before = t_before.copy(), h_before.copy()
            mismatch = np.zeros(shape, dtype)
            for j in range(1, REFINE_STEPS + 1):
                if j == REFINE_STEPS:
                    sub_after, sh_after = t_after, h_after
                else:
                    fraction = np.asarray(j / REFINE_STEPS, dtype)
                    sub_after = t_before * (1 - fraction) + t_after * fraction
                    sh_after, mismatch = probe(sub_after)
                inner = crossing & ~done & (sh_before > 0) & (sh_after <= 0)
                if inner.any():
                    low, h_low = sub_before.copy(), sh_before.copy()
                    high, h_high = sub_after.copy(), sh_after.copy()
                    for _ in range(int(secant)):
                        t = np.where(inner, _secant(low, h_low, high, h_high), high)
                        h, mismatch = probe(t)
                        behind = h <= 0
                        high, h_high = np.where(behind, t, high), np.where(behind, h, h_high)
                        low, h_low = np.where(behind, low, t), np.where(behind, h_low, h)
                    t = np.where(inner, _secant(low, h_low, high, h_high), high)
                    judged = np.abs(mismatch) <= thickness if secant else True
                    accept = inner & (t < 1) & judged
                    hit = np.where(accept, t, hit)
                    found |= accept
                    done |= accept
                sub_before, sh_before = sub_after, sh_after
        t_before, h_before = t_after, h_after
    seen_plainly = (
        np.asarray(inverse_distance(plain.reshape(-1, 3)), dtype=dtype).reshape(shape) > 0
    )
    background = usable & ~done & ~(seen_plainly & bool(enclosed))
    look = _towards(towards(hit), plain, found)
    return look, background


def _secant(low, h_low, high, h_high):
    """Where ``H`` (positive at ``low``, not at ``high``) is zero if linear between them,
    written from ``high`` so that ``H(high) = 0`` gives ``high`` exactly."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return high + (high - low) * h_high / (h_low - h_high)


def inverse_distance_from_depth(depth, directions, near: float, far: float) -> np.ndarray:
    """The inverse distance ``(...)`` from a cube capture's centre to what its depth buffer
    holds: ``depth`` ``(...)`` in [0, 1] read in the unit ``directions`` ``(..., 3)``, each
    face a 90-degree perspective view with clip distances ``near`` and ``far``. The
    depth gives the distance along the face's axis, ``Z = 2 f n / (f + n - (2 d - 1)(f -
    n))``; along a direction whose largest component is ``a`` the distance is ``Z / a``.
    Depth 1 (the far plane: the sky, or nothing drawn) is the background: 0."""
    depth = np.asarray(depth, dtype=np.float64)
    directions = np.asarray(directions, dtype=np.float64)
    major = np.max(np.abs(directions), axis=-1)
    inverse_z = (far + near - (2 * depth - 1) * (far - near)) / (2 * far * near)
    return np.where(depth >= 1.0, 0.0, major * inverse_z)


def nearest_cube_texel(faces: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """What ``GL_NEAREST`` sampling of a cube map reads in ``directions`` ``(..., 3)``:
    ``faces`` ``(6, n, n, ...)`` in GL face order with row 0 at the top (``t = 1``, as
    :func:`mirrorlab.envmap.bake_cube_faces` makes them). Returns ``(..., ...)``."""
    faces = np.asarray(faces)
    size = faces.shape[1]
    face, s, t = cube_map(directions)
    column = np.clip(np.floor(s * size).astype(np.int64), 0, size - 1)
    row = size - 1 - np.clip(np.floor(t * size).astype(np.int64), 0, size - 1)
    return faces[face, row, column]


def depth_capture(faces: np.ndarray, near: float, far: float) -> InverseDistance:
    """The :data:`InverseDistance` of a captured depth cube ``faces`` ``(6, n, n)`` (depth in
    [0, 1], row 0 at the top) sampled as the shader samples it (nearest texel)."""

    def inverse_distance(directions: np.ndarray) -> np.ndarray:
        return inverse_distance_from_depth(
            nearest_cube_texel(faces, directions), directions, near, far
        )

    return inverse_distance


def box_distance(center, box_min, box_max) -> InverseDistance:
    """The :data:`InverseDistance` a capture from ``center`` inside an empty box room
    would hold (for checks: the distance search in such a room is the box proxy)."""
    center = np.asarray(center, dtype=np.float64)

    def inverse_distance(directions: np.ndarray) -> np.ndarray:
        exit_distance = box_exit(
            np.broadcast_to(center, directions.shape), directions, box_min, box_max
        )
        with np.errstate(divide="ignore"):
            return np.where(exit_distance > 0, 1 / exit_distance, 0.0)

    return inverse_distance
