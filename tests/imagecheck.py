"""Shared helpers for image tests: geometry-derived expectations, tolerant comparisons,
and diff images written on failure (to tests/_failures/, ignored by git)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.model import Camera, PlanarReflector
from mirrorlab.testing import assert_image_close, difference_image, save_images

FAILURES = Path(__file__).resolve().parent / "_failures"
os.environ.setdefault("MIRRORLAB_FAILURES", str(FAILURES))


def red_dominant(pixels: np.ndarray) -> np.ndarray:
    """Mask of pixels that can only be the robot's hand: red at least 2.5 times green and
    blue and not near black. ``pixels`` ``(..., 3)`` uint8."""
    p = pixels.astype(np.int32)
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (r > 40) & (r > 2.5 * g) & (r > 2.5 * b)


def near(image: np.ndarray, xy: np.ndarray, radius: int = 2) -> np.ndarray:
    """The ``(2r+1, 2r+1, 3)`` patch of ``image`` around pixel ``xy`` (x right, y down)."""
    x, y = (int(np.floor(v)) for v in xy[:2])
    return image[max(y - radius, 0) : y + radius + 1, max(x - radius, 0) : x + radius + 1]


def viewer_matrix(camera: Camera, width: int, height: int) -> np.ndarray:
    return camera.projection(width / height) @ camera.view()


def mirror_image_point(mirror: PlanarReflector, world_point: np.ndarray) -> np.ndarray:
    """Where an ``ortho`` mirror's capture shows ``world_point`` on the glass ``(3,)``.

    The capture maps a point to texture coordinates through its orthographic camera;
    the quad shows texture coordinate (s, t) at the point with those coordinates.
    For the lab's numbers: s = (z + 6) / 8, t = (y + 3) / 8.
    """
    capture = mirror.ortho_capture
    clip = math3d.transform_points(capture.projection() @ capture.view(), world_point)
    s, t = (clip[:2] / clip[3] + 1.0) / 2.0
    return mirror_point_at(mirror, s, t)


def mirror_point_at(mirror: PlanarReflector, s: float, t: float) -> np.ndarray:
    """The quad's point with texture coordinate (s, t), from its corners (corner 0 at
    (0, 0), 1 at (0, 1), 3 at (1, 0), as the lab's mirror has them)."""
    c = mirror.corner_array
    return c[0] + s * (c[3] - c[0]) + t * (c[1] - c[0])


def mirror_mask(
    mirror: PlanarReflector, camera: Camera, width: int, height: int, inset_px: float = 2.0
) -> np.ndarray:
    """``(h, w)`` bool: pixel centres inside the projected mirror quad, at least ``inset_px``
    from its edges."""
    corners = math3d.project_to_pixels(
        viewer_matrix(camera, width, height), mirror.corner_array, width, height
    )[:, :2]
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    inside = np.ones((height, width), bool)
    edge_a, edge_b = corners[1] - corners[0], corners[2] - corners[0]
    sign = np.sign(edge_a[0] * edge_b[1] - edge_a[1] * edge_b[0])
    for i in range(4):
        a, b = corners[i], corners[(i + 1) % 4]
        edge = b - a
        dist = sign * (edge[0] * (ys - a[1]) - edge[1] * (xs - a[0])) / np.linalg.norm(edge)
        inside &= dist > inset_px
    return inside


def save_failure(name: str, **images: np.ndarray) -> Path:
    """Write ``images`` as ``tests/_failures/<name>_<key>.png``; returns the folder."""
    return save_images(name, **images)


def assert_images_close(
    name: str,
    actual: np.ndarray,
    expected: np.ndarray,
    channel_tolerance: int,
    min_fraction_within: float,
    max_mean_abs: float,
) -> None:
    """Tolerant image comparison (:func:`mirrorlab.testing.assert_image_close`); on failure
    writes actual, expected and diff PNGs."""
    assert_image_close(actual, expected, channel_tolerance, min_fraction_within, max_mean_abs, name)


def share_within(
    actual: np.ndarray, expected: np.ndarray, mask: np.ndarray, channel_tolerance: int
) -> float:
    """Share of the pixels under ``mask`` ``(h, w)`` whose every channel is within
    ``channel_tolerance`` (0-255 scale); 1.0 for an empty mask."""
    if not mask.any():
        return 1.0
    diff = np.abs(actual.astype(np.int16) - expected.astype(np.int16)).max(axis=-1)
    return float(np.mean(diff[mask] <= channel_tolerance))


def assert_region_close(
    name: str,
    actual: np.ndarray,
    expected: np.ndarray,
    mask: np.ndarray,
    channel_tolerance: int,
    min_fraction_within: float,
) -> float:
    """Like :func:`assert_images_close` but only over ``mask``; the diff image written on
    failure shows the masked region only. Returns the share within."""
    within = share_within(actual, expected, mask, channel_tolerance)
    if within < min_fraction_within:
        masked = difference_image(actual, expected) * mask[..., None].astype(np.uint8)
        folder = save_failure(name, actual=actual, expected=expected, diff=masked)
        raise AssertionError(
            f"{name}: {within:.4%} of {int(mask.sum())} region pixels within "
            f"{channel_tolerance}/255 (need {min_fraction_within:.2%}); images in {folder}"
        )
    return within
