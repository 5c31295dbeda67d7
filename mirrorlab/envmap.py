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
- ``octahedral_map``: a zero component counts as positive (``-0.0`` too), so the
  fold lines and the square's edges, where the sign picks a side, give one answer; the
  lower hemisphere's edges are where a direction's two images meet
  (:func:`octahedral_wrap`). ``r = 0`` gives the centre, the image of ``+z``.
- ``paraboloid_map``: ``rz = 0`` (either zero) belongs to the front side; the
  denominator ``1 + |rz|`` is at least 1. ``r = 0`` gives the front's centre.

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


# ---------------------------------------------------------------------------- octahedral


def _sign(v: np.ndarray) -> np.ndarray:
    """+1 where ``v >= 0`` (``-0.0`` included), -1 elsewhere, in ``v``'s dtype."""
    return np.where(v >= 0, 1, -1).astype(v.dtype, copy=False)


def octahedral_map(r) -> tuple[np.ndarray, np.ndarray]:
    """Octahedral coordinates ``(s, t)``, each ``(...)`` in [0, 1], of directions ``r``
    ``(..., 3)`` (Engelhardt & Dachsbacher 2008; Cigolle et al., JCGT 2014).

    ``p = r / (|rx| + |ry| + |rz|)`` lies on the octahedron; the upper half (``rz >= 0``)
    projects straight down onto the diamond ``|u| + |v| <= 1``, the lower half is folded
    out over the diamond's edges into the square's four corners:
    ``(u, v) = ((1 - |py|) sign(px), (1 - |px|) sign(py))``. Then ``s = (u + 1)/2``,
    ``t = (v + 1)/2``: ``+z`` at the centre, ``-z`` at the four corners, the equator on
    the diamond (the fold lines, where both formulas agree).

    A zero component counts as positive, ``-0.0`` too, so every direction on a fold or
    an edge has one image; on an edge of the square (the lower half's ``rx = 0`` or
    ``ry = 0``) a direction's two images are mirror images across the edge's midpoint
    (:func:`octahedral_wrap`). ``r = 0`` gives ``(0.5, 0.5)``. ``r`` need not be unit.
    """
    (r,) = _floats(r)
    _check_vectors(r, "r")
    w, _ = _unit(r)
    x, y, z = _split(w)
    l1 = np.abs(x) + np.abs(y) + np.abs(z)
    safe = np.where(l1 > 0, l1, 1)
    px, py, pz = x / safe, y / safe, z / safe
    lower = pz < 0
    u = np.where(lower, (1 - np.abs(py)) * _sign(px), px)
    v = np.where(lower, (1 - np.abs(px)) * _sign(py), py)
    s = np.clip(0.5 + 0.5 * u, 0, 1).astype(r.dtype, copy=False)
    t = np.clip(0.5 + 0.5 * v, 0, 1).astype(r.dtype, copy=False)
    return s, t


def octahedral_wrap(s, t) -> tuple[np.ndarray, np.ndarray]:
    """Any ``(s, t)`` (each ``(...)``, broadcast) as the point of the square [0, 1]^2 that
    continues the map across its edges: the octahedral map's border identification.

    In ``(u, v) = (2s - 1, 2t - 1)``, crossing the right edge ``u = 1`` comes back in
    mirrored: ``(1 + e, v) ~ (1 - e, -v)``, and so for each edge (``(u, 1 + e) ~ (-u, 1 -
    e)``); the four corners meet at ``-z``. The continuation has period 4 in ``u`` and in
    ``v``. This is what the padded border of an octahedral texture holds, so that
    bilinear filtering across an edge reads the directions that lie across it.
    """
    s, t = _floats(s, t)
    s, t = np.broadcast_arrays(s, t)
    u = np.mod(2 * s - 1 + 2, 4) - 2  # in [-2, 2)
    v = np.mod(2 * t - 1 + 2, 4) - 2
    right, left = u > 1, u < -1
    u, v = np.where(right, 2 - u, np.where(left, -2 - u, u)), np.where(right | left, -v, v)
    top, bottom = v > 1, v < -1
    u, v = np.where(top | bottom, -u, u), np.where(top, 2 - v, np.where(bottom, -2 - v, v))
    return (
        np.clip(0.5 + 0.5 * u, 0, 1).astype(s.dtype, copy=False),
        np.clip(0.5 + 0.5 * v, 0, 1).astype(s.dtype, copy=False),
    )


