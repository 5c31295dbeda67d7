"""Culling (:mod:`mirrorlab.culling`) errs large, never small: on generated views and
things, whatever it culls has no point the view can show, and the vectorised tests agree
with the same questions asked one thing at a time. Numpy only. (That culling changes no
pixel is tested with the rasteriser in tests/gl/test_plan_lossless.py.)"""

from __future__ import annotations

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab.culling import (
    boxes_cover_pixels,
    boxes_in_view,
    quads_outside,
    scissor_planes,
    spheres_in_view,
    view_planes,
)

SIZE = (64, 48)


@st.composite
def views(draw):
    """A perspective or orthographic view-projection matrix, and maybe a clip plane."""
    eye = np.array([draw(st.floats(-5, 5)) for _ in range(3)])
    target = eye + np.array([draw(st.floats(-1, 1)) for _ in range(3)])
    target[2] -= 2.5  # never the eye itself
    view = math3d.look_at(eye, target, (0.0, 1.0, 0.0))
    if draw(st.booleans()):
        projection = math3d.perspective(
            draw(st.sampled_from([5.0, 45.0, 120.0, 170.0])),
            SIZE[0] / SIZE[1],
            draw(st.sampled_from([0.05, 1.0])),
            draw(st.sampled_from([10.0, 100.0])),
        )
    else:
        projection = math3d.ortho(-3.0, 3.0, -2.0, 2.0, 0.0, 20.0)
    clip = None
    if draw(st.booleans()):
        normal = np.array([draw(st.floats(-1, 1)) for _ in range(3)])
        normal[2] += 1e-3
        clip = np.append(normal, draw(st.floats(-3, 3)))
        clip *= draw(st.sampled_from([1.0, 0.05, 20.0]))  # no unit normal is promised
    return projection @ view, clip


def inside(points: np.ndarray, matrix: np.ndarray, clip) -> np.ndarray:
    """Which world ``points`` ``(n, 3)`` the clip volume (and clip plane) holds."""
    h = np.column_stack([points, np.ones(len(points))])
    x, y, z, w = (h @ matrix.T).T
    held = (np.abs(x) <= w) & (np.abs(y) <= w) & (np.abs(z) <= w)
    if clip is not None:
        held &= h @ clip >= 0.0
    return held


def samples_of_box(center, half, rng, count=200) -> np.ndarray:
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)])
    return np.vstack([center + half * signs, center + half * rng.uniform(-1, 1, size=(count, 3))])


@settings(max_examples=150, deadline=None)
@given(view=views(), seed=st.integers(0, 2**16))
def test_a_culled_box_has_no_point_in_view(view, seed):
    matrix, clip = view
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-12, 12, size=(40, 3))
    halves = rng.uniform(0.001, 3.0, size=(40, 3))
    kept = boxes_in_view(centers, halves, view_planes(matrix, clip))
    for center, half, keep in zip(centers, halves, kept, strict=True):
        if not keep:
            assert not inside(samples_of_box(center, half, rng), matrix, clip).any()


@settings(max_examples=100, deadline=None)
@given(view=views(), seed=st.integers(0, 2**16))
def test_a_box_culled_by_a_scissor_has_no_point_in_its_rectangle(view, seed):
    matrix, _ = view
    rng = np.random.default_rng(seed)
    x, y = int(rng.integers(0, SIZE[0] - 4)), int(rng.integers(0, SIZE[1] - 4))
    rectangle = (x, y, int(rng.integers(1, SIZE[0] - x)), int(rng.integers(1, SIZE[1] - y)))
    centers = rng.uniform(-12, 12, size=(40, 3))
    halves = rng.uniform(0.001, 2.0, size=(40, 3))
    planes = np.vstack([view_planes(matrix, None), scissor_planes(matrix, SIZE, rectangle)])
    kept = boxes_in_view(centers, halves, planes)
    for center, half, keep in zip(centers, halves, kept, strict=True):
        if keep:
            continue
        points = samples_of_box(center, half, rng)
        seen = inside(points, matrix, None)
        window = math3d.project_to_pixels(matrix, points[seen], *SIZE)
        # in GL window coordinates (y up): no seen point lies in the rectangle
        gx, gy = window[:, 0], SIZE[1] - window[:, 1]
        assert not (
            (gx >= x) & (gx <= x + rectangle[2]) & (gy >= y) & (gy <= y + rectangle[3])
        ).any()


@settings(max_examples=100, deadline=None)
@given(view=views(), seed=st.integers(0, 2**16))
def test_a_box_said_to_cover_no_pixel_spans_no_pixel_centre(view, seed):
    matrix, _ = view
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-6, 6, size=(60, 3))
    halves = rng.uniform(1e-4, 0.05, size=(60, 3))
    covering = boxes_cover_pixels(centers, halves, matrix, SIZE)
    for center, half, covers in zip(centers, halves, covering, strict=True):
        if covers:
            continue
        points = samples_of_box(center, half, rng)
        clip = np.column_stack([points, np.ones(len(points))]) @ matrix.T
        assert np.all(clip[:, 3] > 0)  # a box reaching behind the eye is never said so
        gx = (clip[:, 0] / clip[:, 3] + 1) * SIZE[0] / 2
        gy = (clip[:, 1] / clip[:, 3] + 1) * SIZE[1] / 2
        # the sampled points' box holds no pixel centre (i + 0.5, j + 0.5) of the target
        first_x, last_x = (
            max(np.ceil(gx.min() - 0.5), 0),
            min(np.floor(gx.max() - 0.5), SIZE[0] - 1),
        )
        first_y, last_y = (
            max(np.ceil(gy.min() - 0.5), 0),
            min(np.floor(gy.max() - 0.5), SIZE[1] - 1),
        )
        assert first_x > last_x or first_y > last_y


