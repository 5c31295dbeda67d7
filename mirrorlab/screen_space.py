"""Screen-space reflections (technique ``ssr``): the march of a reflected ray through a
view's own depth buffer, in numpy, as the shader (``shaders/ssr_march.frag``) does it,
and the reflector a miss falls back to (its probe). Numpy only.

The march follows McGuire and Mara, "Efficient GPU Screen-Space Ray Tracing" (JCGT 3(4),
2014): the ray's two ends are projected once, and the march steps along the screen
line between them, pixel by pixel (``stride`` pixels a step, along the line's longer
axis), carrying the ray's eye-space depth perspective-correctly (``z / w`` and ``1 / w``
change linearly in screen space). What differs, and why:

- The ray is clipped in clip space to the view's volume (its sides, or the scissored
  part of the target that was drawn, and its near and far planes) before it is
  projected, for any projection (perspective, orthographic, a mirror's oblique near
  plane): a ray towards the eye ends at the near plane, and no end point has w <= 0.
- A sample meets the surface seen there when the ray's depth over the step spans the
  surface's depth. A sample whose whole step lies behind the surface ends the march,
  as a hit or a miss (McGuire and Mara march on behind it, and take it for a hit within
  the thickness wherever it is). Where that surface continues the surface under the
  last sample and the pixel before it along the ray's line (its depth within the
  thickness of what their inverse depths, carried on linearly, give), the ray went
  through that one surface, seen steeply, between the two samples: a hit when it lies
  within ``thickness`` of it, else ``thickness``. Anywhere else a nearer surface came in
  front of the ray (an object's edge): ``behind``, a miss whatever the thickness, since
  what the ray meets there (the object's hidden side, or what lies beyond it) is hidden
  from the view, and a later sample that met a visible surface would show what the
  hidden one covers (a false hit).
- The reflector's own pixels (marked by the pass in the frame's alpha) are never a hit:
  a ray passes over them, and one that lies behind its reflector's own surface there by
  more than the thickness ends as ``own``.
- A hit is narrowed by ``refine`` halvings between the last sample in front and the end
  of the step that met the surface, each looking at the surface's depth under the
  halfway point, interpolated between the pixel centres around it (in inverse depth,
  exact on a plane: the depth of the pixel's centre alone would put every hit up to
  half a pixel off, towards that centre). Its colour is read there, bilinearly.

The shader looks at fewer samples than this reference, to the same effect: it climbs a
pyramid of the frame's nearest depths and passes over all the samples within a block at
once where the ray stays in front of the block's nearest depth (each of them would pass
alone), going back down to single samples where it does not (the hierarchical march of
Uludag, "Hi-Z Screen-Space Cone-Traced Reflections", GPU Pro 5, kept to the DDA's
samples). The tests find the same reason for every pixel.

Every quantity is a function of its inputs alone, with no division by a value that can
be zero and nothing that can become NaN (rays parallel to the screen, towards the eye,
along the line of sight, starting at the screen's edge).

Reasons (:data:`REASONS`) are what the miss mask shows for each reflector pixel.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.scene.model import (
    SSR_NO_PROBE,
    CurvedReflector,
    Reflector,
    ScreenSpace,
    Transform,
)

if TYPE_CHECKING:
    from collections.abc import Sequence

DEFAULTS = ScreenSpace()
"""The settings a reflector without an ``ssr`` table marches with."""

NOT_REFLECTOR, HIT, SCREEN, DISTANCE, STEPS, BEHIND, THICKNESS, OWN = range(8)
REASONS = (
    "not the reflector",
    "hit",
    "left the view",
    "reached its maximum distance",
    "ran out of steps",
    "passed behind something",
    "went through a surface (thickness)",
    "met its own reflector",
)
"""What happened to each pixel's ray, by code (the miss mask's reasons)."""
REASON_COLORS = np.array(
    [
        (0, 0, 0),
        (255, 255, 255),
        (230, 60, 40),
        (240, 200, 40),
        (250, 130, 30),
        (60, 120, 240),
        (170, 80, 220),
        (80, 200, 200),
    ],
    dtype=np.uint8,
)
"""The miss mask picture's colour for each reason (white: a hit, faded hits grey)."""
END_FADE = 0.1
"""The last share of the step budget (and of ``max_distance``) over which hits fade into
the probe."""
FAR_AWAY = 1e30
"""How far a ray no plane of the view ends is followed (world units): far enough for any
scene (a scene's numbers are at most 1e6), near enough that float32 keeps it finite
through a projection."""
MAX_REFINE = 16
MAX_STEPS = 4096
MAX_STRIDE = 64.0