def octahedral_map_inverse(s, t) -> np.ndarray:
    """The unit direction ``(..., 3)`` at octahedral coordinates ``(s, t)`` (each
    ``(...)``, broadcast; outside [0, 1] continued across the square's edges by
    :func:`octahedral_wrap`).

    ``(u, v) = (2s - 1, 2t - 1)``, ``z = 1 - |u| - |v|``; in the corners (``z < 0``) the
    fold is undone: ``(x, y) = ((1 - |v|) sign(u), (1 - |u|) sign(v))``; then normalised.
    """
    s, t = octahedral_wrap(s, t)
    u, v = 2 * s - 1, 2 * t - 1
    z = 1 - np.abs(u) - np.abs(v)
    lower = z < 0
    x = np.where(lower, (1 - np.abs(v)) * _sign(u), u)
    y = np.where(lower, (1 - np.abs(u)) * _sign(v), v)
    return _unit(np.stack([x, y, z], axis=-1))[0]


def octahedral_level_sizes(size: int) -> tuple[int, ...]:
    """The edge in texels of each mip level of an octahedral texture ``size`` texels wide
    (GL's ``max(1, size >> k)``), as far as a level still has a 2 x 2 interior inside
    its one-texel border: ``size`` must be at least 4."""
    size = _check_size(size, "size")
    if size < 4:
        raise ValueError(f"an octahedral map needs at least 4 texels a side, got {size}")
    sizes: list[int] = []
    while (size >> len(sizes)) >= 4:
        sizes.append(size >> len(sizes))
    return tuple(sizes)


def octahedral_texel_grid(level_size: int) -> tuple[np.ndarray, np.ndarray]:
    """``(s, t)`` ``(n, n)`` each: the octahedral coordinates of the texel centres of a
    level ``n = level_size`` texels wide, in image row order (row 0 at the top).

    Every level has a one-texel border around its interior of ``m = n - 2`` texels: texel
    ``i`` (from the left, or from the bottom for ``t``) has its centre at ``(i - 0.5) /
    m``, so the interior spans [0, 1] and the border texels lie half a texel outside it
    (their directions continue across the edge, :func:`octahedral_wrap`). A lookup at
    ``s`` reads level ``k`` at texel position ``1 + s m_k`` of ``n_k``: the position
    differs from level to level, so a shader filters between levels itself."""
    interior = level_size - 2
    centres = (np.arange(level_size, dtype=np.float64) - 0.5) / interior
    s, t = np.meshgrid(centres, centres[::-1])
    return s, t


