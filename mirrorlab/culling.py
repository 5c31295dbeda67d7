"""Which of a scene's things a view can see, decided for all of them at once: boxes,
quads and spheres kept in arrays (:class:`mirrorlab.bounds.SceneIndex`) tested against a
view's clip volume in one vectorised step each, so that nothing is done in Python for a
thing the view cannot see. Numpy only.

A view's clip volume is where ``-w <= x, y, z <= w`` in its clip coordinates (and, for
the world seen in a stencil mirror, where its clip plane is not negative): six planes
of homogeneous world points, the rows ``w + x``, ``w - x``, ... of its view-projection
matrix (exact for any projective matrix, an oblique near plane and a mirrored view
included). A thing is culled only when all of it lies beyond one of those planes, by
more than a rounding's worth: then the rasteriser would clip every triangle of it
away, so culling it cannot change a pixel.
"""

from __future__ import annotations

import numpy as np

CULL_SLACK = 1e-9
"""Relative margin (of the terms of a plane's equation) by which a thing must lie beyond
a plane to be culled: float rounding never culls what the rasteriser would still draw."""

OUTSIDE_REASONS = (
    "",
    "behind the mirror it would be seen in",
    "out of view (behind the viewer)",
    "out of view (left of the view)",
    "out of view (right of the view)",
    "out of view (below the view)",
    "out of view (above the view)",
    "out of view (behind the viewer)",
    "out of view (beyond the view)",
)
"""The words for each code :func:`quads_outside` gives (0: not beyond any one side)."""


def volume_planes(view_projection: np.ndarray) -> np.ndarray:
    """``(6, 4)``: the clip volume of ``view_projection`` ``(4, 4)`` as planes of
    homogeneous world points (inside where ``plane @ (x, y, z, 1) >= 0``), in the order
    left, right, bottom, top, near, far."""
    m = np.asarray(view_projection, dtype=np.float64)
    return np.array([m[3] + m[0], m[3] - m[0], m[3] + m[1], m[3] - m[1], m[3] + m[2], m[3] - m[2]])


def view_planes(view_projection: np.ndarray, clip_plane: np.ndarray | None) -> np.ndarray:
    """``(6, 4)`` or ``(7, 4)``: :func:`volume_planes` and the world ``clip_plane`` when
    given (what lies on its negative side is cut away)."""
    planes = volume_planes(view_projection)
    if clip_plane is None:
        return planes
    return np.vstack([planes, np.asarray(clip_plane, dtype=np.float64)])


SCISSOR_MARGIN = 1.0
"""Pixels a scissor's planes (:func:`scissor_planes`) lie outside its rectangle."""


def scissor_bounds(
    size: tuple[int, int], rectangle: tuple[int, int, int, int]
) -> tuple[float, float, float, float]:
    """The normalised device x and y bounds ``(left, right, bottom, top)`` of the pixel
    ``rectangle`` ``(x, y, width, height)`` of a ``size`` target, grown by
    :data:`SCISSOR_MARGIN`."""
    width, height = size
    x, y, w, h = rectangle
    return (
        2.0 * (x - SCISSOR_MARGIN) / width - 1.0,
        2.0 * (x + w + SCISSOR_MARGIN) / width - 1.0,
        2.0 * (y - SCISSOR_MARGIN) / height - 1.0,
        2.0 * (y + h + SCISSOR_MARGIN) / height - 1.0,
    )


def scissor_planes(
    view_projection: np.ndarray, size: tuple[int, int], rectangle: tuple[int, int, int, int]
) -> np.ndarray:
    """``(4, 4)``: the part of the clip volume of ``view_projection`` that a scissor
    ``rectangle`` of a ``size`` target lets through (its sides, :func:`scissor_bounds`),
    as planes of homogeneous world points: what lies wholly beyond one cannot colour a
    pixel the scissor keeps."""
    m = np.asarray(view_projection, dtype=np.float64)
    left, right, bottom, top = scissor_bounds(size, rectangle)
    return np.array(
        [m[0] - left * m[3], right * m[3] - m[0], m[1] - bottom * m[3], top * m[3] - m[1]]
    )


def box_rows(centers: np.ndarray, halves: np.ndarray) -> np.ndarray:
    """``(n, 10)``: the world boxes given by their ``centers`` and half-sizes ``halves``
    ``(n, 3)`` as the rows :func:`rows_in_view` tests: centre, half-size, the centre's
    absolute value and 1 (worked out once for a scene's boxes)."""
    rows = np.ones((len(centers), 10))
    rows[:, 0:3] = centers
    rows[:, 3:6] = halves
    rows[:, 6:9] = np.abs(centers)
    return rows