def probe_reflector(reflector: Reflector) -> Reflector | None:
    """The reflector as its probe technique draws it (the ``ssr`` entry's ``probe``): a
    curved reflector with that technique and its own map; a planar mirror as a curved
    reflector over its glass (its pass draws the glass's quad), centred on the mirror,
    with the mirror's map settings. None with :data:`SSR_NO_PROBE`."""
    settings = reflector.ssr or DEFAULTS
    if settings.probe == SSR_NO_PROBE:
        return None
    if isinstance(reflector, CurvedReflector):
        return replace(reflector, technique=settings.probe, ssr=None)
    from mirrorlab.data import data_path

    center = reflector.center
    return CurvedReflector(
        name=reflector.name,
        mesh=data_path("models") / "panel.obj",
        transform=Transform(position=(float(center[0]), float(center[1]), float(center[2]))),
        technique=settings.probe,
        map_size=reflector.map_size,
        source=reflector.source,
        capture_center=reflector.capture_center,
        color=reflector.color,
        parallax=reflector.parallax,
    )


@dataclass(frozen=True)
class MarchResult:
    """What the march found for each of ``n`` rays: ``reason`` ``(n,)`` int (a code of
    :data:`REASONS`), ``pixel`` ``(n, 2)`` float, the window position (x, y in pixels
    from the bottom left; pixel centres at halves) whose colour a hit shows, read
    bilinearly, ``weight`` ``(n,)`` in [0, 1],
    how much of the pixel's colour it gives (the rest is the probe's), and ``steps``
    ``(n,)`` int, the samples taken."""

    reason: np.ndarray
    pixel: np.ndarray
    weight: np.ndarray
    steps: np.ndarray


def eye_depth(window_depth: np.ndarray, pixel: np.ndarray, inverse_projection: np.ndarray, size):
    """The eye-space distance along ``-z`` ``(n,)`` of the surface at window pixels
    ``pixel`` ``(n, 2)`` (integer x, y from the bottom left) whose depth-buffer values
    are ``window_depth`` ``(n,)``, through ``inverse_projection`` ``(4, 4)`` for a
    target of ``size`` (width, height)."""
    width, height = size
    ndc = np.stack(
        [
            (pixel[:, 0] + 0.5) * (2.0 / width) - 1.0,
            (pixel[:, 1] + 0.5) * (2.0 / height) - 1.0,
            2.0 * window_depth - 1.0,
            np.ones(len(pixel)),
        ],
        axis=1,
    )
    z = ndc @ inverse_projection[2]
    w = ndc @ inverse_projection[3]
    return -z / _nonzero(w)


def _nonzero(values: np.ndarray, tiny: float = 1e-30) -> np.ndarray:
    """``values`` with any magnitude below ``tiny`` raised to ``tiny`` (its sign kept)."""
    return np.where(np.abs(values) < tiny, np.where(values < 0, -tiny, tiny), values)


