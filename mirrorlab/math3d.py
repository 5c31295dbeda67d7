"""Matrix helpers in numpy, with OpenGL's conventions.

All matrices are ``(4, 4)`` float64 arrays acting on column vectors
(``p_world = M @ p_local``), the layout of the classic ``gluLookAt``/``glOrtho``
man pages. Upload them to GL with ``transpose=True`` (or ``M.T`` in
column-major order). Angles are in degrees, lengths in scene units.
No OpenGL is imported here.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

Vec3 = Sequence[float] | np.ndarray


def read_only(array: np.ndarray) -> np.ndarray:
    """``array`` itself, made read-only (for arrays worked out once and shared)."""
    array.setflags(write=False)  # (cheaper than setting array.flags.writeable)
    return array


_IDENTITY = np.eye(4)
_IDENTITY.flags.writeable = False


def identity() -> np.ndarray:
    """The ``(4, 4)`` identity (a new array: a copy is cheaper than ``np.eye``)."""
    return _IDENTITY.copy()


def translate(offset: Vec3) -> np.ndarray:
    """Translation by ``offset`` ``(3,)``."""
    m = identity()
    m[:3, 3] = np.asarray(offset, dtype=np.float64)
    return m


def scale(factors: Vec3) -> np.ndarray:
    """Axis-aligned scale by ``factors`` ``(3,)``."""
    return np.diag([*np.asarray(factors, dtype=np.float64), 1.0])


def rotate(angle_deg: float, axis: Vec3) -> np.ndarray:
    """Right-handed rotation by ``angle_deg`` about ``axis`` ``(3,)`` (need not be unit).

    Raises ValueError for a zero axis: there is no rotation to pick.
    """
    a = np.asarray(axis, dtype=np.float64)
    length = np.linalg.norm(a)
    if not np.isfinite(length) or length == 0.0:
        raise ValueError(f"rotation axis must be a non-zero finite vector, got {tuple(a)}")
    x, y, z = (float(v) for v in a / length)
    m = identity()
    m[:3, :3] = rotation_entries(angle_deg, x, y, z)
    return m


def rotation_entries(angle_deg: float, x: float, y: float, z: float) -> list[list[float]]:
    """The ``(3, 3)`` rotation by ``angle_deg`` about the unit axis ``(x, y, z)``, as rows of
    Python floats: the one formula every rotation of mirrorlab is made by (a robot's
    joints too), so that equal angles give equal matrices to the last bit."""
    radians = math.radians(angle_deg)
    c, s = math.cos(radians), math.sin(radians)
    t = 1.0 - c
    return [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.cross`` of two ``(3,)`` vectors, without its general-shape handling, which
    cost more than the rest of :func:`look_at` (every frame computes a few views)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def look_at(eye: Vec3, target: Vec3, up: Vec3) -> np.ndarray:
    """World-to-eye matrix of a camera at ``eye`` looking at ``target``.

    The camera looks down its own -z axis with +y as close to ``up`` as the
    view direction allows (``gluLookAt``). Raises ValueError when ``eye`` equals
    ``target`` or ``up`` is parallel to the view direction, since the camera
    frame is then undefined.
    """
    eye_v = np.asarray(eye, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - eye_v
    f_len = np.linalg.norm(forward)
    if f_len == 0.0 or not np.isfinite(f_len):
        raise ValueError(f"camera position {tuple(eye_v)} must differ from its target")
    forward /= f_len
    up_v = np.asarray(up, dtype=np.float64)
    up_len = np.linalg.norm(up_v)
    if not 0.0 < up_len < np.inf:
        raise ValueError(f"up vector {tuple(up)} must be a non-zero finite vector")
    side = _cross3(forward, up_v / up_len)
    s_len = np.linalg.norm(side)
    if s_len < 1e-12:
        raise ValueError(f"up vector {tuple(up)} is parallel to the view direction")
    side /= s_len
    true_up = _cross3(side, forward)
    m = identity()
    m[0, :3], m[1, :3], m[2, :3] = side, true_up, -forward
    m[:3, 3] = -m[:3, :3] @ eye_v
    return m


def ortho(
    left: float, right: float, bottom: float, top: float, near: float, far: float
) -> np.ndarray:
    """Orthographic projection of ``glOrtho``: the box maps onto the NDC cube [-1, 1]^3."""
    if left == right or bottom == top or near == far:
        raise ValueError(
            f"ortho extents must be non-degenerate, got {(left, right, bottom, top, near, far)}"
        )
    m = identity()
    m[0, 0] = 2.0 / (right - left)
    m[1, 1] = 2.0 / (top - bottom)
    m[2, 2] = -2.0 / (far - near)
    m[0, 3] = -(right + left) / (right - left)
    m[1, 3] = -(top + bottom) / (top - bottom)
    m[2, 3] = -(far + near) / (far - near)
    return m


def perspective(fovy_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """Perspective projection of ``gluPerspective``; ``fovy_deg`` is the full vertical angle."""
    if not (0.0 < fovy_deg < 180.0) or aspect <= 0.0 or not (0.0 < near < far):
        raise ValueError(
            f"perspective needs 0 < fovy < 180, aspect > 0, 0 < near < far; "
            f"got fovy={fovy_deg}, aspect={aspect}, near={near}, far={far}"
        )
    f = 1.0 / np.tan(np.radians(fovy_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0] = f / aspect
    m[1, 1] = f
    m[2, 2] = (far + near) / (near - far)
    m[2, 3] = 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def _row_is(row: np.ndarray, values: tuple[float, ...], atol: float, rtol: float = 0.0) -> bool:
    """``np.allclose(row, values, rtol, atol)`` for a short row, written out (numpy's costs
    more than the rest of a plan's capture view; NaN is never close)."""
    return all(abs(float(a) - b) <= atol + rtol * abs(b) for a, b in zip(row, values, strict=True))


def with_depth_range(projection: np.ndarray, near: float, far: float) -> np.ndarray:
    """``projection`` ``(4, 4)`` with its depth row set for clip distances ``near`` and
    ``far``: the x, y and w rows are kept (a flip, an off-centre frustum), the z row is
    a plain one's, so any oblique near plane is gone. ``projection`` must be a perspective
    (w row (0, 0, -1, 0)) or an orthographic (w row (0, 0, 0, 1)) projection; ValueError
    otherwise."""
    matrix = np.array(projection, dtype=np.float64)
    perspective = _row_is(matrix[3], (0.0, 0.0, -1.0, 0.0), 1e-12)
    if not (0.0 < near < far if perspective else near < far):
        raise ValueError(
            f"depth range needs {'0 < ' if perspective else ''}near < far, got "
            f"near={near}, far={far}"
        )
    if perspective:
        matrix[2] = (0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far))
    elif _row_is(matrix[3], (0.0, 0.0, 0.0, 1.0), 1e-12):
        matrix[2] = (0.0, 0.0, -2.0 / (far - near), -(far + near) / (far - near))
    else:
        raise ValueError(f"not a perspective or orthographic projection: w row {matrix[3]}")
    return matrix