def _bilinear(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``image`` ``(h, w, c)`` (row 0 at the *bottom*) read bilinearly at texel-space
    positions ``x``, ``y`` (texel ``i``'s centre at ``i + 0.5``), clamped to the edge."""
    h, w = image.shape[:2]
    fx = np.clip(x - 0.5, 0, w - 1)
    fy = np.clip(y - 0.5, 0, h - 1)
    x0 = np.minimum(np.floor(fx).astype(np.intp), w - 2 if w > 1 else 0)
    y0 = np.minimum(np.floor(fy).astype(np.intp), h - 2 if h > 1 else 0)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    ax = (fx - x0)[..., None]
    ay = (fy - y0)[..., None]
    lower = image[y0, x0] * (1 - ax) + image[y0, x1] * ax
    upper = image[y1, x0] * (1 - ax) + image[y1, x1] * ax
    return lower * (1 - ay) + upper * ay


def _octahedral_border(level: np.ndarray) -> np.ndarray:
    """``level`` ``(n, n, c)`` (row 0 at the bottom) with its border texels copied from
    the interior texels their centres wrap onto (exact: centres land on centres)."""
    n = level.shape[0]
    interior = n - 2
    centres = (np.arange(n, dtype=np.float64) - 0.5) / interior
    s, t = np.meshgrid(centres, centres)
    ws, wt = octahedral_wrap(s, t)
    i = np.clip(np.floor(ws * interior).astype(np.intp), 0, interior - 1) + 1
    j = np.clip(np.floor(wt * interior).astype(np.intp), 0, interior - 1) + 1
    return level[j, i]


def octahedral_levels(level0: np.ndarray, size: int | None = None) -> list[np.ndarray]:
    """Every mip level of an octahedral texture from its level 0 ``(n, n, c)`` float
    (row 0 at the top, border included), each ``(n_k, n_k, c)`` float, row 0 at the top.

    Level ``k`` averages level ``k - 1`` over each of its texels by four bilinear taps at
    the texel's quarter points (a box filter that does not need the interiors to halve
    exactly), reading across the edges through ``k - 1``'s border; then its own border
    is copied in (:func:`octahedral_wrap`). ``size`` (default ``n``) names the levels
    (:func:`octahedral_level_sizes`)."""
    first = np.asarray(level0, dtype=np.float64)[::-1]  # row 0 at the bottom from here
    sizes = octahedral_level_sizes(size or first.shape[0])
    if first.shape[:2] != (sizes[0], sizes[0]):
        raise ValueError(f"level 0 must be ({sizes[0]}, {sizes[0]}, c), got {first.shape}")
    levels = [first]
    for n in sizes[1:]:
        finer = levels[-1]
        fine_interior = finer.shape[0] - 2
        interior = n - 2
        centres = (np.arange(n, dtype=np.float64) - 0.5) / interior
        s, t = np.meshgrid(centres, centres)
        total = np.zeros((n, n, finer.shape[2]))
        for ds in (-0.25, 0.25):
            for dt in (-0.25, 0.25):
                total += _bilinear(
                    finer,
                    1 + (s + ds / interior) * fine_interior,
                    1 + (t + dt / interior) * fine_interior,
                )
        levels.append(_octahedral_border(total / 4))
    return [level[::-1] for level in levels]


# ---------------------------------------------------------------------------- dual paraboloid

PARABOLOID_EXTENT = 1.0625
"""Half the width of a dual-paraboloid texture's square in paraboloid units: the disc
that holds a hemisphere has radius 1, and the square around it reaches
``PARABOLOID_EXTENT`` from its centre, so that a margin of directions from across the
rim surrounds the disc (7.5 texels of 256 at level 0, about one at level 3): bilinear filtering
and mipmaps at the rim read the directions that lie past it, not a clamped edge."""


def paraboloid_map(r) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Dual-paraboloid side and coordinates ``(side, s, t)``, each ``(...)``, of
    directions ``r`` ``(..., 3)`` (Heidrich & Seidel 1998).

    ``side`` (int64) is 0, the front, for ``rz >= 0`` (``-0.0`` too) and 1, the back,
    for ``rz < 0``. Each side is the image of a camera at the centre looking along
    ``+z`` (front) or ``-z`` (back), both with ``+y`` up, through the paraboloid
    ``(a, b) = (ex, ey) / (1 - ez)`` of the camera's eye-space direction ``e``: in world
    terms ``(a, b) = (-rx, ry) / (1 + rz)`` on the front and ``(rx, ry) / (1 - rz)`` on
    the back, ``1 + |rz|`` below both, at least 1. ``s = (1 + a / E) / 2``, ``t = (1 +
    b / E) / 2`` with ``E`` = :data:`PARABOLOID_EXTENT`: the hemisphere fills a disc of
    radius ``1 / (2E)`` around ``(0.5, 0.5)``, its rim (``rz = 0``) the disc's edge.
    A texture holds the front in its left half and the back in its right:
    ``u = (side + s) / 2``. ``r = 0`` gives the front's centre.
    """
    (r,) = _floats(r)
    _check_vectors(r, "r")
    w, _ = _unit(r)
    x, y, z = _split(w)
    front = z >= 0
    scale = 1 / ((1 + np.abs(z)) * PARABOLOID_EXTENT)
    a = np.where(front, -x, x) * scale
    b = y * scale
    side = np.where(front, 0, 1).astype(np.int64)
    s = np.clip(0.5 + 0.5 * a, 0, 1).astype(r.dtype, copy=False)
    t = np.clip(0.5 + 0.5 * b, 0, 1).astype(r.dtype, copy=False)
    return side, s, t


def paraboloid_map_inverse(side, s, t) -> np.ndarray:
    """The unit direction ``(..., 3)`` shown at ``(s, t)`` of ``side`` (0 front, 1 back;
    each ``(...)``, broadcast), continued past the rim: the point at paraboloid radius
    ``q = sqrt(a^2 + b^2)`` (``a = (2s - 1) E``, ``b = (2t - 1) E``) looks along
    ``e = (2a, 2b, q^2 - 1) / (1 + q^2)`` of its camera, in front of it for ``q < 1``
    and behind it, towards the other side's directions, for ``q > 1`` (so the square's
    margin around the disc shows what lies past the rim). Raises ValueError for a side
    other than 0 or 1."""
    side = np.asarray(side)
    if not np.issubdtype(side.dtype, np.integer):
        raise ValueError(f"paraboloid side must be 0 or 1, got dtype {side.dtype}")
    if side.size and (side.min() < 0 or side.max() > 1):
        raise ValueError(f"paraboloid side must be 0 or 1, got values {np.unique(side)}")
    s, t = _floats(s, t)
    side, s, t = np.broadcast_arrays(side, s, t)
    a = (2 * s - 1) * PARABOLOID_EXTENT
    b = (2 * t - 1) * PARABOLOID_EXTENT
    q = a * a + b * b
    front = side == 0
    r = np.stack([np.where(front, -2 * a, 2 * a), 2 * b, np.where(front, 1 - q, q - 1)], axis=-1)
    return _unit(r)[0]


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


def _env_colours(env: EnvFunction, directions: np.ndarray) -> np.ndarray:
    """``env`` over ``directions`` ``(..., 3)`` as float colours ``(..., 3)`` in [0, 1]."""
    flat = np.ascontiguousarray(directions.reshape(-1, 3), dtype=np.float64)
    colours = np.asarray(env(flat), dtype=np.float64)
    if colours.shape != flat.shape:
        raise ValueError(
            f"env must return (n, 3) colours for (n, 3) directions, got "
            f"{colours.shape} for {flat.shape}"
        )
    return np.nan_to_num(np.clip(colours, 0, 1), nan=0.0).reshape(directions.shape)


def _to_uint8(colours: np.ndarray) -> np.ndarray:
    return np.round(np.clip(colours, 0, 1) * 255).astype(np.uint8)


def bake_octahedral(env: EnvFunction, size: int) -> list[np.ndarray]:
    """Every mip level of an octahedral texture ``size`` texels wide of ``env``: a list of
    ``(n_k, n_k, 3)`` uint8 images (row 0 at the top; :func:`octahedral_level_sizes`),
    each with its one-texel border (:func:`octahedral_texel_grid`).

    Level 0 shows ``env`` at each texel centre's direction (the border's continue across
    the edges); the others are filtered from it (:func:`octahedral_levels`)."""
    sizes = octahedral_level_sizes(size)
    s, t = octahedral_texel_grid(sizes[0])
    level0 = _env_colours(env, octahedral_map_inverse(s, t))
    return [_to_uint8(level) for level in octahedral_levels(level0)]


def bake_paraboloid(env: EnvFunction, size: int) -> np.ndarray:
    """A dual-paraboloid image ``(size, 2 size, 3)`` uint8 of ``env``: the front side in
    the left half, the back in the right (:func:`paraboloid_map`), row 0 at the top.
    Every texel, in the disc or in the margin around it, shows ``env`` at its centre's
    direction (:func:`paraboloid_map_inverse`)."""
    size = _check_size(size, "size")
    s, t = _image_grid(size, size)
    halves = [_shade(env, paraboloid_map_inverse(side, s, t)) for side in (0, 1)]
    return np.concatenate(halves, axis=1)


def octahedral_picture_environment(picture: np.ndarray) -> EnvFunction:
    """The environment a square octahedral picture ``(n, n, 3)`` (uint8 or float in [0,
    1], row 0 at the top; the whole picture the square of :func:`octahedral_map`, no
    border) shows: each direction read bilinearly at its coordinates, across the edges
    as :func:`octahedral_wrap` continues them."""
    image = np.asarray(picture)
    if image.ndim != 3 or image.shape[0] != image.shape[1] or image.shape[0] < 2:
        raise ValueError(f"an octahedral picture must be square (n, n, 3), got {image.shape}")
    colours = image.astype(np.float64) / (255.0 if image.dtype == np.uint8 else 1.0)
    n = colours.shape[0]
    padded = np.zeros((n + 2, n + 2, colours.shape[2]))
    padded[1:-1, 1:-1] = colours[::-1]
    padded = _octahedral_border(padded)

    def env(directions: np.ndarray) -> np.ndarray:
        s, t = octahedral_map(directions)
        return _bilinear(padded, 1 + s * n, 1 + t * n)

    return env


def paraboloid_picture_environment(picture: np.ndarray) -> EnvFunction:
    """The environment a dual-paraboloid picture ``(n, 2n, 3)`` (uint8 or float in [0,
    1], row 0 at the top) shows: the front hemisphere's disc in the left square, the
    back's in the right, each disc touching its square's edges (the common layout,
    without :data:`PARABOLOID_EXTENT`'s margin). Each direction is read bilinearly in
    its side's square, clamped to it."""
    image = np.asarray(picture)
    if image.ndim != 3 or image.shape[1] != 2 * image.shape[0] or image.shape[0] < 2:
        raise ValueError(
            f"a dual-paraboloid picture must be twice as wide as high (n, 2n, 3), got {image.shape}"
        )
    colours = image.astype(np.float64) / (255.0 if image.dtype == np.uint8 else 1.0)
    n = colours.shape[0]
    halves = (colours[::-1, :n], colours[::-1, n:])

    def env(directions: np.ndarray) -> np.ndarray:
        side, s, t = paraboloid_map(directions)
        # the picture's discs reach its squares' edges: undo the margin
        s = 0.5 + (s - 0.5) * PARABOLOID_EXTENT
        t = 0.5 + (t - 0.5) * PARABOLOID_EXTENT
        front = _bilinear(halves[0], s * n, t * n)
        back = _bilinear(halves[1], s * n, t * n)
        return np.where((side == 0)[..., None], front, back)

    return env
