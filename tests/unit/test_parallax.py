"""numpy references of the parallax-corrected cube-map lookups: hand-derived values, the
fall-backs (outside the proxy, empty proxy, at the centre, behind the captured surface,
zero direction), rays parallel to box faces, and invariants under hypothesis: finite
results for any finite input, hit points on the proxy and on the ray, and a distance
search in a box room converging on the box proxy."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from mirrorlab import envmap, math3d, parallax

BOX_MIN = np.array([-4.0, -2.0, -4.0])
BOX_MAX = np.array([4.0, 4.0, 4.0])
CENTER = np.array([0.5, 1.0, -0.8])

any_float = st.floats(-1e30, 1e30, allow_nan=False, allow_infinity=False)
moderate = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False)
extreme_batches = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 12), st.just(3)), elements=any_float
)
moderate_batches = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 12), st.just(3)), elements=moderate
)
# a direction with components exactly 0, subnormal, tiny or ordinary
components = st.sampled_from([0.0, -0.0, 5e-324, -1e-310, 1e-21, 1e-20, 1e-7, 0.3, -1.0, 2.0])
special_directions = st.tuples(components, components, components).map(np.array)
few = settings(max_examples=60, deadline=None)


def unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def assert_unit_or_zero(look: np.ndarray) -> None:
    assert np.all(np.isfinite(look)), look
    length = np.linalg.norm(look.astype(np.float64), axis=-1)
    assert np.all((np.abs(length - 1) < 1e-5) | (length == 0)), length


# ---------------------------------------------------------------------------- box


def test_box_lookup_known_values():
    # From (1, 0, 0) straight up in the box [-2, 2]^3: out through the ceiling at (1, 2, 0),
    # seen from the centre (0, 0, 0) along (1, 2, 0).
    look = parallax.box_lookup([1.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 0.0], [-2] * 3, [2] * 3)
    assert np.allclose(look, unit([1.0, 2.0, 0.0]), atol=1e-15)
    # Towards the corner region: the nearest face decides (x reaches 2 first).
    look = parallax.box_lookup([1.0, 0.0, 0.0], [1.0, 0.5, 0.0], [0.0, 0.0, 0.0], [-2] * 3, [2] * 3)
    assert np.allclose(look, unit([2.0, 0.5, 0.0]), atol=1e-15)
    # From the capture centre itself the correction changes nothing.
    r = unit([0.3, -0.4, 0.5])
    assert np.allclose(parallax.box_lookup(CENTER, r, CENTER, BOX_MIN, BOX_MAX), r, atol=1e-15)


def test_box_lookup_falls_back_to_the_plain_direction():
    r = unit([0.2, 0.9, -0.1])
    outside = parallax.box_lookup([5.0, 0.0, 0.0], r, CENTER, BOX_MIN, BOX_MAX)
    assert np.allclose(outside, r, rtol=0, atol=1e-15)
    # a box whose min is not below its max on an axis has no inside, even on its faces
    for low, high in (([-1, 0, -1], [1, 0, 1]), ([1, -1, -1], [-1, 1, 1])):
        flat = parallax.box_lookup([0.0, 0.0, 0.0], r, [0.1, 0.0, 0.0], low, high)
        assert np.allclose(flat, r, rtol=0, atol=1e-15)
    assert np.array_equal(
        parallax.box_lookup(CENTER, [0.0, 0.0, 0.0], CENTER, BOX_MIN, BOX_MAX), [0.0, 0.0, 0.0]
    )


@pytest.mark.parametrize(
    "r",
    [(1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0), (1.0, 1e-30, -0.0), (1.0, 5e-324, 0.0)],
)
def test_box_lookup_parallel_to_faces_exits_through_the_face_ahead(r):
    origin = np.array([1.0, 2.0, -3.0])
    look = parallax.box_lookup(origin, r, CENTER, BOX_MIN, BOX_MAX)
    r = np.asarray(r)
    axis = int(np.argmax(np.abs(r)))
    hit = origin.copy()
    hit[axis] = BOX_MAX[axis] if r[axis] > 0 else BOX_MIN[axis]
    assert np.allclose(look, unit(hit - CENTER), atol=1e-12)
    # an origin on a face, moving along it, stays on it: exits at the far edge
    on_face = np.array([4.0, 0.0, 0.0])
    look = parallax.box_lookup(on_face, [0.0, 1.0, 0.0], CENTER, BOX_MIN, BOX_MAX)
    assert np.allclose(look, unit(np.array([4.0, 4.0, 0.0]) - CENTER), atol=1e-12)


@few
@given(extreme_batches, extreme_batches, moderate_batches)
def test_box_lookup_is_finite_for_any_finite_input(origin, direction, center):
    n = min(len(origin), len(direction), len(center))
    look = parallax.box_lookup(origin[:n], direction[:n], center[:n], BOX_MIN, BOX_MAX)
    assert_unit_or_zero(look)


@few
@given(moderate_batches, moderate_batches, moderate_batches, special_directions)
def test_box_hit_lies_on_the_box_and_on_the_ray(origins, centers, directions, special):
    n = min(len(origins), len(centers), len(directions))
    origin = np.clip(origins[:n] * 0.4, BOX_MIN, BOX_MAX)  # inside, faces included
    center = np.clip(centers[:n] * 0.4, BOX_MIN + 0.5, BOX_MAX - 0.5)
    direction = np.vstack([directions[: n - 1], special])  # one with zeros, subnormals
    look = parallax.box_lookup(origin, direction, center, BOX_MIN, BOX_MAX)
    assert_unit_or_zero(look)
    moving = np.max(np.abs(direction), axis=-1) > 0
    # The centre's ray along look leaves the box where the origin's ray does.
    seen = center + parallax.box_exit(center, look, BOX_MIN, BOX_MAX)[:, None] * look
    along = seen - origin
    r = envmap._unit(direction)[0]
    tangential = along - np.sum(along * r, axis=-1, keepdims=True) * r
    assert np.all(np.linalg.norm(tangential, axis=-1)[moving] < 1e-8)
    assert np.all(np.sum(along * r, axis=-1)[moving] > -1e-9)
    on_face = np.isclose(seen, BOX_MIN, rtol=0, atol=1e-9) | np.isclose(
        seen, BOX_MAX, rtol=0, atol=1e-9
    )
    assert np.all(on_face.any(axis=-1)[moving])


# ---------------------------------------------------------------------------- sphere


def test_sphere_lookup_known_values_and_fall_backs():
    # From (1, 0, 0) straight up inside a sphere of radius 2: out at (1, sqrt 3, 0).
    look = parallax.sphere_lookup([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], 2.0)
    assert np.allclose(look, [0.5, np.sqrt(3) / 2, 0.0], atol=1e-15)
    # Straight out along the radius: the lookup is the plain one.
    assert np.allclose(
        parallax.sphere_lookup([1.0, 0, 0], [1.0, 0, 0], [0.0, 0, 0], 2.0), [1.0, 0.0, 0.0]
    )
    # Back through the centre: out on the far side, the same direction.
    assert np.allclose(
        parallax.sphere_lookup([1.0, 0, 0], [-1.0, 0, 0], [0.0, 0, 0], 2.0), [-1.0, 0.0, 0.0]
    )
    r = unit([0.3, 0.4, -0.5])
    assert np.array_equal(parallax.sphere_lookup([3.0, 0, 0], r, [0.0, 0, 0], 2.0), r)
    for radius in (0.0, -1.0):
        assert np.array_equal(parallax.sphere_lookup([0.1, 0, 0], r, [0.0, 0, 0], radius), r)
    # On the sphere moving outwards: it leaves at once.
    assert np.allclose(
        parallax.sphere_lookup([0, 2.0, 0], unit([1, 1, 0]), [0.0, 0, 0], 2.0), [0.0, 1.0, 0.0]
    )


@few
@given(extreme_batches, extreme_batches, st.floats(-1e30, 1e30, allow_nan=False))
def test_sphere_lookup_is_finite_for_any_finite_input(origin, direction, radius):
    n = min(len(origin), len(direction))
    look = parallax.sphere_lookup(origin[:n], direction[:n], CENTER, radius)
    assert_unit_or_zero(look)


@few
@given(moderate_batches, moderate_batches, st.floats(0.5, 50.0))
def test_sphere_hit_lies_on_the_sphere_and_on_the_ray(origins, directions, radius):
    n = min(len(origins), len(directions))
    # Strictly inside: on the sphere itself rounding decides between inside and outside
    # (where the plain lookup is used), e.g. (10, 10, 10) / 10 * 2 / sqrt(3) at radius 2.
    offsets = origins[:n] / 10.0 * radius / np.sqrt(3) * 0.999
    origin = CENTER + offsets
    direction = directions[:n]
    look = parallax.sphere_lookup(origin, direction, CENTER, radius)
    assert_unit_or_zero(look)
    moving = np.max(np.abs(direction), axis=-1) > 0
    seen = CENTER + radius * look
    r = envmap._unit(direction)[0]
    along = seen - origin
    tangential = along - np.sum(along * r, axis=-1, keepdims=True) * r
    assert np.all(np.linalg.norm(tangential, axis=-1)[moving] < 1e-9 * radius)
    assert np.all(np.sum(along * r, axis=-1)[moving] > -1e-9 * radius)


# ---------------------------------------------------------------------------- distance


def room_rays(count: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Points on a unit sphere around CENTER and reflected-like directions away from it."""
    rng = np.random.default_rng(seed)
    normal = unit(rng.normal(size=(count, 3)))
    direction = unit(rng.normal(size=(count, 3)))
    direction = np.where(np.sum(direction * normal, -1, keepdims=True) < 0, -direction, direction)
    return CENTER + normal, direction