def clip_segment(
    origins: np.ndarray,
    directions: np.ndarray,
    projection: np.ndarray,
    size: Sequence[int],
    screen: tuple[int, int, int, int],
    max_distance: float,
) -> tuple[np.ndarray, np.ndarray]:
    """How far along each ray (eye space: ``origins``, unit ``directions`` ``(n, 3)``) it
    stays within the view: ``(n,)`` end distances and ``(n,)`` reason codes (:data:`SCREEN`
    where the view's sides, near or far plane end it, :data:`DISTANCE` where
    ``max_distance`` does, 0 for none). ``screen`` is the pixel rectangle ``(x, y,
    width, height)`` the view drew."""
    width, height = (float(v) for v in size)
    x, y, w, h = screen
    # the rectangle's sides in normalised device coordinates
    left, right = 2.0 * x / width - 1.0, 2.0 * (x + w) / width - 1.0
    bottom, top = 2.0 * y / height - 1.0, 2.0 * (y + h) / height - 1.0
    ones = np.ones((len(origins), 1))
    start = np.hstack([origins, ones]) @ projection.T
    along = np.hstack([directions, 0.0 * ones]) @ projection.T
    rows = np.array(
        [
            [1.0, 0.0, 0.0, -left],  # x >= left w, written as (row . clip) >= 0
            [-1.0, 0.0, 0.0, right],
            [0.0, 1.0, 0.0, -bottom],
            [0.0, -1.0, 0.0, top],
            [0.0, 0.0, 1.0, 1.0],  # near: z + w >= 0
            [0.0, 0.0, -1.0, 1.0],  # far: w - z >= 0
        ]
    )
    value = start @ rows.T  # (n, 6): >= 0 inside
    rate = along @ rows.T
    # a bound the ray moves towards ends it (a rate below -1e-30: one nearer parallel to
    # it never does, and no division can overflow)
    leaving = np.where(rate < -1e-30, np.maximum(value, 0.0) / np.maximum(-rate, 1e-30), FAR_AWAY)
    end = np.minimum(leaving.min(axis=1), FAR_AWAY)
    limit = max_distance if max_distance > 0.0 else FAR_AWAY
    reason = np.where(end <= limit, SCREEN, DISTANCE)
    return np.minimum(end, limit), reason


