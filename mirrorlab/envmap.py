"""Environment-map lookups in numpy: the reference every GL path is checked against.

Directions are ``(..., 3)`` arrays (``r``, ``u``, ``n``); every function is
vectorised over the leading axes and broadcasts its arguments. Results keep
the input's floating dtype (float32 stays float32, float64 stays float64;
integer input is promoted to float64, float16 to float32). No OpenGL is
imported here.

Texture coordinates follow OpenGL: ``s`` runs left to right, ``t`` bottom to
top, both in [0, 1]. The bake helpers return images in numpy/PIL row order
(row 0 at the *top*), so in an image ``h`` rows high and ``w`` columns wide,
row ``i`` holds ``t = 1 - (i + 0.5) / h`` and column ``j`` holds
``s = (j + 0.5) / w`` (texel centres). mirrorlab's GL layer flips images on
upload, which puts row 0 at ``t = 1`` as GL expects; raw ``glTexImage2D`` of
an unflipped image would put row 0 at ``t = 0`` instead.

Hard cases, chosen so that nothing returns NaN, Inf or a coordinate out of range:

- ``reflect`` with ``n = 0``: ``r = u`` (no reflection). A tiny, even
  subnormal, ``n`` still counts as its direction.
- ``sphere_map`` of ``r = 0``: the centre ``(0.5, 0.5)``, the image of ``+z``.
- ``sphere_map`` of exactly ``(0, 0, -1)``: the rim point ``(1, 0.5)``; just
  off it, the rim point in the direction of ``(rx, ry)``.
- ``sphere_map_inverse`` outside the disc: clamped to the rim, which is all
  ``(0, 0, -1)``.
- ``cube_map`` ties (edges, corners): Z before Y before X, and the sign bit of
  the major component picks the face, as Mesa's llvmpipe sampler does. A
  zero ``r`` gives +Z (face 4) at ``(0.5, 0.5)``, or -Z when ``rz`` is
  ``-0.0``.
- ``latlong_map`` poles: ``s = 0`` whenever ``rx = ry = 0``; ``r = 0`` gives
  ``(0, 0)``, the image of ``+z``.

Non-finite inputs (NaN, Inf) are outside the domain; they may give NaN.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

EnvFunction = Callable[[np.ndarray], np.ndarray]
"""A world-space environment: unit directions ``(n, 3)`` float64 -> colours ``(n, 3)`` in
[0, 1]."""

CUBE_FACE_NAMES = ("+X", "-X", "+Y", "-Y", "+Z", "-Z")
"""Face names in GL order: face ``k`` is ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + k``."""


# ---------------------------------------------------------------------------- helpers


def _float(x) -> np.ndarray:
    """``x`` as an array of a floating dtype (ints -> float64, float16 -> float32)."""
    a = np.asarray(x)
    if a.dtype == np.float16:
        return a.astype(np.float32)
    if not np.issubdtype(a.dtype, np.floating):
        return a.astype(np.float64)
    return a


def _floats(*arrays) -> list[np.ndarray]:
    """The arguments as arrays of their common floating dtype (not broadcast)."""
    converted = [_float(a) for a in arrays]
    dtype = np.result_type(*converted)
    return [a.astype(dtype, copy=False) for a in converted]


def _check_vectors(v: np.ndarray, name: str) -> None:
    if v.ndim == 0 or v.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {v.shape}")


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``v`` ``(..., 3)`` scaled to unit length, and a mask of the non-zero rows ``(...)``.

    The largest component is divided out first, so subnormal and huge vectors
    normalise without underflow or overflow; zero vectors stay zero.
    """
    scale = np.max(np.abs(v), axis=-1, keepdims=True)
    nonzero = scale > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        w = v / np.where(nonzero, scale, 1)
        length = np.sqrt(np.sum(w * w, axis=-1, keepdims=True))
        w = w / np.where(nonzero, length, 1)
    return w, nonzero[..., 0]


