"""The numpy reference of screen-space reflections' march (:mod:`mirrorlab.screen_space`):
hand-made depth buffers with known answers, every way a ray can end, and with
hypothesis, finite results in range for any ray, projection and depth buffer (rays
parallel to the screen, towards the eye, from the screen's edge)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab import screen_space as ss
from mirrorlab.scene.model import ScreenSpace

SIZE = 64
PROJECTION = math3d.perspective(60.0, 1.0, 0.1, 100.0)


def window_depth(distance, projection=PROJECTION) -> float:
    """The depth buffer's value of a point at eye depth ``distance`` on the view axis."""
    clip = projection @ np.array([0.0, 0.0, -float(distance), 1.0])
    return float((clip[2] / clip[3] + 1.0) / 2.0)


def wall(distance: float) -> np.ndarray:
    """A depth buffer of a wall facing the eye at ``distance`` (eye depth everywhere: a
    plane z = -distance)."""
    return np.full((SIZE, SIZE), window_depth(distance))


def nothing_own() -> np.ndarray:
    return np.zeros((SIZE, SIZE), dtype=bool)


def ray_at(pixel, distance, direction):
    """Origin ``(1, 3)`` on the eye ray through window ``pixel`` at eye depth
    ``distance``, and the unit ``direction`` ``(1, 3)``."""
    ndc = (np.asarray(pixel, dtype=float) + 0.5) / SIZE * 2.0 - 1.0
    inverse = np.linalg.inv(PROJECTION)
    point = inverse @ np.array([ndc[0], ndc[1], -1.0, 1.0])
    along = point[:3] / point[3]
    origin = along * (distance / -along[2])
    d = np.asarray(direction, dtype=float)
    return origin[None], (d / np.linalg.norm(d))[None]


def pixel_of(point) -> np.ndarray:
    clip = PROJECTION @ np.append(point, 1.0)
    return (clip[:2] / clip[3] + 1.0) / 2.0 * SIZE


def test_a_ray_towards_a_wall_hits_it_where_it_meets_it():
    origin, direction = ray_at((20, 32), 5.0, (0.6, 0.1, -0.8))
    result = ss.march(origin, direction, PROJECTION, wall(8.0), nothing_own())
    assert result.reason[0] == ss.HIT
    t = (8.0 - 5.0) / 0.8 * np.linalg.norm((0.6, 0.1, -0.8))  # where z = -8
    expected = pixel_of(origin[0] + direction[0] * t)
    assert np.abs(result.pixel[0] - expected).max() <= 1.0
    assert 0.0 < result.weight[0] <= 1.0


def test_the_ray_depth_is_perspective_correct():
    """Marched pixel by pixel, the hit lies where the 3-D ray meets the wall, to a pixel,
    for walls near and far and rays steep and shallow (a linear depth in screen space
    would put it far off)."""
    for depth in (1.0, 3.0, 20.0):
        for direction in ((0.9, 0.0, -0.44), (0.2, 0.3, -0.93), (-0.5, -0.5, -0.7)):
            origin, d = ray_at((32, 32), 0.8 * depth, direction)
            result = ss.march(origin, d, PROJECTION, wall(depth), nothing_own())
            t = (0.2 * depth) / -d[0, 2]
            point = origin[0] + d[0] * t
            inside = (pixel_of(point) >= 0).all() and (pixel_of(point) < SIZE).all()
            if inside:
                assert result.reason[0] == ss.HIT, (depth, direction)
                assert np.abs(result.pixel[0] - pixel_of(point)).max() <= 1.0


def test_a_ray_towards_the_eye_leaves_the_view_through_the_near_plane():
    origin, direction = np.array([[0.0, 0.0, -5.0]]), np.array([[0.0, 0.0, 1.0]])
    result = ss.march(origin, direction, PROJECTION, wall(8.0), nothing_own())
    assert result.reason[0] == ss.SCREEN and result.weight[0] == 0.0
    end, reason = ss.clip_segment(
        origin, direction, PROJECTION, (SIZE, SIZE), (0, 0, SIZE, SIZE), 0.0
    )
    near_point = origin[0] + direction[0] * end[0]
    assert abs(-near_point[2] - 0.1) < 1e-9 and reason[0] == ss.SCREEN


def test_a_ray_along_the_line_of_sight_away_runs_behind_its_own_surface():
    origin, _ = ray_at((32, 32), 5.0, (0, 0, -1))
    direction = origin / np.linalg.norm(origin)
    result = ss.march(origin, direction, PROJECTION, wall(8.0), nothing_own())
    assert result.reason[0] == ss.OWN


def test_a_ray_parallel_to_the_screen_leaves_it_at_its_side():
    origin, direction = ray_at((32, 32), 5.0, (1.0, 0.0, 0.0))
    result = ss.march(origin, direction, PROJECTION, wall(8.0), nothing_own())
    assert result.reason[0] == ss.SCREEN
    assert result.steps[0] >= SIZE // 2 - 2  # it crossed half the screen, pixel by pixel