def march(
    origins: np.ndarray,
    directions: np.ndarray,
    projection: np.ndarray,
    depth: np.ndarray,
    own: np.ndarray,
    settings: ScreenSpace = DEFAULTS,
    screen: tuple[int, int, int, int] | None = None,
) -> MarchResult:
    """March ``n`` reflected rays through a view's depth buffer, as the shader does.

    ``origins`` and ``directions`` ``(n, 3)``: eye space (the view looks along ``-z``),
    directions of unit length; ``projection`` ``(4, 4)``; ``depth`` ``(height, width)``
    the depth buffer's window depths in [0, 1], row 0 at the bottom (as GL keeps it; 1
    where nothing was drawn); ``own`` ``(height, width)`` bool, the reflector's own
    pixels; ``screen`` the pixel rectangle ``(x, y, width, height)`` that was drawn
    (default: all of it). Float64 throughout.
    """
    origins = np.asarray(origins, dtype=np.float64)
    directions = np.asarray(directions, dtype=np.float64)
    projection = np.asarray(projection, dtype=np.float64)
    height, width = depth.shape
    size = (width, height)
    if screen is None:
        screen = (0, 0, width, height)
    x0, y0 = screen[0], screen[1]
    x1, y1 = screen[0] + screen[2], screen[1] + screen[3]
    count = len(origins)
    inverse = np.linalg.inv(projection)
    end, end_reason = clip_segment(
        origins, directions, projection, size, screen, settings.max_distance
    )

    def window(eye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        clip = np.hstack([eye, np.ones((len(eye), 1))]) @ projection.T
        k = 1.0 / np.maximum(clip[:, 3], 1e-30)
        xy = (clip[:, :2] * k[:, None] + 1.0) * 0.5 * np.array([width, height], dtype=np.float64)
        return xy, k

    s0, k0 = window(origins)
    far_end = origins + directions * end[:, None]
    s1, k1 = window(far_end)
    qz0, qz1 = origins[:, 2] * k0, far_end[:, 2] * k1
    # the ray's window depth, linear along its screen line (both it and the screen
    # position are ratios over the same w): a sample it is in front of there is passed
    # over without a look at eye depths
    wz0 = _window_depth(origins, projection)
    dwz = _window_depth(far_end, projection) - wz0
    span = s1 - s0
    pixels_along = np.maximum(np.abs(span[:, 0]), np.abs(span[:, 1]))
    step = settings.stride / np.maximum(pixels_along, 1e-30)

    def ray_depth(s: np.ndarray) -> np.ndarray:
        """Eye distance of the ray at screen parameter ``s`` (0 at the origin, 1 at the
        end), perspective-correct."""
        k = k0 + s * (k1 - k0)
        return -(qz0 + s * (qz1 - qz0)) / np.maximum(k, 1e-30)

    def pixel_at(s: np.ndarray) -> np.ndarray:
        point = s0 + s[:, None] * span
        p = np.floor(point)
        p[:, 0] = np.clip(p[:, 0], x0, x1 - 1)
        p[:, 1] = np.clip(p[:, 1], y0, y1 - 1)
        return p.astype(np.int64)

    def surface(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z = depth[p[:, 1], p[:, 0]].astype(np.float64)
        empty = z >= 1.0
        distance = eye_depth(z, p.astype(np.float64), inverse, size)
        return np.where(empty, np.inf, distance), empty, own[p[:, 1], p[:, 0]]

    def between(point: np.ndarray) -> np.ndarray:
        """The surface's eye distance at window positions ``point`` ``(m, 2)``: the inverse
        depths of the four pixel centres around it interpolated bilinearly (exact on a
        plane), over those that show a surface (not nothing, not the reflector's own);
        :data:`FAR_AWAY` where none does."""
        corner = np.floor(point - 0.5)
        fraction = point - 0.5 - corner
        inverse = np.zeros(len(point))
        weights = np.zeros(len(point))
        for dx, dy in ((0, 0), (1, 0), (0, 1), (1, 1)):
            p = (corner + np.array([dx, dy])).astype(np.int64)
            p[:, 0] = np.clip(p[:, 0], x0, x1 - 1)
            p[:, 1] = np.clip(p[:, 1], y0, y1 - 1)
            distance, empty, mine = surface(p)
            share = (fraction[:, 0] if dx else 1 - fraction[:, 0]) * (
                fraction[:, 1] if dy else 1 - fraction[:, 1]
            )
            solid = ~empty & ~mine
            inverse += np.where(solid, share / np.where(solid, distance, 1.0), 0.0)
            weights += np.where(solid, share, 0.0)
        inverse /= np.maximum(weights, 1e-30)
        return np.where(inverse > 1e-30, 1.0 / np.maximum(inverse, 1e-30), FAR_AWAY)

    reason = np.zeros(count, dtype=np.int64)
    hit_s = np.zeros(count)
    taken = np.zeros(count, dtype=np.int64)
    # a ray that stays within about its own pixel runs along the line of sight: towards
    # the eye it leaves the view, away from it it runs behind its own surface
    still = pixels_along < 0.5
    towards_eye = ray_depth(np.ones(count)) < ray_depth(np.zeros(count))
    reason[still] = np.where(towards_eye[still], SCREEN, OWN)
    active = ~still
    previous_s = np.zeros(count)
    steps = int(settings.steps)
    for i in range(1, steps + 1):
        if not active.any():
            break
        rays = np.flatnonzero(active)
        s = i * step[rays]
        done = s > 1.0
        if done.any():
            finished = rays[done]
            reason[finished] = end_reason[finished]
            active[finished] = False
            rays, s = rays[~done], s[~done]
            if not len(rays):
                break
        taken[rays] = i
        half = 0.5 * step[rays]
        p = _pixel_of(pixel_at, rays, s, count)
        stored = depth[p[:, 1], p[:, 0]].astype(np.float64)
        start_s, end_s = np.maximum(s - half, 0.0), np.minimum(s + half, 1.0)
        window_far = np.maximum(wz0[rays] + start_s * dwz[rays], wz0[rays] + end_s * dwz[rays])
        passed = (stored >= 1.0) | (window_far < stored)  # nothing there, or in front of it
        previous_s[rays[passed]] = s[passed]
        rays, s, half, p = rays[~passed], s[~passed], half[~passed], p[~passed]
        start_s, end_s = start_s[~passed], end_s[~passed]
        if not len(rays):
            continue
        a = _depth_of(ray_depth, rays, start_s, count)
        b = _depth_of(ray_depth, rays, end_s, count)
        near, far = np.minimum(a, b), np.maximum(a, b)
        seen, empty, mine = surface(p)
        thick = settings.thickness * seen
        reaches = (~empty) & (far >= seen)
        straddles = reaches & (near <= seen)
        behind_all = reaches & (near > seen)  # the whole step behind the surface there
        within = near <= seen + thick
        # the surface under the last sample and the pixel before it along the line, carried
        # on to this one: where the surface here continues it, the ray went through that
        # one surface between the two samples
        pixel_step = 1.0 / np.maximum(pixels_along[rays], 1e-30)
        last = previous_s[rays]
        back = [
            surface(_pixel_of(pixel_at, rays, np.maximum(last - k * pixel_step, 0.0), count))[0]
            for k in (0, 1)
        ]
        carried = _continued(back[1], back[0], (s - last) / pixel_step)
        continues = np.abs(seen - carried) <= thick
        ended = np.zeros(len(rays), dtype=np.int64)
        ended[mine & behind_all & ~within] = OWN
        other = ~mine & behind_all
        ended[other & continues & ~within] = THICKNESS
        ended[other & ~continues] = BEHIND
        met = ~mine & (straddles | (behind_all & continues & within))
        ended[met] = HIT
        stop = ended > 0
        stopped = rays[stop]
        reason[stopped] = ended[stop]
        active[stopped] = False
        hits = rays[met]
        if len(hits):
            hit_s[hits] = _refine(
                previous_s[hits],
                np.minimum(s[met] + half[met], 1.0),
                lambda ss, h=hits: _depth_of(ray_depth, h, ss, count),
                lambda ss, h=hits: between(s0[h] + ss[:, None] * span[h]),
                settings.refine,
            )
        going = rays[~stop]
        previous_s[going] = s[~stop]
    reason[active] = STEPS
    hit = reason == HIT
    pixel = np.zeros((count, 2))
    if hit.any():
        pixel[hit] = _position(s0[hit] + hit_s[hit, None] * span[hit], screen)
    weight = np.where(hit, 1.0, 0.0)
    weight *= fade(pixel, taken, hit_s * end, settings, screen, size)
    return MarchResult(reason, pixel, weight, taken)


def _window_depth(points: np.ndarray, projection: np.ndarray) -> np.ndarray:
    """The window depth ``(n,)`` (0 at the near plane, 1 at the far) of eye-space points
    ``(n, 3)`` through ``projection``."""
    clip = np.hstack([points, np.ones((len(points), 1))]) @ projection.T
    return clip[:, 2] / np.maximum(clip[:, 3], 1e-30) * 0.5 + 0.5


def _continued(before: np.ndarray, last: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """The depth a surface seen under the pixel ``before`` the last sample and under the
    ``last`` sample (eye distances; infinite where nothing was drawn) has ``pixels``
    further on along the ray's line, where it continues: its inverse depth carried on
    linearly (a plane's inverse depth is linear across the screen)."""
    with np.errstate(divide="ignore"):
        predicted = 1.0 / last + (1.0 / last - 1.0 / before) * pixels
    solid = np.isfinite(last) & np.isfinite(before) & (predicted > 1e-30)
    return np.where(solid, 1.0 / np.where(solid, predicted, 1.0), FAR_AWAY)


def _depth_of(ray_depth, rays: np.ndarray, s: np.ndarray, count: int) -> np.ndarray:
    """:func:`march`'s ``ray_depth`` at ``s`` for the rays ``rays`` alone."""
    full = np.zeros(count)
    full[rays] = s
    return ray_depth(full)[rays]


def _pixel_of(pixel_at, rays: np.ndarray, s: np.ndarray, count: int) -> np.ndarray:
    full = np.zeros(count)
    full[rays] = s
    return pixel_at(full)[rays]


def _solid(found: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """The distance of a surface a hit may land on: infinite where nothing was drawn or
    the pixel is the reflector's own."""
    distance, _, mine = found
    return np.where(mine, np.inf, distance)


def _refine(low, high, ray_depth, surface_depth, halvings: int) -> np.ndarray:
    """Narrow each hit to the first place between ``low`` (the last sample before it) and
    ``high`` (the end of the step that met a surface) where the ray reaches the surface
    under it (``surface_depth``):
    ``halvings`` halvings, each keeping the half where the ray crosses. Returns the
    middle of the last interval (with no halving, ``high``): where the ray crosses the
    surface, to a ``2 ** -halvings`` of a step."""
    low, high = low.copy(), high.copy()
    for _ in range(int(halvings)):
        middle = 0.5 * (low + high)
        crossed = ray_depth(middle) >= surface_depth(middle)
        high = np.where(crossed, middle, high)
        low = np.where(crossed, low, middle)
    return high if halvings <= 0 else 0.5 * (low + high)


def _position(point: np.ndarray, screen: tuple[int, int, int, int]) -> np.ndarray:
    """Window positions ``(n, 2)`` kept within the pixel centres of the rectangle
    ``screen`` (where a hit's colour is read, bilinearly)."""
    x, y, w, h = screen
    return np.stack(
        [np.clip(point[:, 0], x + 0.5, x + w - 0.5), np.clip(point[:, 1], y + 0.5, y + h - 0.5)],
        axis=1,
    )


def fade(
    pixel: np.ndarray,
    steps: np.ndarray,
    travelled: np.ndarray,
    settings: ScreenSpace,
    screen: tuple[int, int, int, int],
    size: Sequence[int],
) -> np.ndarray:
    """``(n,)`` in [0, 1]: how much of a hit at window ``pixel`` ``(n, 2)`` (centres),
    found at sample ``steps`` ``(n,)``, ``travelled`` ``(n,)`` world units along its ray,
    is kept: less within ``edge_fade`` of the drawn rectangle ``screen``'s sides and in
    the last :data:`END_FADE` of the step budget and of ``max_distance`` (smoothstep
    ramps), so that a hit hands over to the probe without a jump."""
    x, y, w, h = screen
    edge = np.minimum.reduce(
        [pixel[:, 0] - x, x + w - pixel[:, 0], pixel[:, 1] - y, y + h - pixel[:, 1]]
    )
    width = settings.edge_fade * min(size)
    kept = _smooth(edge / width) if width > 0 else np.ones(len(pixel))
    budget = END_FADE * settings.steps
    kept *= _smooth((settings.steps - steps + 1) / budget)
    if settings.max_distance > 0:
        kept *= _smooth((1.0 - travelled / settings.max_distance) / END_FADE)
    return kept


def _smooth(x: np.ndarray) -> np.ndarray:
    """GLSL's smoothstep(0, 1, x)."""
    t = np.clip(x, 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def reflect_eye(positions: np.ndarray, normals: np.ndarray, orthographic: bool = False):
    """Unit reflected rays ``(n, 3)`` of the view rays through eye-space ``positions``
    ``(n, 3)`` off surfaces with ``normals`` ``(n, 3)`` (eye space; an orthographic view
    looks along ``-z`` everywhere). A zero normal reflects nothing (the ray goes on)."""
    positions = np.asarray(positions, dtype=np.float64)
    if orthographic:
        incoming = np.broadcast_to(np.array([0.0, 0.0, -1.0]), positions.shape)
    else:
        length = np.linalg.norm(positions, axis=1, keepdims=True)
        incoming = np.where(length > 1e-30, positions / np.maximum(length, 1e-300), 0.0)
    n = np.asarray(normals, dtype=np.float64)
    n_length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(n_length > 1e-30, n / np.maximum(n_length, 1e-300), 0.0)
    n = np.where(np.einsum("nd,nd->n", n, incoming)[:, None] > 0.0, -n, n)  # the ray's side
    reflected = incoming - 2.0 * np.einsum("nd,nd->n", n, incoming)[:, None] * n
    r_length = np.linalg.norm(reflected, axis=1, keepdims=True)
    return np.where(r_length > 1e-30, reflected / np.maximum(r_length, 1e-300), [1.0, 0.0, 0.0])


@dataclass(frozen=True)
class MissMask:
    """What screen-space reflections did at each pixel of a frame: ``reason`` ``(h, w)``
    uint8 (a code of :data:`REASONS`; 0 off the reflectors), ``weight`` ``(h, w)``
    float32 in [0, 1] (the share of the pixel's colour from the screen; the rest from
    the probe), ``pixel`` ``(h, w, 2)`` float32 (the window pixel a hit shows, x and y
    from the bottom left). Row 0 at the top, as frames are."""

    reason: np.ndarray
    weight: np.ndarray
    pixel: np.ndarray

    @property
    def reflector(self) -> np.ndarray:
        """``(h, w)`` bool: the pixels where a reflector drawn by ``ssr`` shows."""
        return self.reason != NOT_REFLECTOR

    @property
    def miss_share(self) -> float:
        """The share of the reflector pixels that fell back to the probe entirely (no
        screen colour at all); NaN with no reflector pixel."""
        mine = self.reflector
        return float((self.weight[mine] <= 0.0).mean()) if mine.any() else float("nan")

    @property
    def probe_share(self) -> float:
        """The share of the reflector pixels' colour that came from the probe (faded hits
        counted in part); NaN with no reflector pixel."""
        mine = self.reflector
        return float((1.0 - self.weight[mine]).mean()) if mine.any() else float("nan")

    def counts(self) -> dict[str, int]:
        """How many reflector pixels ended each way, by reason."""
        values = np.bincount(self.reason.ravel(), minlength=len(REASONS))
        return {REASONS[i]: int(values[i]) for i in range(1, len(REASONS))}

    def image(self) -> np.ndarray:
        """``(h, w, 3)`` uint8: the mask as a picture, each reason in its colour
        (:data:`REASON_COLORS`); a faded hit is the probe's share of the reason colour,
        darkened towards grey."""
        picture = REASON_COLORS[np.clip(self.reason, 0, len(REASONS) - 1)].astype(np.float32)
        hits = self.reason == HIT
        shade = 80.0 + 175.0 * self.weight[hits]
        picture[hits] = shade[:, None]
        return np.round(picture).astype(np.uint8)


def handover(mask: MissMask) -> np.ndarray:
    """``(h, w)`` bool: where a reflector's colour hands over from the screen to the probe,
    the pixels whose hit fades into the probe (a weight strictly between 0 and 1: near
    the screen's edges, at the end of the step budget or of ``max_distance``)."""
    return mask.reflector & (mask.weight > 0.0) & (mask.weight < 1.0)


def false_hits(mask: MissMask, visible: np.ndarray, reflector: np.ndarray) -> np.ndarray:
    """``(h, w)`` bool: the pixels of a reflector (``reflector`` ``(h, w)`` bool: where the
    truth's primary ray meets it) where screen-space reflections used a screen pixel
    (a weight above 0) although what the reflected ray meets first is off the screen or
    hidden in the view (``visible`` ``(h, w)`` bool False: see
    :func:`mirrorlab.raytrace.reflection_hits`)."""
    return reflector & mask.reflector & (mask.weight > 0.0) & ~visible