@pytest.mark.parametrize(
    ("steps", "secant", "p99_degrees"),
    [(2, 0, 5.0), (8, 0, 0.6), (8, 2, 0.01), (16, 3, 1e-4), (32, 6, 5e-6)],
)
def test_distance_search_in_a_box_room_converges_on_the_box_proxy(steps, secant, p99_degrees):
    # The capture of an empty box room holds the box's own distances, so searching them
    # must find the box proxy's answer; the error shrinks with the steps. Measured p99:
    # 3.4, 0.41, 0.0052, 3.8e-5, 1.5e-6 degrees.
    origin, direction = room_rays(4000, 7)
    room = parallax.box_distance(CENTER, BOX_MIN, BOX_MAX)
    look, background = parallax.distance_lookup(
        origin, direction, CENTER, room, steps, secant, thickness=0.1
    )
    box = parallax.box_lookup(origin, direction, CENTER, BOX_MIN, BOX_MAX)
    degrees = np.degrees(np.arccos(np.clip(np.sum(look * box, axis=-1), -1, 1)))
    assert not background.any()
    assert np.percentile(degrees, 99) < p99_degrees, np.percentile(degrees, [50, 99, 100])
    plain = np.degrees(np.arccos(np.clip(np.sum(direction * box, axis=-1), -1, 1)))
    assert np.median(plain) > 5.0  # the correction matters here (measured median 12)


