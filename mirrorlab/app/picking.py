"""Which reflector is under the mouse: a ray from the camera through a pixel, met with each
reflector (a planar mirror's quad, a curved reflector's bounding sphere). Numpy only.

Window systems give the cursor in window coordinates, which on a high-DPI screen are
fewer than the framebuffer's pixels: :func:`framebuffer_pixel` scales one to the other.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mirrorlab.plan import bounding_sphere
from mirrorlab.scene.model import Camera, CurvedReflector, PlanarReflector, Scene


def framebuffer_pixel(
    cursor: Sequence[float], window_size: Sequence[int], framebuffer_size: Sequence[int]
) -> tuple[float, float] | None:
    """The framebuffer position ``(x right, y down)`` in pixels of a cursor at ``cursor``
    in window coordinates; None when the cursor is outside the window."""
    x, y = (float(v) for v in cursor)
    width, height = (int(v) for v in window_size)
    if width <= 0 or height <= 0 or not (0.0 <= x < width and 0.0 <= y < height):
        return None
    fb_width, fb_height = (int(v) for v in framebuffer_size)
    return x * fb_width / width, y * fb_height / height


def pixel_ray(
    camera: Camera, size: Sequence[int], pixel: Sequence[float]
) -> tuple[np.ndarray, np.ndarray]:
    """World origin ``(3,)`` on the near plane and unit direction ``(3,)`` of the ray
    through framebuffer position ``pixel`` (x right, y down, in pixels) of a ``size``
    (width, height) frame."""
    width, height = (int(v) for v in size)
    ndc_x = 2.0 * float(pixel[0]) / width - 1.0
    ndc_y = 1.0 - 2.0 * float(pixel[1]) / height
    inverse = np.linalg.inv(camera.projection(width / height) @ camera.view())
    ends = inverse @ np.array([[ndc_x, ndc_y, -1.0, 1.0], [ndc_x, ndc_y, 1.0, 1.0]]).T
    near, far = (ends[:3] / ends[3]).T
    direction = far - near
    return near, direction / np.linalg.norm(direction)


def _hit_planar(
    reflector: PlanarReflector, origin: np.ndarray, direction: np.ndarray
) -> float | None:
    normal = np.asarray(reflector.normal, dtype=np.float64)
    facing = float(direction @ normal)
    if abs(facing) < 1e-12:
        return None
    distance = float((np.asarray(reflector.center) - origin) @ normal) / facing
    if distance <= 0.0:
        return None
    point = origin + distance * direction
    corners = reflector.corner_array.astype(np.float64)
    # Inside the convex quad: on the inner side of each edge (as seen along the normal).
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        if float(np.cross(b - a, point - a) @ normal) < 0.0:
            return None
    return distance


def _hit_curved(
    reflector: CurvedReflector, origin: np.ndarray, direction: np.ndarray
) -> float | None:
    center, radius = bounding_sphere(reflector)
    offset = origin - center
    half_b = float(offset @ direction)
    c = float(offset @ offset) - radius * radius
    discriminant = half_b * half_b - c
    if discriminant < 0.0:
        return None
    root = np.sqrt(discriminant)
    for distance in (-half_b - root, -half_b + root):
        if distance > 0.0:
            return float(distance)
    return None


def pick_reflector(scene: Scene, size: Sequence[int], pixel: Sequence[float]) -> int | None:
    """Index in ``scene.reflectors`` of the nearest reflector the camera sees at ``pixel``
    (framebuffer pixels, x right, y down, of a ``size`` frame), or None."""
    origin, direction = pixel_ray(scene.camera, size, pixel)
    best: tuple[float, int] | None = None
    for index, reflector in enumerate(scene.reflectors):
        if isinstance(reflector, PlanarReflector):
            distance = _hit_planar(reflector, origin, direction)
        else:
            distance = _hit_curved(reflector, origin, direction)
        if distance is not None and (best is None or distance < best[0]):
            best = (distance, index)
    return None if best is None else best[1]
