"""Footprints (:mod:`mirrorlab.footprint`) err large, never small: for random mirrors and
spheres seen by random cameras (rolled, tilted, lenses from 2 to 178 degrees, reaching
across the view's edges and behind the eye), every pixel whose centre sees the reflector
lies in the footprint's bounds, and their number is at most its pixel count. The
pixels are found independently: a ray through each pixel centre, met with the quad or
the sphere in numpy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab.footprint import clip_polygon, polygon_area, polygon_footprint, sphere_footprint
from mirrorlab.plan import reflector_footprint
from mirrorlab.scene.model import Camera, PlanarReflector
from mirrorlab.views import camera_view
from tests.scenekit import quad

SIZE = (48, 36)


def pixel_rays(camera: Camera, size) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origins on the near plane and unit directions ``(h, w, 3)`` of the rays through the
    pixel centres (GL window rows: row 0 at the bottom), and the view's forward axis."""
    width, height = size
    inverse = np.linalg.inv(camera.projection(width / height) @ camera.view())
    x = (np.arange(width) + 0.5) / width * 2 - 1
    y = (np.arange(height) + 0.5) / height * 2 - 1
    ndc_x, ndc_y = np.meshgrid(x, y)
    flat = np.stack([ndc_x.ravel(), ndc_y.ravel()], axis=1)

    def unproject(z):
        points = np.column_stack([flat, np.full(len(flat), z), np.ones(len(flat))]) @ inverse.T
        return points[:, :3] / points[:, 3:]

    near, far = unproject(-1.0), unproject(1.0)
    directions = far - near
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    forward = -camera.view()[2, :3]
    return (near.reshape(height, width, 3), directions.reshape(height, width, 3), forward)


def depth_ok(camera: Camera, points: np.ndarray, forward: np.ndarray) -> np.ndarray:
    near, far = camera.depth_range
    depth = (points - np.asarray(camera.eye)) @ forward
    return (depth >= near) & (depth <= far)


def quad_pixels(corners: np.ndarray, camera: Camera, size) -> np.ndarray:
    """``(h, w)`` bool: pixel centres whose ray meets the convex quad within near..far."""
    origin, direction, forward = pixel_rays(camera, size)
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    denominator = direction @ normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((corners[0] - origin) @ normal) / denominator
    hit = origin + t[..., None] * direction
    inside = np.isfinite(t) & (t >= 0)
    for i in range(4):
        a, b = corners[i], corners[(i + 1) % 4]
        inside &= (np.cross(b - a, hit - a) @ normal) >= 0
    return inside & depth_ok(camera, hit, forward)


def sphere_pixels(center: np.ndarray, radius: float, camera: Camera, size) -> np.ndarray:
    origin, direction, forward = pixel_rays(camera, size)
    offset = origin - center
    b = np.einsum("hwd,hwd->hw", offset, direction)
    c = np.einsum("hwd,hwd->hw", offset, offset) - radius * radius
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    hit = (disc >= 0) & (-b + root >= 0)
    t = np.where(-b - root >= 0, -b - root, -b + root)
    points = origin + t[..., None] * direction
    # anything of the sphere within near..far along that ray: entry or exit inside it
    exit_points = origin + (-b + root)[..., None] * direction
    return hit & (depth_ok(camera, points, forward) | depth_ok(camera, exit_points, forward))


def assert_covers(footprint, covered: np.ndarray) -> None:
    count = int(covered.sum())
    assert footprint.pixels >= count, (footprint.pixels, count)
    if count:
        assert footprint.bounds is not None, count
        x, y, w, h = footprint.bounds
        rows, cols = np.nonzero(covered)
        assert cols.min() >= x and cols.max() < x + w, (footprint.bounds, cols.min(), cols.max())
        assert rows.min() >= y and rows.max() < y + h, (footprint.bounds, rows.min(), rows.max())