def test_distance_search_falls_back_and_leaves_for_the_background():
    origin, direction = room_rays(50, 3)
    room = parallax.box_distance(CENTER, BOX_MIN, BOX_MAX)
    # at the centre: the plain lookup, in the capture
    look, background = parallax.distance_lookup(CENTER, direction, CENTER, room)
    assert np.allclose(look, direction) and not background.any()
    # behind what the capture saw (outside the room): plain, in the capture
    outside = origin + 20.0
    look, background = parallax.distance_lookup(outside, direction, CENTER, room)
    assert np.allclose(look, direction) and not background.any()

    # an empty world: every ray leaves for the background, along its own direction
    def nothing(directions):
        return np.zeros(len(directions))

    look, background = parallax.distance_lookup(origin, direction, CENTER, nothing)
    assert np.allclose(look, direction) and background.all()
    with pytest.raises(ValueError, match="steps"):
        parallax.distance_lookup(origin, direction, CENTER, room, steps=0)
    with pytest.raises(ValueError, match="thickness"):
        parallax.distance_lookup(origin, direction, CENTER, room, thickness=0.0)


def test_distance_search_passes_behind_an_object_it_does_not_meet():
    # A wall at x = 3 in front of the centre that ends at y = 1 (a ledge), seen from the
    # centre at the origin; the rest of the world is empty. A ray from (0, 1.5, 0) going
    # along +x passes over the ledge: from the centre, its far points hide behind the
    # wall (the height field calls them inside it), but it never meets the wall.
    def ledge(directions):
        d = np.asarray(directions, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = 3.0 / d[:, 0]
            y = t * d[:, 1]
        return np.where((d[:, 0] > 0) & (y < 1.0), d[:, 0] / 3.0, 0.0)

    over = np.array([0.0, 1.5, 0.0])
    look, background = parallax.distance_lookup(
        over, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], ledge, steps=16, secant=4
    )
    assert background and np.allclose(look, [1.0, 0.0, 0.0])
    # with a thickness that takes every crossing for a hit, or with no secant steps to
    # judge by, the ledge is "hit"
    for secant, thickness in ((4, 1.0), (0, 0.1)):
        look, background = parallax.distance_lookup(
            over, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], ledge, 16, secant, thickness
        )
        assert not background
    under = np.array([0.0, 0.5, 0.0])  # this one meets the wall at (3, 0.5, 0)
    look, background = parallax.distance_lookup(
        under, [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], ledge, steps=16, secant=4
    )
    assert not background and np.allclose(look, unit([3.0, 0.5, 0.0]), atol=1e-6)