def normal_matrix(model: np.ndarray) -> np.ndarray:
    """``(3, 3)`` inverse-transpose of the upper-left of ``model``, for transforming normals."""
    return np.linalg.inv(model[:3, :3]).T


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Apply ``matrix`` ``(4, 4)`` to ``points`` ``(..., 3)``; returns ``(..., 4)`` homogeneous."""
    p = np.asarray(points, dtype=np.float64)
    homogeneous = np.concatenate([p, np.ones((*p.shape[:-1], 1))], axis=-1)
    return homogeneous @ matrix.T


def project_to_pixels(
    projection_view: np.ndarray, points: np.ndarray, width: int, height: int
) -> np.ndarray:
    """Window coordinates of world ``points`` ``(..., 3)`` as ``(..., 3)``: x, y in pixels, depth.

    x runs right and y runs *down* (image row order, as in a PNG or a numpy
    image), both measured in pixels from the top-left corner of the image;
    depth is NDC z in [-1, 1]. Points behind the camera give meaningless values.
    """
    clip = transform_points(projection_view, points)
    ndc = clip[..., :3] / clip[..., 3:4]
    x = (ndc[..., 0] + 1.0) * 0.5 * width
    y = (1.0 - ndc[..., 1]) * 0.5 * height
    return np.stack([x, y, ndc[..., 2]], axis=-1)


def plane_through(point: Vec3, normal: Vec3) -> np.ndarray:
    """The plane ``(4,)`` = (a, b, c, d) with unit normal (a, b, c) through ``point``:
    a point p lies on the normal's side when ``plane @ (p, 1) > 0``."""
    n = np.asarray(normal, dtype=np.float64)
    length = np.linalg.norm(n)
    if not np.isfinite(length) or length == 0.0:
        raise ValueError(f"plane normal must be a non-zero finite vector, got {normal!r}")
    n = n / length
    return np.append(n, -float(n @ np.asarray(point, dtype=np.float64)))


def reflection_matrix(plane: np.ndarray) -> np.ndarray:
    """``(4, 4)`` reflection in ``plane`` (a, b, c, d) with unit normal: p -> p - 2 (plane.p) n.

    Its determinant is -1: it turns counter-clockwise triangles clockwise.
    """
    a, b, c, d = (float(v) for v in plane)
    n = np.array([a, b, c])
    matrix = identity()
    matrix[:3, :3] -= 2.0 * np.outer(n, n)
    matrix[:3, 3] = -2.0 * d * n
    return matrix


def oblique_projection(projection: np.ndarray, plane_in_eye_space: np.ndarray) -> np.ndarray:
    """``projection`` ``(4, 4)`` with its near plane replaced by ``plane_in_eye_space`` (Lengyel).

    What lies on the plane's negative side is clipped. For a perspective projection the
    eye must lie strictly behind the plane (d < 0), as it does behind a near plane; for
    an orthographic one the view box's far corner must lie in front of it. The far plane
    tilts with the near one, so depth precision drops as the plane turns away from the
    view axis. Raises ValueError where no such projection exists.
    """
    clip_plane = np.asarray(plane_in_eye_space, dtype=np.float64)
    matrix = np.array(projection, dtype=np.float64)
    perspective = not _row_is(matrix[3], (0.0, 0.0, 0.0, 1.0), 1e-8, 1e-5)
    if perspective and not clip_plane[3] < 0.0:
        raise ValueError(
            f"oblique near plane must have the eye strictly behind it (d < 0), got {clip_plane}"
        )
    # The corner of the view volume opposite the plane: chosen by the signs of the plane
    # in clip space, not in eye space, which differ where the projection flips x or y (a
    # view of the world seen in a mirror) or is off-centre.
    inverse = np.linalg.inv(matrix)
    in_clip = inverse.T @ clip_plane
    corner = inverse @ np.array([np.sign(in_clip[0]), np.sign(in_clip[1]), 1.0, 1.0])
    reach = float(clip_plane @ corner)
    if not reach > 0.0:
        raise ValueError(f"oblique near plane {clip_plane} leaves nothing of the view volume")
    scaled = clip_plane * (2.0 / reach)
    matrix[2] = scaled - matrix[3]
    return matrix
