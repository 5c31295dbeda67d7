"""numpy references of the octahedral and dual-paraboloid maps: hand-derived values, the
hard cases (the fold lines, the square's edges and corners, the poles, exact axes, signed
zeros, subnormal and huge components, the paraboloid's rim), round trips and the padded
layouts, with hypothesis where a promise is general."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from mirrorlab import envmap

DTYPES = (np.float32, np.float64)
any_float = st.floats(allow_nan=False, allow_infinity=False)
vector_batches = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 16), st.just(3)), elements=any_float
)
moderate_batches = hnp.arrays(
    np.float64,
    st.tuples(st.integers(1, 16), st.just(3)),
    elements=st.floats(-1e3, 1e3, allow_nan=False),
)
coordinates = st.floats(-50, 50, allow_nan=False)
small_settings = settings(max_examples=60, deadline=None)
E = envmap.PARABOLOID_EXTENT


def unit_rows(v: np.ndarray) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    length = np.linalg.norm(v, axis=-1)
    keep = (length > 1e-6) & np.isfinite(length)
    return v[keep] / length[keep, None]


def cast_finite(r: np.ndarray, dtype) -> np.ndarray:
    """The rows of ``r`` that stay finite in ``dtype`` (huge float64 overflow float32)."""
    with np.errstate(over="ignore"):
        cast = r.astype(dtype)
    return cast[np.all(np.isfinite(cast), axis=-1)]


def finite_in_unit_square(*arrays) -> None:
    for a in arrays:
        a = np.asarray(a)
        assert np.all(np.isfinite(a)) and np.all((a >= 0) & (a <= 1)), a


def direction_env(directions: np.ndarray) -> np.ndarray:
    return (directions + 1) / 2


# ---------------------------------------------------------------------------- octahedral


@pytest.mark.parametrize(
    ("r", "st_"),
    [
        ((0, 0, 1), (0.5, 0.5)),
        ((1, 0, 0), (1.0, 0.5)),
        ((-1, 0, 0), (0.0, 0.5)),
        ((0, 1, 0), (0.5, 1.0)),
        ((0, -1, 0), (0.5, 0.0)),
        ((0, 0, -1), (1.0, 1.0)),  # -z: every corner; zeros count as positive
        ((1, 1, 0), (0.75, 0.75)),  # on the fold line |u| + |v| = 1
        ((1, 1, 1), (2 / 3, 2 / 3)),
        ((1, 1, -1), (5 / 6, 5 / 6)),  # folded: (1 - 1/3, 1 - 1/3) -> (2/3 + 1) / 2
        ((-2, 1, -1), (1 / 8, 3 / 4)),  # p = (-1/2, 1/4, -1/4): u = -3/4, v = 1/2
    ],
)
@pytest.mark.parametrize("dtype", DTYPES)
def test_octahedral_known_values(r, st_, dtype):
    s, t = envmap.octahedral_map(np.asarray(r, dtype=dtype))
    assert s.dtype == dtype and (float(s), float(t)) == pytest.approx(st_, abs=1e-6)


def test_octahedral_signed_zeros_and_zero():
    # -0.0 counts as positive, so the lower hemisphere's edge points and -z have one image
    for r in ((-0.0, -0.0, -1.0), (0.0, -0.0, -1.0), (-0.0, 0.0, -1.0)):
        assert envmap.octahedral_map(np.array(r)) == (1.0, 1.0)
    assert envmap.octahedral_map(np.array([-0.0, 0.5, -0.5])) == envmap.octahedral_map(
        np.array([0.0, 0.5, -0.5])
    )
    assert envmap.octahedral_map(np.zeros(3)) == (0.5, 0.5)
    assert envmap.octahedral_map(np.array([0.0, 0.0, -0.0])) == (0.5, 0.5)


@small_settings
@given(vector_batches)
def test_octahedral_finite_and_in_range_for_any_finite_input(r):
    for dtype in DTYPES:
        finite_in_unit_square(*envmap.octahedral_map(cast_finite(r, dtype)))


@small_settings
@given(moderate_batches, st.sampled_from([1e-300, 1e-30, 1e-5, 7.0, 1e30, 1e300]))
def test_octahedral_round_trips_at_any_length(v, k):
    r = unit_rows(v)
    back = envmap.octahedral_map_inverse(*envmap.octahedral_map(r * k))
    assert np.all(np.abs(back - r) <= 8 * np.finfo(np.float64).eps), np.abs(back - r).max()
    back32 = envmap.octahedral_map_inverse(*envmap.octahedral_map(r.astype(np.float32)))
    assert back32.dtype == np.float32
    assert np.all(np.abs(back32 - r) <= 8 * np.finfo(np.float32).eps)


@small_settings
@given(st.floats(-np.pi, np.pi), st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e-9, -1e-9]))
def test_octahedral_fold_lines_are_continuous(phi, z):
    """On the equator both formulas give the diamond |u| + |v| = 1; just above and just
    below it the images are as close as the directions."""
    r = np.array([np.cos(phi), np.sin(phi), z])
    s, t = envmap.octahedral_map(r)
    u, v = 2 * s - 1, 2 * t - 1
    assert abs(abs(u) + abs(v) - 1) <= 4 * max(abs(z), 1e-15)
    above = envmap.octahedral_map(np.array([r[0], r[1], abs(z)]))
    below = envmap.octahedral_map(np.array([r[0], r[1], -abs(z)]))
    assert np.hypot(above[0] - below[0], above[1] - below[1]) <= 4 * abs(z) + 1e-15


@small_settings
@given(st.floats(0.01, 0.99), st.sampled_from([1e-12, 1e-6, 1e-3]), st.integers(0, 3))
def test_octahedral_edges_join_mirrored(height, offset, edge):
    """In the lower hemisphere a direction next to the plane x = 0 (or y = 0) lands next to
    an edge of the square; its mirror image across that plane lands next to the same
    edge at the mirrored place, and wrapping one across the edge gives the other."""
    z = -height
    a = np.sqrt(1 - z * z)
    along = np.array([0.0, a, z]) if edge < 2 else np.array([a, 0.0, z])
    if edge % 2:
        along[:2] = -along[:2]
    across = np.array([offset, 0, 0]) if edge < 2 else np.array([0, offset, 0])
    one = envmap.octahedral_map(along + across)
    other = envmap.octahedral_map(along - across)
    u1, v1 = 2 * one[0] - 1, 2 * one[1] - 1
    u2, v2 = 2 * other[0] - 1, 2 * other[1] - 1
    if edge < 2:  # near the top or bottom edge v = +-1: u mirrored
        assert abs(abs(v1) - 1) < 2 * offset + 1e-12 and u1 == pytest.approx(-u2, abs=1e-12)
    else:
        assert abs(abs(u1) - 1) < 2 * offset + 1e-12 and v1 == pytest.approx(-v2, abs=1e-12)
    direction = envmap.octahedral_map_inverse(*one)
    assert np.allclose(direction, unit_rows((along + across)[None])[0], atol=1e-9)


@small_settings
@given(coordinates, coordinates)
def test_octahedral_wrap_continues_across_edges_with_period_four(s, t):
    ws, wt = envmap.octahedral_wrap(s, t)
    finite_in_unit_square(ws, wt)
    direction = envmap.octahedral_map_inverse(s, t)
    assert np.allclose(direction, envmap.octahedral_map_inverse(ws, wt), atol=1e-12)
    assert np.allclose(direction, envmap.octahedral_map_inverse(s + 2, t), atol=1e-9)
    assert np.allclose(direction, envmap.octahedral_map_inverse(s, t - 2), atol=1e-9)
    assert np.linalg.norm(direction) == pytest.approx(1)


@small_settings
@given(st.floats(0, 1), st.floats(1e-9, 0.2))
def test_octahedral_inverse_is_continuous_across_every_edge(position, gap):
    """Just outside an edge is just inside its mirrored place: the directions meet."""
    for outside, inside in (
        ((1 + gap, position), (1 - gap, 1 - position)),
        ((-gap, position), (gap, 1 - position)),
        ((position, 1 + gap), (1 - position, 1 - gap)),
        ((position, -gap), (1 - position, gap)),
    ):
        a = envmap.octahedral_map_inverse(*outside)
        b = envmap.octahedral_map_inverse(*inside)
        assert np.allclose(a, b, atol=1e-12)


@small_settings
@given(hnp.arrays(np.float64, st.tuples(st.integers(1, 8), st.just(2)), elements=coordinates))
def test_octahedral_inverse_always_unit_and_finite(points):
    for dtype in DTYPES:
        r = envmap.octahedral_map_inverse(points[:, 0].astype(dtype), points[:, 1].astype(dtype))
        assert r.dtype == dtype and np.all(np.isfinite(r))
        assert np.allclose(np.linalg.norm(r, axis=-1), 1, atol=1e-6)


def test_octahedral_corners_and_edge_midpoints():
    for corner in ((0, 0), (0, 1), (1, 0), (1, 1)):
        assert np.allclose(envmap.octahedral_map_inverse(*corner), [0, 0, -1])
    assert np.allclose(envmap.octahedral_map_inverse(1, 0.5), [1, 0, 0])
    assert np.allclose(envmap.octahedral_map_inverse(0.5, 0), [0, -1, 0])
    assert np.allclose(envmap.octahedral_map_inverse(0.5, 0.5), [0, 0, 1])


def test_octahedral_level_sizes_and_grid():
    assert envmap.octahedral_level_sizes(256) == (256, 128, 64, 32, 16, 8, 4)
    assert envmap.octahedral_level_sizes(10) == (10, 5)
    assert envmap.octahedral_level_sizes(4) == (4,)
    with pytest.raises(ValueError, match="at least 4"):
        envmap.octahedral_level_sizes(3)
    s, t = envmap.octahedral_texel_grid(6)  # interior 4: centres at (i - 0.5) / 4
    assert np.allclose(s[0], [-0.125, 0.125, 0.375, 0.625, 0.875, 1.125])
    assert np.allclose(t[:, 0], [1.125, 0.875, 0.625, 0.375, 0.125, -0.125])  # row 0 on top


@pytest.mark.parametrize("size", [6, 13, 32])
def test_bake_octahedral_borders_hold_what_lies_across_the_edges(size):
    levels = envmap.bake_octahedral(direction_env, size)
    assert [level.shape[0] for level in levels] == list(envmap.octahedral_level_sizes(size))
    for level in levels:
        n = level.shape[0]
        s, t = envmap.octahedral_texel_grid(n)
        ws, wt = envmap.octahedral_wrap(s, t)
        # each border texel is the interior texel its centre wraps onto (row 0 on top)
        column = np.floor(ws * (n - 2)).astype(int) + 1
        row = n - 2 - np.floor(wt * (n - 2)).astype(int)
        assert np.array_equal(level, level[row, column])
    # level 0 holds each texel centre's direction
    s, t = envmap.octahedral_texel_grid(size)
    expected = np.round(direction_env(envmap.octahedral_map_inverse(s, t)) * 255)
    assert np.array_equal(levels[0], expected.astype(np.uint8))


def test_bake_octahedral_levels_average_their_finer_level():
    """A coarse level's texel is close to the mean of what the finer level shows over its
    area, wherever it is (the border's continuation included): a constant stays the
    constant, and the average of a smooth field is close to its centre value."""
    levels = envmap.bake_octahedral(lambda d: np.full_like(d, 0.4), 32)
    for level in levels:
        assert np.all(level == 102)
    levels = envmap.bake_octahedral(direction_env, 64)
    for level in levels[1:4]:
        s, t = envmap.octahedral_texel_grid(level.shape[0])
        centre = direction_env(envmap.octahedral_map_inverse(s, t)) * 255
        assert np.abs(level - centre).max() < 12 * 64 / level.shape[0]


# ---------------------------------------------------------------------------- paraboloid


@pytest.mark.parametrize(
    ("r", "side", "st_"),
    [
        ((0, 0, 1), 0, (0.5, 0.5)),
        ((0, 0, -1), 1, (0.5, 0.5)),
        ((1, 0, 0), 0, (0.5 - 0.5 / E, 0.5)),  # the rim; the front sees +x on its left
        ((-1, 0, 0), 0, (0.5 + 0.5 / E, 0.5)),
        ((0, 1, 0), 0, (0.5, 0.5 + 0.5 / E)),
        ((1, 0, -1e-30), 1, (0.5 + 0.5 / E, 0.5)),  # just behind the rim: the back
        ((0, 1, -1), 1, (0.5, 0.5 + 0.5 / (E * (1 + 2**-0.5)) * 2**-0.5)),
    ],
)
@pytest.mark.parametrize("dtype", DTYPES)
def test_paraboloid_known_values(r, side, st_, dtype):
    got_side, s, t = envmap.paraboloid_map(np.asarray(r, dtype=dtype))
    assert int(got_side) == side and s.dtype == dtype
    assert (float(s), float(t)) == pytest.approx(st_, abs=1e-6)


def test_paraboloid_rim_zeros_and_zero():
    for z in (0.0, -0.0):
        side, s, t = envmap.paraboloid_map(np.array([0.6, 0.8, z]))
        assert side == 0
        assert np.hypot(s - 0.5, t - 0.5) == pytest.approx(0.5 / E)
    assert [float(v) for v in envmap.paraboloid_map(np.zeros(3))] == [0, 0.5, 0.5]


@small_settings
@given(vector_batches)
def test_paraboloid_finite_and_in_range_for_any_finite_input(r):
    for dtype in DTYPES:
        side, s, t = envmap.paraboloid_map(cast_finite(r, dtype))
        assert set(np.unique(side)) <= {0, 1}
        finite_in_unit_square(s, t)
        # never outside its disc
        assert np.all(np.hypot(s - 0.5, t - 0.5) <= 0.5 / E + 1e-6)


@small_settings
@given(moderate_batches, st.sampled_from([1e-300, 1e-30, 3.0, 1e300]))
def test_paraboloid_round_trips_at_any_length(v, k):
    r = unit_rows(v)
    back = envmap.paraboloid_map_inverse(*envmap.paraboloid_map(r * k))
    assert np.all(np.abs(back - r) <= 8 * np.finfo(np.float64).eps)
    back32 = envmap.paraboloid_map_inverse(*envmap.paraboloid_map(r.astype(np.float32)))
    assert np.all(np.abs(back32 - r) <= 8 * np.finfo(np.float32).eps)


@small_settings
@given(st.floats(-np.pi, np.pi), st.one_of(st.just(0.0), st.floats(1e-6, 0.2)))
def test_paraboloid_margin_continues_past_the_rim_into_the_other_side(phi, past):
    """A point of the margin (paraboloid radius above 1) shows a direction of the other
    side, close to the rim, and the other side shows that direction at the point its
    own paraboloid puts it: the two sides agree across the rim."""
    radius = 1 + past
    for side in (0, 1):
        a, b = radius * np.cos(phi), radius * np.sin(phi)
        s, t = 0.5 + 0.5 * a / E, 0.5 + 0.5 * b / E
        direction = envmap.paraboloid_map_inverse(side, s, t)
        assert np.linalg.norm(direction) == pytest.approx(1)
        rz = direction[2] if side == 0 else -direction[2]
        assert rz <= 1e-12  # behind this side's camera plane: the other side's
        if past > 0:
            other, s2, t2 = envmap.paraboloid_map(direction)
            assert other == 1 - side
            assert np.allclose(envmap.paraboloid_map_inverse(other, s2, t2), direction)


def test_paraboloid_inverse_rejects_bad_sides():
    with pytest.raises(ValueError):
        envmap.paraboloid_map_inverse(2, 0.5, 0.5)
    with pytest.raises(ValueError):
        envmap.paraboloid_map_inverse(np.array(0.0), 0.5, 0.5)


def test_bake_paraboloid_layout():
    size = 16
    image = envmap.bake_paraboloid(direction_env, size)
    assert image.shape == (size, 2 * size, 3) and image.dtype == np.uint8
    # front centre +z (blue high), back centre -z
    assert image[size // 2, size // 2, 2] > 240 and image[size // 2, size + size // 2, 2] < 15
    # the front's left edge looks at +x, the back's right edge at +x; the top rows at +y
    assert image[size // 2, 0, 0] > 240 and image[size // 2, 2 * size - 1, 0] > 240
    assert image[0, size // 2, 1] > 240 and image[0, size + size // 2, 1] > 240
    s, t = (np.arange(size) + 0.5) / size, 1 - (np.arange(size) + 0.5) / size
    ss, tt = np.meshgrid(s, t)
    expected = np.round(direction_env(envmap.paraboloid_map_inverse(1, ss, tt)) * 255)
    assert np.array_equal(image[:, size:], expected.astype(np.uint8))


# ---------------------------------------------------------------------------- pictures


def test_octahedral_picture_environment_reads_back_its_directions():
    n = 64
    centres = (np.arange(n) + 0.5) / n
    s, t = np.meshgrid(centres, centres[::-1])
    picture = direction_env(envmap.octahedral_map_inverse(s, t))
    env = envmap.octahedral_picture_environment(picture)
    r = unit_rows(np.random.default_rng(1).normal(size=(2000, 3)))
    assert np.abs(env(r) - direction_env(r)).max() < 0.03
    with pytest.raises(ValueError, match="square"):
        envmap.octahedral_picture_environment(np.zeros((4, 8, 3)))


def test_paraboloid_picture_environment_reads_back_its_directions():
    n = 64
    centres = (np.arange(n) + 0.5) / n
    s, t = np.meshgrid(centres, centres[::-1])
    # the common layout: each disc touches its square's edges (no margin)
    halves = []
    for side in (0, 1):
        a, b = 2 * s - 1, 2 * t - 1
        direction = envmap.paraboloid_map_inverse(
            side, 0.5 + 0.5 * a / envmap.PARABOLOID_EXTENT, 0.5 + 0.5 * b / envmap.PARABOLOID_EXTENT
        )
        halves.append(direction_env(direction))
    env = envmap.paraboloid_picture_environment(np.concatenate(halves, axis=1))
    r = unit_rows(np.random.default_rng(2).normal(size=(2000, 3)))
    assert np.abs(env(r) - direction_env(r)).max() < 0.04
    with pytest.raises(ValueError, match="twice as wide"):
        envmap.paraboloid_picture_environment(np.zeros((8, 8, 3)))