def plane_test(planes: np.ndarray) -> np.ndarray:
    """``(10, k)``: the test of :func:`rows_in_view` against ``planes`` ``(k, 4)``
    (worked out once for a view). A box may show unless, for one plane, even its corner
    farthest along the normal lies beyond it by more than :data:`CULL_SLACK` of the terms
    compared: ``value + CULL_SLACK * size >= 0``, where ``value`` (the farthest corner's
    side) is ``centre . n + half . |n| + d`` and ``size`` is ``|centre| . |n| + half . |n|
    + |d|``; both are linear in a box's row, so the whole test is one matrix."""
    normals = np.asarray(planes, dtype=np.float64)[:, :3]
    offsets = np.asarray(planes, dtype=np.float64)[:, 3]
    reach = np.abs(normals).T
    return np.vstack(
        [
            normals.T,
            (1.0 + CULL_SLACK) * reach,
            CULL_SLACK * reach,
            (offsets + CULL_SLACK * np.abs(offsets))[None, :],
        ]
    )


def rows_in_view(rows: np.ndarray, test: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which boxes (:func:`box_rows` ``(n, 10)``) may show within the planes
    of ``test`` (:func:`plane_test` ``(10, k)``, or several side by side): one product."""
    if not len(rows):
        return np.zeros(0, dtype=bool)
    return np.logical_and.reduce(rows @ test >= 0.0, axis=1)


def boxes_in_view(centers: np.ndarray, halves: np.ndarray, planes: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which of the world boxes given by their ``centers`` and half-sizes
    ``halves`` ``(n, 3)`` may show within ``planes`` ``(k, 4)`` (False only for a box
    wholly beyond one plane: even its corner farthest along the plane's normal is).
    :func:`rows_in_view` of :func:`box_rows` and :func:`plane_test`."""
    return rows_in_view(box_rows(centers, halves), plane_test(planes))


PIXEL_MARGIN = 0.05
"""Pixels by which a thing's projected box is grown before asking whether it holds a
pixel centre: more than the rasteriser's snapping of vertices to its sub-pixel grid
(1/256 of a pixel on llvmpipe) and float rounding."""
_CORNER_SIGNS = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


def boxes_cover_pixels(
    centers: np.ndarray,
    halves: np.ndarray,
    view_projection: np.ndarray,
    size: tuple[int, int],
    rectangle: tuple[int, int, int, int] | None = None,
) -> np.ndarray:
    """``(n,)`` bool: which of the world boxes (``centers``, ``halves`` ``(n, 3)``) may
    colour a pixel of a ``size`` target (within the pixel ``rectangle`` when given).

    A triangle colours only the pixels whose centres it covers, and every triangle of a
    thing lies within the projection of its box; so a box whose projected corners, all
    in front of the eye, span no pixel centre (a thing smaller than a pixel, between
    centres) colours none. A box reaching to or behind the eye's plane may colour any.
    """
    if not len(centers):
        return np.zeros(0, dtype=bool)
    # corner by corner (8, n): a reduction over the leading axis is a few elementwise
    # passes, where one over eight values a box costs numpy a loop a box
    corners = centers + halves * _CORNER_SIGNS[:, None, :]  # (8, n, 3)
    rows = np.asarray(view_projection, dtype=np.float64)[[0, 1, 3]]  # x, y and w
    clip = corners.reshape(-1, 3) @ rows[:, :3].T + rows[:, 3]  # (8n, 3)
    w = clip[:, 2]
    in_front = w > 0.0
    ahead = in_front.reshape(8, -1).all(axis=0)
    safe = np.where(in_front, w, 1.0)
    width, height = size
    x = ((clip[:, 0] / safe + 1.0) * (0.5 * width)).reshape(8, -1)
    y = ((clip[:, 1] / safe + 1.0) * (0.5 * height)).reshape(8, -1)
    x0, y0, x1, y1 = 0, 0, width - 1, height - 1
    if rectangle is not None:
        x0, y0 = rectangle[0], rectangle[1]
        x1, y1 = rectangle[0] + rectangle[2] - 1, rectangle[1] + rectangle[3] - 1
    # pixel i's centre is i + 0.5: some centre lies in [low, high] when
    # ceil(low - 0.5) <= floor(high - 0.5)
    first_x = np.maximum(np.ceil(x.min(axis=0) - PIXEL_MARGIN - 0.5), x0)
    last_x = np.minimum(np.floor(x.max(axis=0) + PIXEL_MARGIN - 0.5), x1)
    first_y = np.maximum(np.ceil(y.min(axis=0) - PIXEL_MARGIN - 0.5), y0)
    last_y = np.minimum(np.floor(y.max(axis=0) + PIXEL_MARGIN - 0.5), y1)
    return ~ahead | ((first_x <= last_x) & (first_y <= last_y))


_TERMS_OF_SIDES = np.array(
    [
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
    ]
)
"""From the absolute clip coordinates ``(|x|, |y|, |z|, |w|)`` to the terms each side of
the view compares, summed: |x| + |w| for the left and right, |y| + |w|, |z| + |w|."""


def quads_outside(
    corners: np.ndarray,
    view_projection: np.ndarray,
    clip_plane: np.ndarray | None,
    orthographic: bool,
    sides: tuple[float, float, float, float] = (-1.0, 1.0, -1.0, 1.0),
) -> np.ndarray:
    """``(p,)`` int8: for each quad of ``corners`` ``(p, 4, 3)`` (world), the code of the
    side of the view all four corners lie beyond, in :data:`OUTSIDE_REASONS` (0 when no
    one side has them all): the clip plane first, then behind a perspective eye, then
    left, right, below, above, in front of the near and beyond the far plane. Beyond a
    side means by more than :data:`CULL_SLACK` of the terms compared (a quad lying on
    the near plane, as a mirror seen in a mirror in its own plane does, is not beyond
    it); behind the eye, at or behind its plane. ``sides`` narrows the left, right,
    bottom and top sides from -1, 1, -1, 1 of normalised device coordinates (to what a
    scissor keeps, :func:`scissor_bounds`)."""
    return rows_outside(quad_rows(corners), view_projection, clip_plane, orthographic, sides)


def quad_rows(corners: np.ndarray) -> np.ndarray:
    """``(4, p, 4)``: the homogeneous world corners of the quads ``corners`` ``(p, 4, 3)``,
    first corners first (what :func:`rows_outside` takes)."""
    corners = np.asarray(corners, dtype=np.float64)
    rows = np.ones((4, len(corners), 4))
    rows[..., :3] = corners.transpose(1, 0, 2)
    return rows


def rows_outside(
    rows: np.ndarray,
    view_projection: np.ndarray,
    clip_plane: np.ndarray | None,
    orthographic: bool,
    sides: tuple[float, float, float, float] = (-1.0, 1.0, -1.0, 1.0),
) -> np.ndarray:
    """:func:`quads_outside` of the quads whose :func:`quad_rows` are ``rows``
    ``(4, p, 4)``: a few products over all the corners at once."""
    count = rows.shape[1]
    if not count:
        return np.zeros(0, dtype=np.int8)
    points = rows.reshape(-1, 4)
    # each side's clip coordinate against w as one product: leads (4p, 6), and the terms
    # each compares (|x| + |w| for the left and right sides, and so on)
    left, right, bottom, top = sides
    sides_of_clip = np.array(
        [
            [1.0, -1.0, 0.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, -1.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, 0.0, 1.0, -1.0],
            [-left, right, -bottom, top, 1.0, 1.0],
        ]
    )
    clip = points @ np.asarray(view_projection, dtype=np.float64).T  # (4p, 4)
    beyond = _all_corners(
        (clip @ sides_of_clip < (-CULL_SLACK) * (np.abs(clip) @ _TERMS_OF_SIDES)), count
    )
    first_code = 3
    if not orthographic:
        behind = _all_corners(clip[:, 3] <= 0.0, count)
        beyond = np.concatenate([behind[:, None], beyond], axis=1)
        first_code = 2
    codes = np.where(beyond.any(axis=1), np.argmax(beyond, axis=1) + first_code, 0)
    if clip_plane is not None:
        plane = np.asarray(clip_plane, dtype=np.float64)
        codes[
            _all_corners(points @ plane < (-CULL_SLACK) * (np.abs(points) @ np.abs(plane)), count)
        ] = 1
    return codes.astype(np.int8)


def _all_corners(each: np.ndarray, count: int) -> np.ndarray:
    """``(p, ...)`` bool: true where it is for all four corners in ``each`` ``(4p, ...)``
    (first corners first, as :func:`quad_rows` lays them out)."""
    first, second, third, fourth = each.reshape(4, count, *each.shape[1:])
    return first & second & third & fourth


def facing(
    centers: np.ndarray, normals: np.ndarray, eye: np.ndarray | None, forward: np.ndarray
) -> np.ndarray:
    """``(p,)`` bool: whether a viewer at ``eye`` ``(3,)`` (None: orthographic, looking
    along ``forward`` ``(3,)``) is on the reflecting side of each mirror (``centers``,
    unit ``normals`` ``(p, 3)``), strictly: edge-on is not facing."""
    if eye is not None:
        towards = np.asarray(eye, dtype=np.float64) - centers
    else:
        towards = np.broadcast_to(-np.asarray(forward, dtype=np.float64), centers.shape)
    return np.einsum("ij,ij->i", towards, normals) > 0.0


def spheres_in_view(
    centers: np.ndarray,
    radii: np.ndarray,
    view_projection: np.ndarray,
    clip_plane: np.ndarray | None,
) -> np.ndarray:
    """``(c,)`` bool: which of the world spheres ``centers`` ``(c, 3)``, ``radii`` ``(c,)``
    reach into the view (False only for a sphere wholly beyond one plane)."""
    if not len(centers):
        return np.zeros(0, dtype=bool)
    points = np.concatenate([centers, np.ones((len(centers), 1))], axis=1)
    inside = np.ones(len(centers), dtype=bool)
    planes = view_planes(view_projection, clip_plane)
    # distances, not multiples of them: no plane here need have a unit normal (hypot's
    # length does not overflow where a sum of squares would: a needle-thin view's planes)
    lengths = np.hypot.reduce(planes[:, :3], axis=1)
    for plane, length in zip(planes, lengths, strict=True):
        if length > 0:
            inside &= (points @ plane) / length >= -radii
    return inside