def test_a_ray_that_goes_behind_an_object_is_a_miss():
    depth = wall(20.0)
    depth[:, 40:44] = window_depth(5.2)  # a post in front of the far wall
    origin, direction = ray_at((30, 32), 5.0, (0.7, 0.0, -0.7))  # behind the post at x=40
    result = ss.march(origin, direction, PROJECTION, depth, nothing_own())
    assert result.reason[0] == ss.BEHIND


def plane_depth(normal, point) -> np.ndarray:
    """The depth buffer of a plane through eye-space ``point`` with ``normal``."""
    inverse = np.linalg.inv(PROJECTION)
    x, y = np.meshgrid(
        (np.arange(SIZE) + 0.5) / SIZE * 2 - 1, (np.arange(SIZE) + 0.5) / SIZE * 2 - 1
    )
    near = np.stack([x, y, -np.ones_like(x), np.ones_like(x)], axis=-1) @ inverse.T
    rays = near[..., :3] / near[..., 3:]
    n = np.asarray(normal, dtype=float)
    t = (n @ np.asarray(point, dtype=float)) / (rays @ n)
    hit = rays * t[..., None]
    clip = np.concatenate([hit, np.ones_like(t)[..., None]], axis=-1) @ PROJECTION.T
    return np.where(t > 0, (clip[..., 2] / clip[..., 3] + 1) / 2, 1.0)


def test_a_thickness_too_small_for_the_step_is_told_apart():
    """A ray that goes through one steep surface (a side wall seen at a grazing angle)
    farther than the thickness within one step fails the thickness test; a thicker
    surface (or a finer stride) catches it. An object's edge coming in front of the ray
    is another thing: the ray passed behind it."""
    side_wall = plane_depth((-1.0, 0.0, 0.1), (1.0, 0.0, -10.0))
    origin, direction = ray_at((32, 32), 5.0, (1.0, 0.0, -0.2))
    coarse = ScreenSpace(stride=8.0, thickness=0.005, refine=0)
    result = ss.march(origin, direction, PROJECTION, side_wall, nothing_own(), coarse)
    assert result.reason[0] == ss.THICKNESS
    for fixed in (replace(coarse, thickness=0.5), replace(coarse, stride=1.0, thickness=0.05)):
        again = ss.march(origin, direction, PROJECTION, side_wall, nothing_own(), fixed)
        assert again.reason[0] == ss.HIT
    post = wall(20.0)
    post[:, 40:56] = window_depth(5.2)  # an object's edge: behind it, whatever the thickness
    origin, direction = ray_at((30, 32), 5.0, (0.7, 0.0, -0.7))
    edge = ss.march(origin, direction, PROJECTION, post, nothing_own(), coarse)
    assert edge.reason[0] == ss.BEHIND


def test_steps_and_distance_end_a_march():
    origin, direction = ray_at((4, 32), 5.0, (1.0, 0.0, -0.05))
    few = ss.march(origin, direction, PROJECTION, wall(30.0), nothing_own(), ScreenSpace(steps=5))
    assert few.reason[0] == ss.STEPS and few.steps[0] == 5
    short = ScreenSpace(max_distance=0.5)
    near = ss.march(origin, direction, PROJECTION, wall(30.0), nothing_own(), short)
    assert near.reason[0] == ss.DISTANCE


def test_the_reflectors_own_pixels_are_never_a_hit():
    origin, direction = ray_at((20, 32), 5.0, (0.6, 0.0, -0.8))
    own = nothing_own()
    own[:, 20:] = True  # the wall the ray meets is the reflector itself
    result = ss.march(origin, direction, PROJECTION, wall(8.0), own)
    assert result.reason[0] in (ss.OWN, ss.SCREEN)
    assert result.weight[0] == 0.0


def test_nothing_drawn_is_no_surface():
    cleared = np.ones((SIZE, SIZE))
    origin, direction = ray_at((20, 32), 5.0, (0.6, 0.0, -0.8))
    result = ss.march(origin, direction, PROJECTION, cleared, nothing_own())
    assert result.reason[0] == ss.SCREEN


def test_hits_fade_into_the_probe_towards_the_screens_edge_without_a_jump():
    settings_ = ScreenSpace(edge_fade=0.1)
    columns = np.arange(SIZE) + 0.5
    pixel = np.stack([columns, np.full(SIZE, 32.5)], axis=1)
    kept = ss.fade(pixel, np.ones(SIZE), np.zeros(SIZE), settings_, (0, 0, SIZE, SIZE), (SIZE,) * 2)
    assert kept[0] < 0.05 and kept[32] == 1.0
    assert np.abs(np.diff(kept)).max() < 0.25  # a ramp, not a step
    # and at the end of the step budget
    steps = np.arange(1, 101)
    late = ss.fade(
        np.full((100, 2), 32.5),
        steps,
        np.zeros(100),
        ScreenSpace(steps=100),
        (0, 0, SIZE, SIZE),
        (SIZE,) * 2,
    )
    assert late[0] == 1.0 and late[-1] < 0.05 and np.all(np.diff(late) <= 0)


