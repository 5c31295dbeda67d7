"""Where a reflector can show in a view, and how many pixels it can cover there: its
footprint, worked out so that it errs large, never small. Numpy only.

A planar mirror's footprint is its quad clipped against the view volume in clip space
(Sutherland-Hodgman against the six planes ``-w <= x, y, z <= w`` and the view's own clip
plane), then projected: a convex polygon in window coordinates, with its area. Clipping
in clip space, before the divide by ``w``, is what keeps a quad that reaches behind the
eye or across a corner of the view correct (clamping each projected corner to the screen
on its own collapses a long thin mirror crossing the view to a line).

A curved reflector's footprint is that of its bounding sphere: the sphere's silhouette
seen from a perspective eye is an ellipse (the cone of rays touching the sphere, cut by
the image plane; exact, not the small-angle circle, so it grows off-axis as the sphere
does), from an orthographic view a circle; the ellipse is replaced by a polygon drawn
around it (so that it contains it) and clipped to the screen. A sphere that reaches the
eye's plane covers the whole screen, as far as its footprint tells.

Pixel coordinates are GL window coordinates: x from the left edge, y from the *bottom*
edge, in pixels (what ``glScissor`` takes). A pixel is drawn where its centre is
covered, so a footprint counts as covering every pixel whose square its polygon touches:
:attr:`Footprint.pixels` is the area of the polygon grown by half a pixel on every side
(its Minkowski sum with a pixel), an upper bound on the pixels it can colour, and
:attr:`Footprint.bounds` the pixel rectangle they lie in. Both are what a later pass may
use to skip or scissor work without changing a pixel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SLACK = 1e-6
"""Relative widening of the view volume while clipping: float rounding never drops a
polygon the rasteriser would still draw a pixel of."""
ELLIPSE_SIDES = 32
"""Sides of the polygon drawn around a projected sphere's ellipse."""


@dataclass(frozen=True)
class Footprint:
    """What a reflector covers in a view of ``size`` (width, height) pixels.

    ``polygon`` ``(k, 2)`` float64: the convex outline in window coordinates (empty when
    nothing is in view); ``area``: its area in pixels.
    """

    polygon: np.ndarray
    area: float
    size: tuple[int, int]

    @property
    def empty(self) -> bool:
        """True when no pixel can be covered."""
        return len(self.polygon) < 3 or self.bounds is None

    @property
    def pixels(self) -> float:
        """An upper bound on the pixels covered: the polygon's area grown by half a pixel
        each way (area + width + height of its bounding box + 1), and at most the pixels
        of :attr:`bounds`. 0 when empty."""
        bounds = self.bounds
        if len(self.polygon) < 3 or bounds is None:
            return 0.0
        extent = self.polygon.max(axis=0) - self.polygon.min(axis=0)
        grown = self.area + float(extent[0] + extent[1]) + 1.0
        return float(min(grown, bounds[2] * bounds[3]))

    @property
    def bounds(self) -> tuple[int, int, int, int] | None:
        """``(x, y, width, height)``: the smallest pixel rectangle holding every pixel the
        footprint may cover (GL window coordinates, for ``glScissor``), None when it holds
        none."""
        if len(self.polygon) < 3:
            return None
        width, height = self.size
        low = self.polygon.min(axis=0)
        high = self.polygon.max(axis=0)
        # Pixel i is covered when its centre i + 0.5 lies inside: i from ceil(low - 0.5)
        # to floor(high - 0.5); one more each way for the rasteriser's rounding.
        x0 = max(int(np.floor(low[0] - 0.5)), 0)
        y0 = max(int(np.floor(low[1] - 0.5)), 0)
        x1 = min(int(np.ceil(high[0] - 0.5)), width - 1)
        y1 = min(int(np.ceil(high[1] - 0.5)), height - 1)
        if x1 < x0 or y1 < y0:
            return None
        return x0, y0, x1 - x0 + 1, y1 - y0 + 1

    def rectangle(self, margin: int = 0) -> tuple[int, int, int, int] | None:
        """:attr:`bounds` grown by ``margin`` pixels each way, within the target."""
        bounds = self.bounds
        if bounds is None:
            return None
        width, height = self.size
        x0, y0 = max(bounds[0] - margin, 0), max(bounds[1] - margin, 0)
        x1 = min(bounds[0] + bounds[2] + margin, width)
        y1 = min(bounds[1] + bounds[3] + margin, height)
        return x0, y0, x1 - x0, y1 - y0


def empty_footprint(size: tuple[int, int]) -> Footprint:
    return Footprint(np.zeros((0, 2)), 0.0, (int(size[0]), int(size[1])))