SCISSORS = [(-1.0, 1.0, -1.0, 1.0), (-0.5, 0.25, -0.75, 0.875), (0.5, 0.625, -1.0, -0.5)]
"""The sides of views narrowed by scissors (:func:`mirrorlab.culling.scissor_bounds`), the
whole view first."""


def reference_outside(
    corners: np.ndarray, matrix: np.ndarray, clip, orthographic: bool, sides=SCISSORS[0]
) -> int:
    """One quad's code, asked side by side as the one-reflector test did (exact
    comparisons)."""
    h = np.column_stack([corners, np.ones(4)])
    if clip is not None and np.all(h @ clip < 0.0):
        return 1
    x, y, z, w = (h @ matrix.T).T
    if not orthographic and np.all(w <= 0.0):
        return 2
    left, right, bottom, top = sides
    for code, beyond in enumerate(
        (x < left * w, x > right * w, y < bottom * w, y > top * w, z < -w, z > w), start=3
    ):
        if np.all(beyond):
            return code
    return 0


@settings(max_examples=150, deadline=None)
@given(view=views(), seed=st.integers(0, 2**16), sides=st.sampled_from(SCISSORS))
def test_quads_outside_agrees_with_asking_each_quad_on_its_own(view, seed, sides):
    matrix, clip = view
    rng = np.random.default_rng(seed)
    corners = rng.uniform(-15, 15, size=(30, 1, 3)) + rng.uniform(-2, 2, size=(30, 4, 3))
    orthographic = bool(np.allclose(matrix[3, :3], 0.0))
    codes = quads_outside(corners, matrix, clip, orthographic, sides)
    for quad, code in zip(corners, codes, strict=True):
        expected = reference_outside(quad, matrix, clip, orthographic, sides)
        # beyond a side by more than a rounding: the same code; within a rounding of
        # it, the vectorised test may keep a quad the exact one would call outside
        assert code == expected or (code == 0 and _near_a_side(quad, matrix, clip, sides))


def _near_a_side(quad, matrix, clip, sides) -> bool:
    h = np.column_stack([quad, np.ones(4)])
    x, y, z, w = (h @ matrix.T).T
    left, right, bottom, top = sides
    leads = np.stack([x - left * w, right * w - x, y - bottom * w, top * w - y, z + w, w - z])
    near = np.any(np.abs(leads) <= 1e-8 * (np.abs(w) + np.abs(np.stack([x, x, y, y, z, z]))))
    if clip is not None:
        near |= bool(np.any(np.abs(h @ clip) <= 1e-8 * (np.abs(h) @ np.abs(clip))))
    return bool(near)


# a clip plane whose normal is not a unit vector: the sphere test once read its value as
# a distance and culled spheres reaching just across it
LONG_NORMAL_VIEW = (
    math3d.perspective(120.0, SIZE[0] / SIZE[1], 0.05, 10.0),
    np.array([1.0, 0.125, 1.001, 0.0]),
)


@settings(max_examples=100, deadline=None)
@given(view=views(), seed=st.integers(0, 2**16))
@example(view=LONG_NORMAL_VIEW, seed=0)
def test_a_culled_sphere_has_no_point_in_view(view, seed):
    matrix, clip = view
    rng = np.random.default_rng(seed)
    centers = rng.uniform(-12, 12, size=(30, 3))
    radii = rng.uniform(0.01, 3.0, size=30)
    kept = spheres_in_view(centers, radii, matrix, clip)
    for center, radius, keep in zip(centers, radii, kept, strict=True):
        if keep:
            continue
        directions = rng.normal(size=(300, 3))
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        points = center + directions * radius * rng.uniform(0, 1, size=(300, 1)) ** (1 / 3)
        assert not inside(points, matrix, clip).any()


def test_a_needle_thin_views_planes_measure_spheres_without_overflow():
    """A view's plane normals as long as 1e300 (a projection that magnifies that much):
    the distances to them are measured without a square that overflows, and a sphere on
    the axis is in view while one beside it is not."""
    projection = np.diag([1e300, 1e300, -1.0, 0.0])
    projection[2, 3], projection[3, 2] = -0.2, -1.0  # looks down -z, near 0.1
    centers = np.array([[0.0, 0.0, -10.0], [5.0, 0.0, -10.0]])
    with np.errstate(all="raise"):
        inside = spheres_in_view(centers, np.array([1.0, 1.0]), projection, None)
    assert inside.tolist() == [True, False]