def _split(v: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return v[..., 0], v[..., 1], v[..., 2]


# ---------------------------------------------------------------------------- reflection


def reflect(u, n) -> np.ndarray:
    """Mirror the incident direction ``u`` ``(..., 3)`` about the normal ``n`` ``(..., 3)``.

    ``r = u - 2 (n.u) n`` with ``n`` normalised here (``u`` is used as given:
    ``|r| = |u|``). ``u`` points *towards* the surface, like the eye-to-vertex
    vector of GL's sphere-map texgen. A zero ``n`` gives ``r = u``; any
    non-zero finite ``n``, however small (subnormal included), is normalised
    after dividing by its largest component, so it reflects like its
    direction. Returns ``(..., 3)`` in the common float dtype of ``u`` and ``n``.
    """
    u, n = _floats(u, n)
    _check_vectors(u, "u")
    _check_vectors(n, "n")
    n_hat, _ = _unit(n)
    projection = np.sum(n_hat * u, axis=-1, keepdims=True) * n_hat
    return u - projection - projection  # not 2 * projection, which could overflow


# ---------------------------------------------------------------------------- sphere map


def sphere_map(r) -> tuple[np.ndarray, np.ndarray]:
    """Sphere-map coordinates ``(s, t)``, each ``(...)``, of eye-space reflection vectors.

    The formula of ``GL_SPHERE_MAP``: ``m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2)``,
    ``s = rx/m + 1/2``, ``t = ry/m + 1/2``, after normalising ``r`` ``(..., 3)``
    (any non-zero length is accepted). ``+z`` (straight back at the viewer)
    lands on the centre, ``-z`` on the whole rim of the disc of radius 1/2.

    Numerics: for ``rz < 0``, ``rz + 1`` is computed as
    ``(rx^2 + ry^2) / (1 - rz)``, which keeps its relative accuracy as ``r``
    approaches ``(0, 0, -1)``; there the result tends to the rim point in the
    direction of ``(rx, ry)``, and ``r = (0, 0, -1)`` exactly (``m = 0``)
    gives the fixed rim point ``(1, 0.5)``. ``r = 0`` gives ``(0.5, 0.5)``.
    Results are always finite and in [0, 1].
    """
    (r,) = _floats(r)
    _check_vectors(r, "r")
    w, _ = _unit(r)  # r = 0 stays 0, which the formula sends to the centre
    x, y, z = _split(w)
    rho = np.hypot(x, y)
    with np.errstate(invalid="ignore", divide="ignore"):
        z_plus_one = np.where(z >= 0, 1 + z, rho * rho / (1 - z))
        half_m = np.hypot(rho, z_plus_one)
        singular = half_m == 0
        safe = np.where(singular, 1, half_m)
        qs = np.where(singular, 1, x / safe)
        qt = np.where(singular, 0, y / safe)
    s = np.clip(0.5 + 0.5 * qs, 0, 1).astype(r.dtype, copy=False)
    t = np.clip(0.5 + 0.5 * qt, 0, 1).astype(r.dtype, copy=False)
    return s, t


def sphere_map_texgen(vertex_eye, normal_eye) -> tuple[np.ndarray, np.ndarray]:
    """What ``GL_SPHERE_MAP`` texgen gives a vertex: ``(s, t)``, each ``(...)``.

    ``vertex_eye`` ``(..., 3)`` is the vertex position in eye space (the eye
    at the origin), ``normal_eye`` ``(..., 3)`` its eye-space normal (for a
    model-view matrix ``M``: ``normal_matrix(M) @ n``). As GL does:
    ``u = vertex / |vertex|``, ``r = reflect(u, n)``, then :func:`sphere_map`.
    The normal is normalised here, which matches GL with ``GL_NORMALIZE``
    enabled or unit normals; GL without it reflects about the raw normal.

    Where GL gives NaN this stays finite: a vertex at the eye gives ``u = 0``,
    so ``r = 0`` and ``(0.5, 0.5)``; a zero normal gives ``r = u``.
    """
    vertex, normal = _floats(vertex_eye, normal_eye)
    _check_vectors(vertex, "vertex_eye")
    u, _ = _unit(vertex)
    return sphere_map(reflect(u, normal))


def sphere_map_inverse(s, t) -> np.ndarray:
    """The unit eye-space reflection vector ``(..., 3)`` that :func:`sphere_map` sends to
    ``(s, t)`` (each ``(...)``, broadcast).

    The map is the image of a mirror ball seen orthographically down ``-z``:
    ``(x, y) = (2s - 1, 2t - 1)``, ball normal ``(x, y, sqrt(1 - x^2 - y^2))``,
    and ``r`` is the view direction ``(0, 0, -1)`` reflected about it:
    ``r = (2 nz x, 2 nz y, 1 - 2 (x^2 + y^2))``. Points outside the disc
    ``x^2 + y^2 <= 1`` are clamped radially onto its rim, where every point
    means ``(0, 0, -1)``.

    Round trip: for unit ``r`` with ``1 + rz >= 1e-6``,
    ``|sphere_map_inverse(*sphere_map(r)) - r| <= 8 eps / sqrt(1 + rz)`` with
    ``eps`` the dtype's machine epsilon (2.2e-16 for float64, 1.2e-7 for
    float32): the map stretches angles by ``2 / sqrt(2 (1 + rz))`` near the
    rim, so errors grow towards the singular direction ``(0, 0, -1)``.
    """
    s, t = _floats(s, t)
    s, t = np.broadcast_arrays(s, t)
    x = 2 * s - 1
    y = 2 * t - 1
    rho = np.hypot(x, y)
    outside = rho > 1
    with np.errstate(invalid="ignore", divide="ignore"):
        shrink = np.where(outside, 1 / np.where(outside, rho, 1), 1)
    x, y = x * shrink, y * shrink
    rho = np.minimum(rho, 1)
    nz = np.sqrt((1 - rho) * (1 + rho))
    r = np.stack([2 * nz * x, 2 * nz * y, 1 - 2 * rho * rho], axis=-1)
    return _unit(r)[0].astype(s.dtype, copy=False)


# ---------------------------------------------------------------------------- cube map


def cube_map(r) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cube-map face and face coordinates ``(face, s, t)``, each ``(...)``, of ``r`` ``(..., 3)``.

    ``face`` is an int64 array, ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + face`` in
    GL order +X, -X, +Y, -Y, +Z, -Z. The major axis ``ma`` is the component of
    largest magnitude; ``(sc, tc)`` come from the OpenGL spec's table
    (+X: -rz, -ry; -X: +rz, -ry; +Y: +rx, +rz; -Y: +rx, -rz; +Z: +rx, -ry;
    -Z: -rx, -ry) and ``s = (sc/|ma| + 1)/2``, ``t = (tc/|ma| + 1)/2``, in
    [0, 1]. ``r`` need not be unit. As in GL, face images are addressed with
    ``t = 0`` at the first row of data given to ``glTexImage2D``.

    Deterministic rules where the spec leaves a choice, the same as Mesa's
    llvmpipe sampler (checked in ``tests/gl/test_envmap_oracles.py``): on ties
    in magnitude Z wins over Y and Y over X (``|z| >= |x|`` and ``|z| >= |y|``
    picks Z, then ``|y| >= |x|`` picks Y); the sign *bit* of the major
    component picks the negative face, so a zero major component (only when
    ``r = 0``) gives +Z at ``(0.5, 0.5)``, or -Z when ``rz`` is ``-0.0``. Edges
    and corners are ties and follow the same rule; there ``s`` or ``t`` is
    exactly 0 or 1, and the tied faces name texels that touch the shared edge.
    """
    (r,) = _floats(r)
    _check_vectors(r, "r")
    x, y, z = _split(r)
    ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
    use_z = (az >= ax) & (az >= ay)
    use_y = ~use_z & (ay >= ax)
    axis = np.where(use_z, 2, np.where(use_y, 1, 0))
    major = np.where(use_z, z, np.where(use_y, y, x))
    negative = np.signbit(major)
    face = (2 * axis + negative).astype(np.int64)
    # The spec's table, one row per face.
    sc_by_face = np.stack([-z, z, x, x, x, -x])
    tc_by_face = np.stack([-y, -y, z, -z, -y, -y])
    sc = np.take_along_axis(sc_by_face, face[None], axis=0)[0]
    tc = np.take_along_axis(tc_by_face, face[None], axis=0)[0]
    ma = np.abs(major)
    with np.errstate(invalid="ignore", divide="ignore"):
        safe = np.where(ma > 0, ma, 1)
        s = np.clip((sc / safe + 1) / 2, 0, 1)
        t = np.clip((tc / safe + 1) / 2, 0, 1)
    return face, s.astype(r.dtype, copy=False), t.astype(r.dtype, copy=False)


def cube_face_direction(face, s, t) -> np.ndarray:
    """The unit direction ``(..., 3)`` that :func:`cube_map` sends to ``(face, s, t)``.

    ``face`` integers 0..5 (GL order), ``s``, ``t`` in [0, 1] (clipped to it),
    all broadcast. Inverts the spec's table: for +X, ``(1, -tc, -sc)``, and so
    on, with ``sc = 2s - 1``, ``tc = 2t - 1``. Raises ValueError for a face
    outside 0..5. The float dtype follows ``s`` and ``t``.
    """
    face = np.asarray(face)
    if not np.issubdtype(face.dtype, np.integer):
        raise ValueError(f"cube face must be integers 0..5, got dtype {face.dtype}")
    if face.size and (face.min() < 0 or face.max() > 5):
        raise ValueError(f"cube face must be in 0..5, got values {np.unique(face)}")
    s, t = _floats(s, t)
    face, s, t = np.broadcast_arrays(face, s, t)
    sc = 2 * np.clip(s, 0, 1) - 1
    tc = 2 * np.clip(t, 0, 1) - 1
    one = np.ones_like(sc)
    by_face = np.stack(
        [
            np.stack([one, -tc, -sc], axis=-1),  # +X
            np.stack([-one, -tc, sc], axis=-1),  # -X
            np.stack([sc, one, tc], axis=-1),  # +Y
            np.stack([sc, -one, -tc], axis=-1),  # -Y
            np.stack([sc, -tc, one], axis=-1),  # +Z
            np.stack([-sc, -tc, -one], axis=-1),  # -Z
        ]
    )
    r = np.take_along_axis(by_face, face[None, ..., None], axis=0)[0]
    return _unit(r)[0]


# ---------------------------------------------------------------------------- latitude-longitude


def latlong_map(r) -> tuple[np.ndarray, np.ndarray]:
    """Blinn-Newell latitude-longitude coordinates ``(s, t)``, each ``(...)``, of
    ``r`` ``(..., 3)``.

    ``theta`` is the polar angle from ``+z`` (``arccos(rz)`` for unit ``r``),
    ``phi = atan2(ry, rx)``; ``s = phi / (2 pi)`` wrapped into [0, 1),
    ``t = theta / pi`` in [0, 1] (``t = 0`` at ``+z``, ``t = 1`` at ``-z``).

    Numerics: ``r`` is normalised first; ``theta`` is computed as
    ``atan2(sqrt(rx^2 + ry^2), rz)``, equal to ``arccos(rz)`` on the unit sphere
    but accurate near the poles and immune to ``|rz|`` rounding above 1 (which
    would make ``arccos`` return NaN). At the poles (``rx = ry = 0``, any
    zero signs) ``s = 0``; a wrapped value that rounds up to 1 becomes 0;
    ``r = 0`` gives ``(0, 0)``.

    The seam: ``s`` jumps from just below 1 (``ry < 0``) to 0 (``ry >= 0``)
    across the half-plane ``ry = 0, rx > 0`` (``phi = 0``). A triangle whose
    vertices straddle it would interpolate ``s`` across almost the whole map;
    a shader must compute ``s`` per fragment from the interpolated direction,
    or shift the vertex values that differ from the first by more than 1/2
    by one whole turn and wrap with ``fract`` after interpolation (with
    ``GL_REPEAT`` in s).
    """
    (r,) = _floats(r)
    _check_vectors(r, "r")
    w, nonzero = _unit(r)
    x, y, z = _split(w)
    rho = np.hypot(x, y)
    theta = np.where(nonzero, np.arctan2(rho, z), 0)
    s = np.arctan2(y, x) / (2 * np.pi)
    s = np.where(s < 0, s + 1, s)
    s = np.where((s >= 1) | (rho == 0), 0, s)
    t = np.clip(theta / np.pi, 0, 1)
    return s.astype(r.dtype, copy=False), t.astype(r.dtype, copy=False)


def latlong_map_inverse(s, t) -> np.ndarray:
    """The unit direction ``(..., 3)`` at latitude-longitude coordinates ``(s, t)``.

    ``phi = 2 pi s`` (any ``s``: the map is periodic in it), ``theta = pi t``
    with ``t`` clipped to [0, 1]; ``r = (sin theta cos phi, sin theta sin phi,
    cos theta)``.
    """
    s, t = _floats(s, t)
    s, t = np.broadcast_arrays(s, t)
    phi = 2 * np.pi * s
    theta = np.pi * np.clip(t, 0, 1)
    sin_theta = np.sin(theta)
    r = np.stack([sin_theta * np.cos(phi), sin_theta * np.sin(phi), np.cos(theta)], axis=-1)
    return r.astype(s.dtype, copy=False)


# ---------------------------------------------------------------------------- demo style


def normal_map(n, width, height) -> tuple[np.ndarray, np.ndarray]:
    """The gamedev article's "demo style" texel position ``(u, v)``, each ``(...)``.

    ``u = nx * width/2 + width/2 - 1`` and ``v = ny * height/2 + height/2 - 1``
    (``N.x*128 + 127`` on a 256-wide map), with ``n`` ``(..., 3)`` normalised
    first; ``nz`` is ignored, so a normal and its mirror image through the
    screen plane share a texel. ``v`` grows with ``ny``.

    The article's formula is off by one at the low end: it maps ``nx`` in
    [-1, 1] onto [-1, width - 1], so ``nx = -1`` asks for texel -1 (outside
    the map) and ``nx = 0`` gives ``width/2 - 1``, half a texel left of the
    true centre ``(width - 1)/2``. Here ``u`` is clamped to [0, width - 1] and
    ``v`` to [0, height - 1]; results are fractional texel positions (take
    ``floor`` for an index). A zero ``n`` gives ``(width/2 - 1, height/2 - 1)``.
    """
    (n,) = _floats(n)
    _check_vectors(n, "n")
    w = np.asarray(width, dtype=n.dtype)
    h = np.asarray(height, dtype=n.dtype)
    if np.any(w < 1) or np.any(h < 1):
        raise ValueError(f"map size must be positive, got {width}x{height}")
    unit, _ = _unit(n)
    u = unit[..., 0] * (w / 2) + (w / 2 - 1)
    v = unit[..., 1] * (h / 2) + (h / 2 - 1)
    return np.clip(u, 0, w - 1), np.clip(v, 0, h - 1)


# ---------------------------------------------------------------------------- baking


def _texel_centres(count: int) -> np.ndarray:
    return (np.arange(count, dtype=np.float64) + 0.5) / count


def _check_size(value: int, name: str) -> int:
    if int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


def _shade(env: EnvFunction, directions: np.ndarray) -> np.ndarray:
    """``env`` over ``directions`` ``(..., 3)`` as uint8 colours ``(..., 3)``."""
    flat = np.ascontiguousarray(directions.reshape(-1, 3), dtype=np.float64)
    colours = np.asarray(env(flat), dtype=np.float64)
    if colours.shape != flat.shape:
        raise ValueError(
            f"env must return (n, 3) colours for (n, 3) directions, got "
            f"{colours.shape} for {flat.shape}"
        )
    colours = np.nan_to_num(np.clip(colours, 0, 1), nan=0.0)
    return np.round(colours * 255).astype(np.uint8).reshape(directions.shape)


def _image_grid(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """``(s, t)`` at the texel centres of a ``(height, width)`` image, row 0 at the top."""
    s = _texel_centres(width)
    t = 1 - _texel_centres(height)
    return np.meshgrid(s, t)


def bake_sphere_map(env: EnvFunction, size: int, view_rotation) -> np.ndarray:
    """A sphere-map image ``(size, size, 3)`` uint8 of the world-space environment ``env``.

    The map lives in eye space: texel ``(s, t)`` shows
    ``env(R.T @ sphere_map_inverse(s, t))`` where ``view_rotation`` ``R``
    ``(3, 3)`` is the rotation part of the world-to-eye matrix (eye = R world,
    e.g. ``look_at(...)[:3, :3]``). Row 0 is the top of the image
    (``t = 1 - (i + 0.5)/size``), column ``j`` has ``s = (j + 0.5)/size``.
    Texels whose centre is outside the disc get the rim value: the colour of
    eye-space ``(0, 0, -1)``, the direction the rim converges to, so that
    filtering at the edge of the disc blends towards the right colour.
    """
    size = _check_size(size, "size")
    rotation = np.asarray(view_rotation, dtype=np.float64)
    if rotation.shape != (3, 3):
        raise ValueError(f"view_rotation must be (3, 3), got {rotation.shape}")
    s, t = _image_grid(size, size)
    eye_dirs = sphere_map_inverse(s, t)
    world_dirs = _unit(eye_dirs @ rotation)[0]  # row vectors: (R.T r).T = r.T R
    return _shade(env, world_dirs)


def bake_cube_faces(env: EnvFunction, size: int) -> np.ndarray:
    """Six cube faces ``(6, size, size, 3)`` uint8 of ``env``, in GL face order.

    Face ``k`` texel (row ``i``, column ``j``) shows
    ``env(cube_face_direction(k, (j + 0.5)/size, 1 - (i + 0.5)/size))``: row 0
    is the top of the image, ``t = 1``, ready for mirrorlab's GL layer, which
    flips rows on upload. Raw ``glTexImage2D`` wants the rows reversed
    (``faces[k, ::-1]``), since it puts the first row at ``t = 0``.
    """
    size = _check_size(size, "size")
    s, t = _image_grid(size, size)
    faces = np.arange(6)[:, None, None]
    return _shade(env, cube_face_direction(faces, s, t))


def bake_latlong(env: EnvFunction, width: int, height: int) -> np.ndarray:
    """A latitude-longitude image ``(height, width, 3)`` uint8 of ``env``.

    Pixel (row ``i``, column ``j``) shows ``env(latlong_map_inverse(s, t))`` with
    ``s = (j + 0.5)/width`` and ``t = 1 - (i + 0.5)/height``: row 0 at the top
    is ``t`` near 1, the ``-z`` pole; the bottom row is near ``+z``.
    """
    width = _check_size(width, "width")
    height = _check_size(height, "height")
    s, t = _image_grid(width, height)
    return _shade(env, latlong_map_inverse(s, t))