def post_and_wall(directions):
    """Seen from the origin: a post at x = 2 (|z| < 0.2) in front of a wall at x = 8."""
    d = np.asarray(directions, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = 2.0 * d[:, 2] / d[:, 0]
    ahead = d[:, 0] > 0
    return np.where(ahead & (np.abs(z) < 0.2), d[:, 0] / 2.0, np.where(ahead, d[:, 0] / 8.0, 0.0))


@pytest.mark.parametrize("steps", [4, 6, 8, 10, 12])
def test_distance_search_finds_the_wall_behind_a_post_it_passed_behind(steps, monkeypatch):
    # The ray from (0, 0, -1) along (1, 0, 0.3) misses the post, passes behind it (as the
    # centre sees it) from x = 2.5 to 5, comes out and meets the wall at (8, 0, 1.4), all
    # within one linear step: only the smaller steps see it come out.
    origin, direction = np.array([0.0, 0.0, -1.0]), unit([1.0, 0.0, 0.3])
    wall = unit([8.0, 0.0, 1.4])
    look, background = parallax.distance_lookup(
        origin, direction, np.zeros(3), post_and_wall, steps, 2, 0.1, enclosed=True
    )
    assert not background
    assert np.degrees(np.arccos(np.clip(look @ wall, -1, 1))) < 1e-3
    missed = 0
    monkeypatch.setattr(parallax, "REFINE_STEPS", 1)
    for count in (4, 6, 10, 12):
        look, _ = parallax.distance_lookup(
            origin, direction, np.zeros(3), post_and_wall, count, 2, 0.1, enclosed=True
        )
        missed += np.degrees(np.arccos(np.clip(look @ wall, -1, 1))) > 1.0
    assert missed == 4  # without them every one of these falls back


def test_with_no_surface_found_a_closed_room_falls_back_to_the_plain_lookup():
    # Over the ledge, along +x: the wall the ray meets at x = 6 is hidden from the centre
    # by the ledge, so no crossing is accepted. Closed in, the plain lookup (in the
    # capture); open, the background.
    def ledge_and_wall(directions):
        d = np.asarray(directions, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            y = 3.0 * d[:, 1] / d[:, 0]
        ahead = d[:, 0] > 0
        return np.where(ahead & (y < 1.0), d[:, 0] / 3.0, np.where(ahead, d[:, 0] / 6.0, 0.0))

    over = np.array([0.0, 1.5, 0.0])
    for enclosed in (True, False):
        look, background = parallax.distance_lookup(
            over, [1.0, 0.0, 0.0], np.zeros(3), ledge_and_wall, 8, 2, enclosed=enclosed
        )
        assert np.allclose(look, [1.0, 0.0, 0.0]) and background == (not enclosed)


@few
@given(
    extreme_batches,
    extreme_batches,
    st.integers(1, 9),
    st.integers(0, 4),
    st.floats(1e-3, 1.0),
    st.integers(0, 2**32 - 1),
)
def test_distance_search_is_finite_for_any_finite_input_and_field(
    origin, direction, steps, secant, thickness, seed
):
    # A rough field: each direction's inverse distance is noise (zeros included).
    rng = np.random.default_rng(seed)
    table = rng.random((6, 4, 4)) * (rng.random((6, 4, 4)) > 0.3) * 10.0

    def noisy(directions):
        return parallax.nearest_cube_texel(table, directions)

    n = min(len(origin), len(direction))
    look, background = parallax.distance_lookup(
        origin[:n], direction[:n], CENTER * 0.0, noisy, steps, secant, thickness
    )
    assert_unit_or_zero(look)
    assert background.dtype == bool and background.shape == (n,)


def test_float32_stays_float32():
    r32 = np.array([[0.3, 0.4, -0.5]], np.float32)
    o32 = np.array([[1.0, 0.0, 0.0]], np.float32)
    assert (
        parallax.box_lookup(
            o32,
            r32,
            np.zeros(3, np.float32),
            BOX_MIN.astype(np.float32),
            BOX_MAX.astype(np.float32),
        ).dtype
        == np.float32
    )
    assert (
        parallax.sphere_lookup(o32, r32, np.zeros(3, np.float32), np.float32(3)).dtype == np.float32
    )


# ---------------------------------------------------------------------------- depths


def test_inverse_distance_from_depth_inverts_the_capture_projection():
    near, far = 0.05, 200.0
    projection = math3d.perspective(90.0, 1.0, near, far)
    # A point 5 units from the centre along a direction 30 degrees off the -Z face's axis.
    direction = unit([np.tan(np.radians(30.0)), 0.1, -1.0])
    eye_point = 5.0 * direction  # the -Z face looks down -z: eye space = world here
    clip = projection @ np.append(eye_point, 1.0)
    depth = (clip[2] / clip[3] + 1) / 2
    assert parallax.inverse_distance_from_depth(depth, direction, near, far) == pytest.approx(
        1 / 5.0, rel=1e-9
    )
    assert parallax.inverse_distance_from_depth(1.0, direction, near, far) == 0.0


def test_nearest_cube_texel_reads_the_texel_a_direction_falls_in():
    size = 4
    table = np.arange(6 * size * size, dtype=np.float64).reshape(6, size, size)
    faces, rows, columns = np.meshgrid(
        np.arange(6), np.arange(size), np.arange(size), indexing="ij"
    )
    # row 0 at the top: t = 1 - (row + 0.5) / size
    directions = envmap.cube_face_direction(faces, (columns + 0.5) / size, 1 - (rows + 0.5) / size)
    assert np.array_equal(parallax.nearest_cube_texel(table, directions), table)