def test_the_scissored_part_of_a_view_is_its_screen():
    origin, direction = ray_at((20, 32), 5.0, (1.0, 0.0, -0.05))
    result = ss.march(
        origin, direction, PROJECTION, wall(30.0), nothing_own(), screen=(0, 0, 30, SIZE)
    )
    assert result.reason[0] == ss.SCREEN and result.steps[0] < 12


def projections():
    perspective = st.builds(
        lambda fovy, near, far: math3d.perspective(fovy, 1.0, near, near * far),
        st.floats(5.0, 170.0),
        st.floats(0.01, 10.0),
        st.floats(2.0, 1e5),
    )
    orthographic = st.builds(
        lambda half, near, far: math3d.ortho(-half, half, -half, half, near, near + far),
        st.floats(0.1, 100.0),
        st.floats(0.0, 5.0),
        st.floats(0.5, 1e3),
    )
    return st.one_of(perspective, orthographic)


unit = st.floats(-1.0, 1.0, allow_subnormal=True)


@settings(max_examples=60, deadline=None)
@given(
    projection=projections(),
    direction=st.tuples(unit, unit, unit).filter(lambda v: np.linalg.norm(v) > 1e-6),
    depth_seed=st.integers(0, 2**16),
    px=st.integers(0, SIZE - 1),
    py=st.integers(0, SIZE - 1),
    along=st.floats(0.0, 1.0),
    stride=st.sampled_from([1.0, 2.5, 7.0]),
)
def test_any_ray_gives_a_finite_answer_in_range(
    projection, direction, depth_seed, px, py, along, stride
):
    rng = np.random.default_rng(depth_seed)
    depth = np.where(rng.random((SIZE, SIZE)) < 0.2, 1.0, rng.random((SIZE, SIZE)))
    own = rng.random((SIZE, SIZE)) < 0.1
    inverse = np.linalg.inv(projection)
    ndc = np.array([(px + 0.5) / SIZE * 2 - 1, (py + 0.5) / SIZE * 2 - 1, 2 * along - 1, 1.0])
    point = inverse @ ndc
    origin = (point[:3] / point[3])[None]
    d = np.asarray(direction, dtype=float)
    d = (d / np.linalg.norm(d))[None]
    with np.errstate(divide="raise", over="raise", invalid="raise"):  # and no NaN
        result = ss.march(origin, d, projection, depth, own, ScreenSpace(stride=stride, steps=64))
    assert 1 <= result.reason[0] < len(ss.REASONS)
    assert np.isfinite(result.pixel).all() and np.isfinite(result.weight).all()
    assert 0.0 <= result.weight[0] <= 1.0
    if result.reason[0] == ss.HIT:
        assert (0 <= result.pixel[0]).all() and (result.pixel[0] <= SIZE).all()
        assert not own[int(result.pixel[0, 1]), int(result.pixel[0, 0])]
    else:
        assert result.weight[0] == 0.0


def test_reflected_rays_are_unit_and_turn_to_the_side_they_come_from():
    positions = np.array([[0.0, 0.0, -5.0], [1.0, 0.0, -5.0], [0.0, 0.0, 0.0]])
    normals = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # one from behind
    rays = ss.reflect_eye(positions, normals)
    assert np.allclose(np.linalg.norm(rays, axis=1), 1.0)
    assert rays[0, 2] > 0.99 and rays[1, 2] > 0.0  # both turn back towards the eye
    flat = ss.reflect_eye(positions[:1], normals[:1], orthographic=True)
    assert np.allclose(flat, [[0.0, 0.0, 1.0]])


def test_the_miss_mask_counts_and_shares():
    reason = np.array([[0, 1, 1], [2, 5, 1]], dtype=np.uint8)
    weight = np.array([[0, 1, 0.5], [0, 0, 1]], dtype=np.float32)
    mask = ss.MissMask(reason, weight, np.zeros((2, 3, 2), dtype=np.float32))
    assert mask.reflector.sum() == 5
    assert mask.miss_share == 2 / 5 and abs(mask.probe_share - 2.5 / 5) < 1e-9
    assert mask.counts()["hit"] == 3 and mask.counts()["passed behind something"] == 1
    picture = mask.image()
    assert picture.shape == (2, 3, 3) and (picture[0, 0] == 0).all()
    assert picture[0, 1, 0] > picture[0, 2, 0]  # a faded hit is darker