def full_screen(size: tuple[int, int]) -> Footprint:
    """The whole screen of ``size`` (width, height) pixels."""
    width, height = float(size[0]), float(size[1])
    polygon = np.array([[0.0, 0.0], [width, 0.0], [width, height], [0.0, height]])
    return Footprint(polygon, width * height, (int(size[0]), int(size[1])))


# --------------------------------------------------------------------------- clipping


def clip_polygon(points: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """Sutherland-Hodgman: the convex polygon ``points`` ``(n, d)`` clipped to where
    ``points @ plane >= 0`` for every row of ``planes`` ``(m, d)``. Returns ``(k, d)``
    (k may be 0). Works in any dimension; in homogeneous clip space (d = 4) it clips
    against the view volume before anything is divided by ``w``."""
    polygon = np.asarray(points, dtype=np.float64)
    for plane in np.asarray(planes, dtype=np.float64):
        if len(polygon) == 0:
            break
        side = polygon @ plane
        inside = side >= 0.0
        if inside.all():
            continue
        if not inside.any():
            return polygon[:0]
        kept = []
        count = len(polygon)
        for i in range(count):
            j = (i + 1) % count
            if inside[i]:
                kept.append(polygon[i])
            if inside[i] != inside[j]:
                t = side[i] / (side[i] - side[j])
                kept.append(polygon[i] + t * (polygon[j] - polygon[i]))
        polygon = np.array(kept)
    return polygon


def polygon_area(polygon: np.ndarray) -> float:
    """Area of a simple polygon ``(k, 2)`` (shoelace formula), 0 for fewer than 3 points."""
    if len(polygon) < 3:
        return 0.0
    x, y = polygon[:, 0], polygon[:, 1]
    twice = x[:-1] @ y[1:] - y[:-1] @ x[1:] + x[-1] * y[0] - y[-1] * x[0]
    return float(abs(twice) / 2.0)


def view_volume_planes(slack: float = SLACK) -> np.ndarray:
    """``(6, 4)``: the view volume ``-w <= x, y, z <= w`` as planes of homogeneous clip
    coordinates (inside where ``point @ plane >= 0``), widened by ``slack`` of ``w``."""
    w = 1.0 + slack
    return np.array(
        [
            [1.0, 0, 0, w],
            [-1.0, 0, 0, w],
            [0, 1.0, 0, w],
            [0, -1.0, 0, w],
            [0, 0, 1.0, w],
            [0, 0, -1.0, w],
        ]
    )


def to_window(clip: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Clip coordinates ``(k, 4)`` (with ``w > 0``) to window coordinates ``(k, 2)``."""
    width, height = size
    w = np.maximum(clip[:, 3:4], 1e-300)
    ndc = clip[:, :2] / w
    return np.column_stack([(ndc[:, 0] + 1.0) * 0.5 * width, (ndc[:, 1] + 1.0) * 0.5 * height])


def screen_planes(size: tuple[int, int], margin: float = 0.0) -> np.ndarray:
    """``(4, 3)``: the screen rectangle (grown by ``margin`` pixels) as planes of
    homogeneous window coordinates (x, y, 1)."""
    width, height = size
    return np.array(
        [[1.0, 0, margin], [-1.0, 0, width + margin], [0, 1.0, margin], [0, -1.0, height + margin]]
    )


# --------------------------------------------------------------------------- footprints


def polygon_footprint(
    points: np.ndarray,
    view_projection: np.ndarray,
    size: tuple[int, int],
    clip_plane: np.ndarray | None = None,
    depth: bool = True,
) -> Footprint:
    """The footprint of the convex polygon ``points`` ``(n, 3)`` (world) seen through
    ``view_projection`` ``(4, 4)`` on a ``size`` target, cut by the world plane
    ``clip_plane`` ``(4,)`` (what lies on its negative side is not drawn) when given.
    ``depth`` False clips against the sides of the view volume only, not its near and far
    planes (larger, never smaller)."""
    matrix = np.asarray(view_projection, dtype=np.float64)
    homogeneous = np.column_stack([np.asarray(points, dtype=np.float64), np.ones(len(points))])
    clip = homogeneous @ matrix.T
    planes = view_volume_planes() if depth else view_volume_planes()[:4]
    if clip_plane is not None:
        # the world plane in clip coordinates: plane @ p_world = plane @ M^-1 @ p_clip
        try:
            in_clip = np.asarray(clip_plane, dtype=np.float64) @ np.linalg.inv(matrix)
        except np.linalg.LinAlgError:
            in_clip = None
        if in_clip is not None and np.all(np.isfinite(in_clip)):
            # the same relative slack as the volume's, measured against the plane's size
            in_clip = in_clip + np.array([0, 0, 0, SLACK]) * np.abs(in_clip).max()
            planes = np.vstack([planes, in_clip])
    clipped = clip_polygon(clip, planes)
    if len(clipped) < 3 or not np.any(clipped[:, 3] > 0.0):
        return empty_footprint(size)
    polygon = to_window(clipped, size)
    return Footprint(polygon, polygon_area(polygon), (int(size[0]), int(size[1])))


def sphere_footprint(
    center: np.ndarray,
    radius: float,
    view: np.ndarray,
    projection: np.ndarray,
    size: tuple[int, int],
) -> Footprint:
    """The footprint of the sphere ``center`` ``(3,)`` (world), ``radius``, seen through
    the rigid ``view`` and ``projection`` (both ``(4, 4)``; perspective or orthographic,
    an oblique near plane allowed: only the x, y and w rows matter) on a ``size``
    target: a polygon around its projected ellipse, clipped to the screen."""
    size = (int(size[0]), int(size[1]))
    projection = np.asarray(projection, dtype=np.float64)
    eye_center = (np.asarray(view, dtype=np.float64) @ np.append(center, 1.0))[:3]
    xy = projection[:2, :3]
    if _is_orthographic(projection):
        # a circle of the radius in eye x, y, mapped by the projection's x and y rows
        middle = xy @ eye_center + projection[:2, 3]
        ellipse = xy[:, :2] * radius  # columns: the images of eye x and y
        return _ellipse_footprint(middle, ellipse, size)
    distance_squared = float(eye_center @ eye_center)
    if not -eye_center[2] > radius or distance_squared <= radius * radius:
        return full_screen(size)  # it reaches the eye's plane: the silhouette is unbounded
    # Rays d = to_eye @ (ndc x, ndc y, 1) in eye space; those inside the cone touching
    # the sphere satisfy (d.c)^2 >= (|c|^2 - r^2) |d|^2: a conic u^T C u >= 0 in NDC.
    inverse = np.linalg.inv(projection[:2, :2])
    to_eye = np.zeros((3, 3))
    to_eye[:2, :2] = inverse
    to_eye[:2, 2] = inverse @ projection[:2, 2]
    to_eye[2, 2] = -1.0
    cone = np.outer(eye_center, eye_center) - (distance_squared - radius * radius) * np.eye(3)
    conic = to_eye.T @ cone @ to_eye
    quadratic, linear, constant = conic[:2, :2], conic[:2, 2], conic[2, 2]
    try:
        middle = -np.linalg.solve(quadratic, linear)
    except np.linalg.LinAlgError:
        return full_screen(size)
    level = constant + linear @ middle  # the conic's value at the ellipse's centre
    shape = -quadratic / level if level > 0 else None  # (u - m)^T S (u - m) <= 1
    if shape is None or not np.all(np.isfinite(shape)):
        return full_screen(size)
    values, vectors = np.linalg.eigh(shape)
    if not np.all(values > 0):
        return full_screen(size)
    ellipse = vectors / np.sqrt(values)  # columns: the semi-axes in NDC
    return _ellipse_footprint(middle, ellipse, size)


def _ellipse_footprint(middle: np.ndarray, axes: np.ndarray, size: tuple[int, int]) -> Footprint:
    """The ellipse ``middle + axes @ (cos a, sin a)`` (NDC) as a polygon drawn around it,
    in window coordinates, clipped to the screen."""
    width, height = size
    angles = np.arange(ELLIPSE_SIDES) * (2.0 * np.pi / ELLIPSE_SIDES)
    # the vertices of a regular polygon around the unit circle lie 1/cos(pi/n) out
    circle = np.column_stack([np.cos(angles), np.sin(angles)]) / np.cos(np.pi / ELLIPSE_SIDES)
    ndc = middle + circle @ axes.T
    window = np.column_stack([(ndc[:, 0] + 1.0) * 0.5 * width, (ndc[:, 1] + 1.0) * 0.5 * height])
    if not np.all(np.isfinite(window)):
        return full_screen(size)
    clipped = clip_polygon(
        np.column_stack([window, np.ones(len(window))]), screen_planes(size, 1e-6 * max(size))
    )
    if len(clipped) < 3:
        return empty_footprint(size)
    polygon = clipped[:, :2]
    return Footprint(polygon, polygon_area(polygon), size)


def _is_orthographic(projection: np.ndarray) -> bool:
    x, y, z, w = (float(v) for v in projection[3])
    return max(abs(x), abs(y), abs(z)) <= 1e-8 and abs(w - 1.0) <= 1e-5