def test_a_long_thin_mirror_across_the_view_is_not_a_line():
    # 40 x 0.6, crossing the view diagonally with both ends far outside it: clamping each
    # projected corner to the screen collapsed it to about 0 pixels.
    camera = Camera(eye=(0.0, 0.0, 10.0), target=(0.0, 0.0, 0.0), fovy=45.0)
    corners = np.array(quad((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (1.0, 1.0, 0.0), 0.6, 40.0))
    size = (160, 160)
    footprint = polygon_footprint(corners, camera.projection(1.0) @ camera.view(), size)
    covered = quad_pixels(corners, camera, size)
    assert covered.sum() > 1000
    assert_covers(footprint, covered)
    assert footprint.area == pytest.approx(covered.sum(), rel=0.1)


def test_a_rolled_horizontal_strip_keeps_its_pixels():
    for roll in (20.0, 45.0, 60.0):
        up = (np.sin(np.radians(roll)), np.cos(np.radians(roll)), 0.0)
        camera = Camera(eye=(0.0, 0.5, 8.0), target=(0.0, 0.0, 0.0), up=up, fovy=60.0)
        corners = np.array(quad((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), 60.0, 0.5))
        footprint = polygon_footprint(corners, camera.projection(1.0) @ camera.view(), (128, 128))
        covered = quad_pixels(corners, camera, (128, 128))
        assert covered.sum() > 300
        assert_covers(footprint, covered)


def test_a_sphere_sixty_degrees_off_axis_in_a_wide_lens_covers_its_stretched_ellipse():
    camera = Camera(eye=(0.0, 0.0, 0.0), target=(0.0, 0.0, -1.0), fovy=150.0)
    angle = np.radians(60.0)
    center = np.array([np.sin(angle), 0.0, -np.cos(angle)]) * 20.0
    size = (128, 128)
    footprint = sphere_footprint(center, 1.0, camera.view(), camera.projection(1.0), size)
    covered = sphere_pixels(center, 1.0, camera, size)
    assert covered.sum() >= 10
    assert_covers(footprint, covered)
    # the small-angle circle (radius * focal / depth) is the size on the axis only
    focal = size[1] / 2 / np.tan(np.radians(75.0))
    on_axis = np.pi * (focal / 20.0) ** 2
    assert footprint.area > 2.0 * on_axis


def test_clipping_in_clip_space_keeps_what_lies_in_front_of_the_eye():
    # a square half behind the eye: only the half in front is kept
    square = np.array([[-1, -1, -1, 1], [1, -1, -1, 1], [1, 1, -1, 1], [-1, 1, -1, 1.0]])
    half = clip_polygon(square, np.array([[1.0, 0, 0, 0]]))  # x >= 0
    assert len(half) == 4 and polygon_area(half[:, :2]) == pytest.approx(2.0)
    assert len(clip_polygon(square, np.array([[0, 0, 0, -1.0]]))) == 0


def test_a_mirror_behind_a_clip_plane_has_no_footprint():
    camera = Camera(eye=(0.0, 0.0, 10.0), target=(0.0, 0.0, 0.0))
    corners = np.array(quad((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), 4.0, 4.0))
    matrix = camera.projection(1.0) @ camera.view()
    assert not polygon_footprint(corners, matrix, SIZE).empty
    behind = math3d.plane_through((0.0, 0.0, 1.0), (0.0, 0.0, 1.0))  # keeps z >= 1 only
    assert polygon_footprint(corners, matrix, SIZE, behind).empty
    crossing = math3d.plane_through((0.0, 0.0, 0.0), (1.0, 0.0, 0.0))  # keeps x >= 0
    half = polygon_footprint(corners, matrix, SIZE, crossing)
    whole = polygon_footprint(corners, matrix, SIZE)
    assert half.area == pytest.approx(whole.area / 2, rel=1e-4)  # the slack errs large


unit = st.floats(-1.0, 1.0)


@st.composite
def cameras(draw):
    eye = np.array([draw(st.floats(-12, 12)), draw(st.floats(-6, 6)), draw(st.floats(-12, 12))])
    look = np.array([draw(unit), draw(unit), draw(unit)])
    if np.linalg.norm(look) < 0.2:
        look = np.array([0.0, 0.0, -1.0])
    roll = np.radians(draw(st.floats(-180, 180)))
    forward = look / np.linalg.norm(look)
    side = np.cross(forward, [0.0, 1.0, 0.0])
    if np.linalg.norm(side) < 0.1:
        side = np.array([1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cos(roll) * np.cross(side, forward) + np.sin(roll) * side
    fovy = draw(st.sampled_from([2.0, 10.0, 45.0, 90.0, 150.0, 178.0]))
    near = draw(st.sampled_from([0.01, 0.1, 1.0]))
    far = draw(st.sampled_from([3.0, 30.0, 300.0]))
    return Camera(
        eye=tuple(eye),
        target=tuple(eye + look),
        up=tuple(up),
        fovy=fovy,
        near=near,
        far=max(far, near * 2),
    )


@settings(max_examples=150, deadline=None)
@given(
    camera=cameras(),
    center=st.tuples(st.floats(-10, 10), st.floats(-5, 5), st.floats(-10, 10)),
    normal=st.tuples(unit, unit, unit),
    up=st.tuples(unit, unit, unit),
    width=st.floats(0.05, 60.0),
    height=st.floats(0.05, 60.0),
    aspect=st.sampled_from([(48, 36), (36, 48), (40, 40), (64, 16)]),
)
def test_a_mirror_footprint_holds_every_pixel_it_covers(
    camera, center, normal, up, width, height, aspect
):
    normal = np.array(normal)
    if np.linalg.norm(normal) < 0.1 or np.linalg.norm(np.cross(normal, up)) < 0.1:
        return
    corners = quad(center, normal, up, width, height)
    mirror = PlanarReflector("m", corners)
    view = camera_view(camera, aspect)
    footprint = reflector_footprint(mirror, view)
    assert_covers(footprint, quad_pixels(np.array(corners), camera, aspect))


@settings(max_examples=150, deadline=None)
@given(
    camera=cameras(),
    center=st.tuples(st.floats(-10, 10), st.floats(-5, 5), st.floats(-10, 10)),
    radius=st.floats(0.05, 8.0),
    aspect=st.sampled_from([(48, 36), (36, 48), (40, 40), (64, 16)]),
)
def test_a_sphere_footprint_holds_every_pixel_it_covers(camera, center, radius, aspect):
    view = camera_view(camera, aspect)
    center = np.array(center)
    footprint = sphere_footprint(center, radius, view.view, view.projection, aspect)
    assert_covers(footprint, sphere_pixels(center, radius, camera, aspect))
