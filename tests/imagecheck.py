"""Shared helpers for image tests: geometry-derived expectations, tolerant comparisons,
and diff images written on failure (to tests/_failures/, ignored by git)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from mirrorlab import math3d
from mirrorlab.scene.robot import Camera, LabScene

FAILURES = Path(__file__).resolve().parent / "_failures"


def red_dominant(pixels: np.ndarray) -> np.ndarray:
    """Mask of pixels that can only be the robot's hand: red at least 2.5 times green and
    blue and not near black. ``pixels`` ``(..., 3)`` uint8."""
    p = pixels.astype(np.int32)
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (r > 40) & (r > 2.5 * g) & (r > 2.5 * b)


def near(image: np.ndarray, xy: np.ndarray, radius: int = 2) -> np.ndarray:
    """The ``(2r+1, 2r+1, 3)`` patch of ``image`` around pixel ``xy`` (x right, y down)."""
    x, y = (int(np.floor(v)) for v in xy[:2])
    return image[max(y - radius, 0): y + radius + 1, max(x - radius, 0): x + radius + 1]


def viewer_matrix(camera: Camera, width: int, height: int) -> np.ndarray:
    return camera.projection(width / height) @ camera.view()


def mirror_image_point(scene: LabScene, world_point: np.ndarray) -> np.ndarray:
    """Where the lab's orthographic capture shows ``world_point`` on the mirror ``(3,)``.

    The capture maps a point to texture coordinates by its (z, y) through the
    ortho extents; the mirror quad shows texture coordinate (s, t) at the quad
    point with those coordinates. Derived from the lab's numbers, not from the
    renderer.
    """
    left, right, bottom, top = scene.capture.extents[:4]
    s = (world_point[2] - left) / (right - left)
    t = (world_point[1] - bottom) / (top - bottom)
    return mirror_point_at(scene, s, t)


def mirror_point_at(scene: LabScene, s: float, t: float) -> np.ndarray:
    """The mirror quad's point with texture coordinate (s, t), from its corners."""
    c = scene.mirror.corners  # (s, t) = (0,0), (0,1), (1,1), (1,0)
    return c[0] + s * (c[3] - c[0]) + t * (c[1] - c[0])


def mirror_mask(scene: LabScene, camera: Camera, width: int, height: int,
                inset_px: float = 2.0) -> np.ndarray:
    """``(h, w)`` bool: pixel centres inside the projected mirror quad, at least ``inset_px``
    from its edges."""
    corners = math3d.project_to_pixels(viewer_matrix(camera, width, height),
                                       scene.mirror.corners, width, height)[:, :2]
    ys, xs = np.mgrid[0:height, 0:width] + 0.5
    inside = np.ones((height, width), bool)
    sign = np.sign(_cross2(corners[1] - corners[0], corners[2] - corners[0]))
    for i in range(4):
        a, b = corners[i], corners[(i + 1) % 4]
        edge = b - a
        dist = sign * (edge[0] * (ys - a[1]) - edge[1] * (xs - a[0])) / np.linalg.norm(edge)
        inside &= dist > inset_px
    return inside


def _cross2(u: np.ndarray, v: np.ndarray) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def save_failure(name: str, **images: np.ndarray) -> Path:
    """Write ``images`` as ``tests/_failures/<name>_<key>.png``; returns the folder."""
    FAILURES.mkdir(exist_ok=True)
    for key, image in images.items():
        Image.fromarray(np.asarray(image, dtype=np.uint8)).save(FAILURES / f"{name}_{key}.png")
    return FAILURES


def diff_image(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Absolute difference, amplified x4 for visibility, ``(h, w, 3)`` uint8."""
    d = np.abs(a.astype(np.int16) - b.astype(np.int16)) * 4
    return np.clip(d, 0, 255).astype(np.uint8)


def assert_images_close(name: str, actual: np.ndarray, expected: np.ndarray,
                        channel_tolerance: int, min_fraction_within: float,
                        max_mean_abs: float) -> None:
    """Tolerant image comparison; on failure writes actual, expected and diff PNGs.

    Passes when at least ``min_fraction_within`` of pixels have every channel
    within ``channel_tolerance`` (0-255 scale) and the mean absolute channel
    difference is at most ``max_mean_abs``.
    """
    assert actual.shape == expected.shape, f"{name}: shape {actual.shape} != {expected.shape}"
    diff = np.abs(actual.astype(np.int16) - expected.astype(np.int16))
    within = float(np.mean(diff.max(axis=-1) <= channel_tolerance))
    mean_abs = float(diff.mean())
    if within < min_fraction_within or mean_abs > max_mean_abs:
        folder = save_failure(name, actual=actual, expected=expected,
                              diff=diff_image(actual, expected))
        raise AssertionError(
            f"{name}: {within:.4%} of pixels within {channel_tolerance}/255 "
            f"(need {min_fraction_within:.2%}), mean abs diff {mean_abs:.3f} "
            f"(max {max_mean_abs}); images in {folder}"
        )


def share_within(actual: np.ndarray, expected: np.ndarray, mask: np.ndarray,
                 channel_tolerance: int) -> float:
    """Share of the pixels under ``mask`` ``(h, w)`` whose every channel is within
    ``channel_tolerance`` (0-255 scale); 1.0 for an empty mask."""
    if not mask.any():
        return 1.0
    diff = np.abs(actual.astype(np.int16) - expected.astype(np.int16)).max(axis=-1)
    return float(np.mean(diff[mask] <= channel_tolerance))


def assert_region_close(name: str, actual: np.ndarray, expected: np.ndarray,
                        mask: np.ndarray, channel_tolerance: int,
                        min_fraction_within: float) -> float:
    """Like :func:`assert_images_close` but only over ``mask``; the diff image written on
    failure shows the masked region only. Returns the share within."""
    within = share_within(actual, expected, mask, channel_tolerance)
    if within < min_fraction_within:
        masked = diff_image(actual, expected) * mask[..., None].astype(np.uint8)
        folder = save_failure(name, actual=actual, expected=expected, diff=masked)
        raise AssertionError(
            f"{name}: {within:.4%} of {int(mask.sum())} region pixels within "
            f"{channel_tolerance}/255 (need {min_fraction_within:.2%}); images in {folder}")
    return within
