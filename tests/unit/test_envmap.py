"""numpy environment-map references: hand-derived values, the hard cases (singular
directions, ties, poles, zeros, subnormals) and invariants checked with hypothesis."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from mirrorlab import envmap, math3d

SQRT2 = np.sqrt(2.0)
DTYPES = (np.float32, np.float64)

# Any finite float: tiny, subnormal, zero of either sign, huge.
any_float = st.floats(allow_nan=False, allow_infinity=False)
moderate = st.floats(-1e3, 1e3, allow_nan=False)
vector_batches = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 16), st.just(3)), elements=any_float
)
moderate_batches = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 16), st.just(3)), elements=moderate
)
# Two batches of the same length, as one (n, 2, 3) array.
moderate_pairs = hnp.arrays(
    np.float64, st.tuples(st.integers(1, 16), st.just(2), st.just(3)), elements=moderate
)
small_settings = settings(max_examples=60, deadline=None)


def unit_rows(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` with a comfortable length, normalised (the rest dropped)."""
    v = np.asarray(v, dtype=np.float64)
    length = np.linalg.norm(v, axis=-1)
    keep = (length > 1e-6) & np.isfinite(length)
    return v[keep] / length[keep, None]


def textbook_sphere_map(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The red book's formula exactly as printed, for unit ``r`` away from (0, 0, -1)."""
    m = 2 * np.sqrt(r[..., 0] ** 2 + r[..., 1] ** 2 + (r[..., 2] + 1) ** 2)
    return r[..., 0] / m + 0.5, r[..., 1] / m + 0.5


def assert_st_in_range(*arrays):
    for a in arrays:
        a = np.asarray(a)
        assert np.all(np.isfinite(a)), f"non-finite texture coordinate in {a}"
        assert np.all((a >= 0) & (a <= 1)), f"texture coordinate outside [0, 1] in {a}"


# ---------------------------------------------------------------------------- reflect


def test_reflect_known_values():
    assert np.allclose(envmap.reflect([1, -1, 0], [0, 1, 0]), [1, 1, 0])
    # Head-on: straight back. The normal's length does not matter.
    assert np.allclose(envmap.reflect([0, 0, -1], [0, 0, 7]), [0, 0, 1])
    # u need not be unit: |r| = |u|.
    assert np.allclose(envmap.reflect([0, -3, -4], [0, 0, 1]), [0, -3, 4])


def test_reflect_zero_normal_returns_u_and_subnormal_normal_keeps_its_direction():
    u = np.array([0.3, -0.2, -0.9])
    assert np.array_equal(envmap.reflect(u, [0.0, 0.0, 0.0]), u)
    assert np.array_equal(envmap.reflect(u, [-0.0, 0.0, -0.0]), u)
    tiny64 = np.array([0.0, 5e-324, 0.0])  # the smallest float64 subnormal
    assert np.allclose(envmap.reflect(u, tiny64), envmap.reflect(u, [0, 1, 0]), atol=1e-15)
    tiny32 = np.array([1e-45, 0, 0], np.float32)  # float32 subnormal; its square underflows
    r32 = envmap.reflect(u.astype(np.float32), tiny32)
    assert r32.dtype == np.float32
    assert np.allclose(r32, [-0.3, -0.2, -0.9], atol=1e-6)


def test_reflect_grazing_incidence_is_continuous():
    # n.u -> 0: r -> u, with |r - u| = 2 |n.u| for unit n.
    u = np.array([0.0, 0.0, -1.0])
    for eps in (1e-3, 1e-9, 1e-15, 0.0):
        n = np.array([1.0, 0.0, eps])
        n_unit = n / np.linalg.norm(n)
        r = envmap.reflect(u, n)
        assert np.all(np.isfinite(r))
        assert np.linalg.norm(r - u) == pytest.approx(2 * abs(n_unit @ u), abs=1e-15)


def test_reflect_broadcasts_and_keeps_dtype():
    u = np.ones((4, 1, 3), np.float32)
    n = np.ones((1, 6, 3), np.float32)
    r = envmap.reflect(u, n)
    assert r.shape == (4, 6, 3) and r.dtype == np.float32
    assert envmap.reflect(np.ones((5, 3)), [0, 0, 1]).shape == (5, 3)
    assert envmap.reflect([1, 2, 3], [0, 0, 1]).dtype == np.float64  # ints promote
    assert envmap.reflect(u, n.astype(np.float64)).dtype == np.float64
    with pytest.raises(ValueError):
        envmap.reflect([1, 2], [0, 0, 1])


@small_settings
@given(moderate_pairs)
def test_reflect_is_an_involution_that_keeps_length(pairs):
    u, n = pairs[:, 0], pairs[:, 1]
    r = envmap.reflect(u, n)
    assert np.all(np.isfinite(r))
    scale = 1 + np.linalg.norm(u, axis=-1)
    assert np.allclose(
        np.linalg.norm(r, axis=-1), np.linalg.norm(u, axis=-1), atol=1e-12 * scale.max()
    )
    assert np.allclose(envmap.reflect(r, n), u, atol=1e-12 * scale.max())
    # The normal component flips, the tangential one stays.
    keep = np.linalg.norm(n, axis=-1) > 1e-6
    n_hat = n[keep] / np.linalg.norm(n[keep], axis=-1, keepdims=True)
    along_u = np.sum(u[keep] * n_hat, axis=-1)
    along_r = np.sum(r[keep] * n_hat, axis=-1)
    assert np.allclose(along_r, -along_u, atol=1e-12 * scale.max())


# ---------------------------------------------------------------------------- sphere map


def test_sphere_map_known_values():
    s, t = envmap.sphere_map(np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]]))
    edge = 1 / (2 * SQRT2)  # the equator maps to the circle of radius 1/(2 sqrt 2)
    assert np.allclose(s, [0.5, 0.5 + edge, 0.5, 0.5 - edge, 0.5])
    assert np.allclose(t, [0.5, 0.5, 0.5 + edge, 0.5, 0.5 - edge])


@small_settings
@given(moderate_batches)
def test_sphere_map_matches_the_textbook_formula_away_from_the_singular_point(v):
    r = unit_rows(v)
    r = r[1 + r[:, 2] > 1e-3]
    s, t = envmap.sphere_map(r)
    s0, t0 = textbook_sphere_map(r)
    assert np.allclose(s, s0, atol=1e-12) and np.allclose(t, t0, atol=1e-12)
    # Latitude circles go to circles about the centre: radius sqrt((1 - rz)/2)/2, written
    # as rho / (2 sqrt(2 (1 + rz))) to avoid cancellation near +z.
    radius = np.hypot(s - 0.5, t - 0.5)
    rho = np.hypot(r[:, 0], r[:, 1])
    assert np.allclose(radius, rho / (2 * np.sqrt(2 * (1 + r[:, 2]))), atol=1e-12)


@pytest.mark.parametrize("dtype", DTYPES)
def test_sphere_map_exactly_at_the_singular_direction_gives_the_fixed_rim_point(dtype):
    for values in ([0, 0, -1], [0.0, -0.0, -1], [-0.0, -0.0, -5], [0, 0, -1e-30]):
        r = np.array(values, dtype=dtype)
        s, t = envmap.sphere_map(r)
        assert (float(s), float(t)) == (1.0, 0.5)
        assert np.asarray(s).dtype == dtype


@pytest.mark.parametrize("offset", [1e-3, 1e-7, 1e-12, 1e-30, 1e-300])
@pytest.mark.parametrize("angle_deg", [0, 37, 90, 180, 251, 315])
def test_sphere_map_near_the_singular_direction_tends_to_the_rim_in_the_direction_of_rx_ry(
    offset, angle_deg
):
    a = np.radians(angle_deg)
    direction = np.array([np.cos(a), np.sin(a)])
    r = np.array([offset * direction[0], offset * direction[1], -1.0])
    results = {}
    for dtype in DTYPES:
        if dtype == np.float32 and offset < 1e-37:
            continue  # float32 would round (rx, ry) to a subnormal or to zero
        s, t = envmap.sphere_map(r.astype(dtype))
        assert_st_in_range(s, t)
        results[dtype] = np.array([s, t], dtype=np.float64)
    rim = 0.5 + 0.5 * direction
    # Distance from the rim point: about offset/4 (the rim is approached quadratically
    # in angle from the south pole, and linearly in (rx, ry) along it).
    for got in results.values():
        assert np.allclose(got, rim, atol=max(offset, 1e-6)), (got, rim)
    if len(results) == 2:
        assert np.allclose(results[np.float32], results[np.float64], atol=1e-6)


def test_sphere_map_subnormal_offsets_from_the_singular_direction_still_pick_their_rim_point():
    r = np.array([[5e-324, 0, -1], [0, -5e-324, -1], [-1e-310, 1e-310, -1]])
    s, t = envmap.sphere_map(r)
    assert np.allclose(s, [1, 0.5, 0.5 - 0.5 / SQRT2])
    assert np.allclose(t, [0.5, 0, 0.5 + 0.5 / SQRT2])
    s32, t32 = envmap.sphere_map(np.array([[1e-45, 0, -1], [0, -1e-45, -1]], np.float32))
    assert s32.tolist() == [1, 0.5] and t32.tolist() == [0.5, 0]


def test_sphere_map_approaches_the_rim_continuously():
    offsets = 10.0 ** -np.arange(1, 16)
    r = np.stack([offsets, np.zeros_like(offsets), -np.ones_like(offsets)], axis=-1)
    s, t = envmap.sphere_map(r)
    assert np.all(np.diff(s) >= 0) and np.all(s <= 1) and np.allclose(t, 0.5)
    assert s[-1] == pytest.approx(1.0, abs=1e-15)


def test_sphere_map_of_zero_is_the_centre():
    for dtype in DTYPES:
        for r in ([0, 0, 0], [-0.0, -0.0, -0.0]):
            s, t = envmap.sphere_map(np.array(r, dtype))
            assert (float(s), float(t)) == (0.5, 0.5)


@small_settings
@given(vector_batches)
def test_sphere_map_stays_finite_and_in_range_for_any_finite_input(r):
    for dtype in DTYPES:
        with np.errstate(over="ignore"):
            cast = r.astype(dtype)
        cast = cast[np.all(np.isfinite(cast), axis=-1)]
        s, t = envmap.sphere_map(cast)
        assert s.dtype == dtype and t.dtype == dtype and s.shape == cast.shape[:1]
        assert_st_in_range(s, t)


@small_settings
@given(moderate_batches, st.sampled_from([1e-300, 1e-30, 1e-8, 3.0, 1e30, 1e300]))
def test_sphere_map_ignores_the_length_of_r(v, k):
    r = unit_rows(v)
    r = r[1 + r[:, 2] > 1e-6]  # near (0, 0, -1) a scaled rx, ry may underflow to zero
    s1, t1 = envmap.sphere_map(r)
    s2, t2 = envmap.sphere_map(r * k)
    assert np.allclose(s1, s2, atol=1e-13) and np.allclose(t1, t2, atol=1e-13)


@small_settings
@given(moderate_batches)
def test_sphere_map_float32_agrees_with_float64(v):
    r = unit_rows(v).astype(np.float32)
    r = r[1 + r[:, 2].astype(np.float64) > 1e-4]  # the map is steep near (0, 0, -1)
    s32, t32 = envmap.sphere_map(r)
    s64, t64 = envmap.sphere_map(r.astype(np.float64))
    assert np.allclose(s32, s64, atol=2e-6) and np.allclose(t32, t64, atol=2e-6)


# ---------------------------------------------------------------------------- texgen


def test_texgen_known_values():
    # A vertex straight ahead facing the viewer reflects straight back: the centre.
    s, t = envmap.sphere_map_texgen([0, 0, -5], [0, 0, 1])
    assert (s, t) == pytest.approx((0.5, 0.5))
    # u = (0, 0, -1) and a 45-degree normal in xz: r = (-1, 0, 0).
    s, t = envmap.sphere_map_texgen([0, 0, -2], [-1, 0, 1])
    assert (s, t) == pytest.approx((0.5 - 1 / (2 * SQRT2), 0.5))


def test_texgen_vertex_at_the_eye_and_zero_normal_stay_finite():
    for dtype in DTYPES:
        s, t = envmap.sphere_map_texgen(np.zeros(3, dtype), np.array([0, 0, 1], dtype))
        assert (float(s), float(t)) == (0.5, 0.5)  # u = 0, so r = 0: the centre
        s, t = envmap.sphere_map_texgen(np.zeros(3, dtype), np.zeros(3, dtype))
        assert (float(s), float(t)) == (0.5, 0.5)
        v = np.array([0.3, -0.4, -2.0], dtype)
        s, t = envmap.sphere_map_texgen(v, np.zeros(3, dtype))  # no normal: r = u
        assert np.allclose([s, t], envmap.sphere_map(v), atol=1e-7)


def test_texgen_grazing_incidence_at_the_view_axis_is_the_singular_point():
    # u = (0, 0, -1) with the normal perpendicular: r = u = (0, 0, -1).
    s, t = envmap.sphere_map_texgen([0, 0, -3], [1, 0, 0])
    assert (float(s), float(t)) == (1.0, 0.5)
    for eps in (1e-4, 1e-9, 1e-14):
        s, t = envmap.sphere_map_texgen([0, 0, -3], [1, 0, eps])
        assert_st_in_range(s, t)


@small_settings
@given(moderate_pairs, st.floats(0.01, 100))
def test_texgen_is_sphere_map_of_the_reflected_eye_ray_with_normalised_normals(pairs, k):
    v, n = pairs[:, 0], pairs[:, 1]
    s, t = envmap.sphere_map_texgen(v, n)
    assert_st_in_range(s, t)
    # Compare with plain numpy where plain normalisation does not underflow.
    plain = (np.linalg.norm(v, axis=-1) > 1e-100) & (np.linalg.norm(n, axis=-1) > 1e-100)
    v, n, s, t = v[plain], n[plain], s[plain], t[plain]
    assert_st_in_range(s, t)
    lengths = np.linalg.norm(v, axis=-1, keepdims=True)
    u = np.where(lengths > 0, v / np.where(lengths > 0, lengths, 1), 0)
    r = envmap.reflect(u, n)
    away = (
        1
        + unit_rows(np.where(np.linalg.norm(r, axis=-1, keepdims=True) > 1e-6, r, [0, 0, 1]))[:, 2]
        > 1e-6
    )
    s0, t0 = envmap.sphere_map(r)
    assert np.allclose(s[away], s0[away], atol=1e-9) and np.allclose(t[away], t0[away], atol=1e-9)
    s2, t2 = envmap.sphere_map_texgen(v, n * k)  # GL_NORMALIZE semantics
    assert np.allclose(s2[away], s[away], atol=1e-9) and np.allclose(t2[away], t[away], atol=1e-9)


# ---------------------------------------------------------------------------- inverse


def test_sphere_map_inverse_known_values():
    edge = 1 / (2 * SQRT2)
    s = np.array([0.5, 0.5 + edge, 0.5, 1.0, 0.0, 0.5])
    t = np.array([0.5, 0.5, 0.5 - edge, 0.5, 0.5, 1.0])
    expected = [[0, 0, 1], [1, 0, 0], [0, -1, 0], [0, 0, -1], [0, 0, -1], [0, 0, -1]]
    assert np.allclose(envmap.sphere_map_inverse(s, t), expected, atol=1e-15)


def test_sphere_map_inverse_clamps_outside_the_disc_to_the_rim():
    s = np.array([1.0, 0.0, 2.0, -3.0, 0.99])
    t = np.array([1.0, 0.0, -3.0, 0.5, 0.99])
    r = envmap.sphere_map_inverse(s, t)
    assert np.all(np.isfinite(r))
    assert np.array_equal(r, np.tile([0.0, 0.0, -1.0], (5, 1)))


@small_settings
@given(
    hnp.arrays(np.float64, st.integers(1, 16), elements=st.floats(-3, 3)),
    hnp.arrays(np.float64, st.integers(1, 16), elements=st.floats(-3, 3)),
)
def test_sphere_map_inverse_is_always_unit(s, t):
    n = min(len(s), len(t))
    for dtype in DTYPES:
        r = envmap.sphere_map_inverse(s[:n].astype(dtype), t[:n].astype(dtype))
        assert r.dtype == dtype and r.shape == (n, 3)
        assert np.allclose(
            np.linalg.norm(r.astype(np.float64), axis=-1), 1, atol=4 * np.finfo(dtype).eps
        )


@settings(max_examples=40, deadline=None)
@given(moderate_batches, st.floats(-14, 0))
def test_sphere_map_round_trip_bound(v, log_gap):
    # Bound from the docstring: |back - r| <= 8 eps / sqrt(1 + rz) for 1 + rz >= 1e-6.
    # Half of each batch is pushed towards the singular direction to exercise the bound.
    r = unit_rows(v)
    pole = np.array([0.0, 0.0, -1.0])
    r = np.concatenate([r, unit_rows(pole + 10.0**log_gap * (r - pole))])
    for dtype in DTYPES:
        rd = r.astype(dtype)
        exact = rd.astype(np.float64)
        exact /= np.linalg.norm(exact, axis=-1, keepdims=True)
        gap = 1 + exact[:, 2]
        keep = gap >= 1e-6
        back = envmap.sphere_map_inverse(*envmap.sphere_map(rd[keep])).astype(np.float64)
        error = np.linalg.norm(back - exact[keep], axis=-1)
        bound = 8 * np.finfo(dtype).eps / np.sqrt(gap[keep])
        assert np.all(error <= bound), (error / bound).max()


def test_sphere_map_of_its_inverse_is_the_identity_inside_the_disc():
    rng = np.random.default_rng(7)
    s, t = rng.uniform(0, 1, (2, 5000))
    inside = np.hypot(s - 0.5, t - 0.5) < 0.499
    s2, t2 = envmap.sphere_map(envmap.sphere_map_inverse(s[inside], t[inside]))
    assert np.allclose(s2, s[inside], atol=1e-13) and np.allclose(t2, t[inside], atol=1e-13)


# ---------------------------------------------------------------------------- cube map


@pytest.mark.parametrize(
    ("r", "face", "s", "t"),
    [
        # One point per face through the spec's table: s = (sc/|ma| + 1)/2, t = (tc/|ma| + 1)/2.
        ((2.0, 0.4, -0.8), 0, (0.4 + 1) / 2, (-0.2 + 1) / 2),  # +X: sc = -rz, tc = -ry
        ((-2.0, 0.4, -0.8), 1, (-0.4 + 1) / 2, (-0.2 + 1) / 2),  # -X: sc = +rz, tc = -ry
        ((0.4, 2.0, -0.8), 2, (0.2 + 1) / 2, (-0.4 + 1) / 2),  # +Y: sc = +rx, tc = +rz
        ((0.4, -2.0, -0.8), 3, (0.2 + 1) / 2, (0.4 + 1) / 2),  # -Y: sc = +rx, tc = -rz
        ((0.4, -0.8, 2.0), 4, (0.2 + 1) / 2, (0.4 + 1) / 2),  # +Z: sc = +rx, tc = -ry
        ((0.4, -0.8, -2.0), 5, (-0.2 + 1) / 2, (0.4 + 1) / 2),  # -Z: sc = -rx, tc = -ry
        # Shen's slide example lands on -Z; its printed (s, t) uses (rx, ry) directly, GL's
        # table negates both for -Z.
        ((-3.2, 5.1, -8.4), 5, (3.2 / 8.4 + 1) / 2, (-5.1 / 8.4 + 1) / 2),
    ],
)
def test_cube_map_follows_the_spec_table(r, face, s, t):
    for dtype in DTYPES:
        f, s_got, t_got = envmap.cube_map(np.array(r, dtype))
        assert int(f) == face
        assert float(s_got) == pytest.approx(s, abs=1e-6) and float(t_got) == pytest.approx(
            t, abs=1e-6
        )


def test_cube_map_axes_hit_face_centres():
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    face, s, t = envmap.cube_map(axes)
    assert face.tolist() == [0, 1, 2, 3, 4, 5]
    assert np.issubdtype(face.dtype, np.integer)
    assert np.all(s == 0.5) and np.all(t == 0.5)
    # Signed zeros in the minor components change nothing.
    face, s, t = envmap.cube_map(np.array([[5, -0.0, 0.0], [-0.0, -0.0, -2]]))
    assert face.tolist() == [0, 5] and np.all(s == 0.5) and np.all(t == 0.5)


@pytest.mark.parametrize(
    ("r", "face", "s", "t"),
    [
        # Ties: Z before Y before X (Mesa llvmpipe's order); edges put s or t at 0 or 1.
        ((1, 1, 0), 2, 1.0, 0.5),  # +X/+Y edge -> +Y, sc = rx = 1
        ((1, -1, 0), 3, 1.0, 0.5),  # +X/-Y edge -> -Y
        ((-1, 1, 0.3), 2, 0.0, 0.65),  # -X/+Y edge -> +Y
        ((1, 0, 1), 4, 1.0, 0.5),  # +X/+Z edge -> +Z
        ((0, 1, -1), 5, 0.5, 0.0),  # +Y/-Z edge -> -Z, tc = -ry = -1
        ((0, -1, 1), 4, 0.5, 1.0),  # -Y/+Z edge -> +Z
        ((1, 1, 1), 4, 1.0, 0.0),  # corner -> +Z
        ((-1, -1, -1), 5, 1.0, 1.0),  # corner -> -Z
        ((3, -3, 3), 4, 1.0, 1.0),  # corner, not unit
        ((1, 1, 0.99999994), 2, 1.0, 0.99999997),  # X/Y tie just off the corner -> +Y
    ],
)
def test_cube_map_ties_edges_and_corners(r, face, s, t):
    f, s_got, t_got = envmap.cube_map(np.array(r, np.float64))
    assert int(f) == face
    assert (float(s_got), float(t_got)) == pytest.approx((s, t), abs=1e-7)


def test_cube_map_of_zero_uses_the_sign_bit_of_rz():
    zeros = np.array([[0.0, 0.0, 0.0], [-0.0, -0.0, 0.0], [0.0, 0.0, -0.0], [-0.0, -0.0, -0.0]])
    for dtype in DTYPES:
        face, s, t = envmap.cube_map(zeros.astype(dtype))
        assert face.tolist() == [4, 4, 5, 5]
        assert np.all(s == 0.5) and np.all(t == 0.5)


def test_cube_map_subnormal_directions_keep_their_face():
    face, s, t = envmap.cube_map(np.array([[5e-324, 0, 0], [0, -1e-320, 5e-324]]))
    assert face.tolist() == [0, 3]
    assert_st_in_range(s, t)


@small_settings
@given(vector_batches)
def test_cube_map_always_names_a_face_and_in_range_coordinates(r):
    for dtype in DTYPES:
        with np.errstate(over="ignore"):
            cast = r.astype(dtype)
        cast = cast[np.all(np.isfinite(cast), axis=-1)]
        face, s, t = envmap.cube_map(cast)
        assert np.issubdtype(face.dtype, np.integer) and s.dtype == dtype
        assert np.all((face >= 0) & (face <= 5))
        assert_st_in_range(s, t)
        # The chosen face's axis carries the largest magnitude, with the face's sign.
        axis = face // 2
        major = np.take_along_axis(cast, axis[:, None], axis=1)[:, 0]
        assert np.all(np.abs(major) == np.abs(cast).max(axis=1))
        assert np.array_equal(np.signbit(major), face % 2 == 1)


@small_settings
@given(
    hnp.arrays(np.float64, (12, 3), elements=st.floats(-4, 4)),
    st.sampled_from([2.0**-600, 2.0**-20, 8.0, 2.0**600]),
)
def test_cube_map_ties_follow_the_documented_rule_and_scale_freely(v, k):
    # Force ties by copying magnitudes between components.
    v = v.copy()
    v[:4, 1] = np.copysign(v[:4, 0], v[:4, 1])
    v[4:8, 2] = np.copysign(v[4:8, 1], v[4:8, 2])
    v[8:, 1] = np.copysign(v[8:, 0], v[8:, 1])
    v[8:, 2] = np.copysign(v[8:, 0], v[8:, 2])
    face, s, t = envmap.cube_map(v)
    mags = np.abs(v)
    biggest = mags.max(axis=1)
    expected_axis = np.where(mags[:, 2] == biggest, 2, np.where(mags[:, 1] == biggest, 1, 0))
    assert np.array_equal(face // 2, expected_axis)
    f2, s2, t2 = envmap.cube_map(v * k)  # k is a power of two: exact unless subnormal
    nonzero = biggest * k > 1e-290
    assert np.array_equal(f2[nonzero], face[nonzero])
    assert np.allclose(s2[nonzero], s[nonzero], atol=1e-12)
    assert np.allclose(t2[nonzero], t[nonzero], atol=1e-12)


@small_settings
@given(
    hnp.arrays(np.int64, 20, elements=st.integers(0, 5)),
    hnp.arrays(np.float64, 20, elements=st.floats(1e-6, 1 - 1e-6)),
    hnp.arrays(np.float64, 20, elements=st.floats(1e-6, 1 - 1e-6)),
)
def test_cube_face_direction_round_trips(face, s, t):
    r = envmap.cube_face_direction(face, s, t)
    assert np.allclose(np.linalg.norm(r, axis=-1), 1, atol=1e-15)
    f2, s2, t2 = envmap.cube_map(r)
    assert np.array_equal(f2, face)
    assert np.allclose(s2, s, atol=1e-12) and np.allclose(t2, t, atol=1e-12)
    back = envmap.cube_face_direction(*envmap.cube_map(r * 3.5))
    assert np.allclose(back, r, atol=1e-15)


def test_cube_face_direction_edges_clip_and_bad_faces():
    # The +X face's s = 0 edge is rz = +1 (sc = -rz), t = 1 is ry = -1 (tc = -ry).
    r = envmap.cube_face_direction(0, 0.0, 1.0)
    assert np.allclose(r, np.array([1, -1, 1]) / np.sqrt(3))
    assert np.allclose(envmap.cube_face_direction(0, -5.0, 7.0), r)  # s, t clipped
    assert envmap.cube_face_direction(np.arange(6), 0.5, np.full((2, 1), 0.5)).shape == (2, 6, 3)
    with pytest.raises(ValueError):
        envmap.cube_face_direction(6, 0.5, 0.5)
    with pytest.raises(ValueError):
        envmap.cube_face_direction(1.0, 0.5, 0.5)


# ---------------------------------------------------------------------------- lat-long


def test_latlong_known_values():
    r = np.array(
        [[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1], [1, 1, SQRT2]]
    )
    s, t = envmap.latlong_map(r)
    assert np.allclose(s, [0, 0.25, 0.5, 0.75, 0, 0, 0.125])
    assert np.allclose(t, [0.5, 0.5, 0.5, 0.5, 0, 1, 0.25])


def test_latlong_poles_signed_zeros_and_zero():
    for dtype in DTYPES:
        poles = np.array(
            [
                [0.0, 0.0, 1.0],
                [-0.0, 0.0, 1.0],
                [0.0, -0.0, 1.0],
                [-0.0, -0.0, 1.0],
                [-0.0, -0.0, -1.0],
                [0.0, -0.0, -3.0],
            ],
            dtype,
        )
        s, t = envmap.latlong_map(poles)
        assert np.all(s == 0)
        assert t.tolist() == [0, 0, 0, 0, 1, 1]
        # r = 0 (any zero signs, -0.0 in z included) is (0, 0), the image of +z.
        s, t = envmap.latlong_map(np.array([[0.0, 0.0, 0.0], [-0.0, -0.0, -0.0]], dtype))
        assert s.tolist() == [0, 0] and t.tolist() == [0, 0]


def test_latlong_rz_rounded_above_one_stays_finite():
    # Vectors that normalise with |rz| a rounding step above 1 would give NaN in arccos.
    big = 1 + 2**-52
    r = np.array([[0, 0, big], [0, 0, -big], [1e-9, 0, big], [0, -1e-9, -big]])
    s, t = envmap.latlong_map(r)
    assert_st_in_range(s, t)
    assert np.allclose(t, [0, 1, 0, 1], atol=1e-9)
    with np.errstate(invalid="ignore"):
        assert np.isnan(np.arccos(big))  # what an unguarded arccos would have done


def test_latlong_wraps_s_into_half_open_interval():
    r = np.array([[1, -1e-20, 0], [1, -1e-300, 0], [1, -5e-324, 0]])
    s, _ = envmap.latlong_map(r)
    assert np.all(s < 1) and np.all(s >= 0)
    s32, _ = envmap.latlong_map(np.array([[1, -1e-10, 0]], np.float32))
    assert np.all(s32 < 1) and s32.dtype == np.float32


def test_latlong_seam_needs_per_fragment_or_unwrapped_s():
    # A triangle straddling the seam at phi = 0 (the +x half-plane).
    phi = np.radians([-1.0, 1.0, 0.5])
    tri = np.stack([np.cos(phi), np.sin(phi), np.full(3, 0.2)], axis=-1)
    s, _ = envmap.latlong_map(tri)
    assert s.max() - s.min() == pytest.approx(358.5 / 360, abs=1e-9)  # a jump of ~1
    centroid = tri.mean(axis=0)
    s_true, _ = envmap.latlong_map(centroid)
    naive = s.mean()  # what per-vertex s interpolated by the rasteriser gives
    assert abs(naive - s_true) > 0.3
    # The fix for vertex-interpolated s: unwrap relative to the first vertex, wrap after.
    unwrapped = np.where(s - s[0] < -0.5, s + 1, np.where(s - s[0] > 0.5, s - 1, s))
    assert np.mod(unwrapped.mean(), 1) == pytest.approx(s_true, abs=1e-3)


@small_settings
@given(vector_batches)
def test_latlong_stays_finite_and_in_range(r):
    for dtype in DTYPES:
        with np.errstate(over="ignore"):
            cast = r.astype(dtype)
        cast = cast[np.all(np.isfinite(cast), axis=-1)]
        s, t = envmap.latlong_map(cast)
        assert s.dtype == dtype and t.dtype == dtype
        assert_st_in_range(s, t)
        assert np.all(s < 1)


@small_settings
@given(moderate_batches)
def test_latlong_round_trips_and_equals_arccos_on_the_unit_sphere(v):
    r = unit_rows(v)
    s, t = envmap.latlong_map(r)
    assert np.allclose(envmap.latlong_map_inverse(s, t), r, atol=1e-14)
    assert np.allclose(t, np.arccos(np.clip(r[:, 2], -1, 1)) / np.pi, atol=1e-7)
    assert np.allclose(envmap.latlong_map_inverse(s + 3, t), r, atol=1e-12)  # periodic in s
    r32 = r.astype(np.float32)
    back32 = envmap.latlong_map_inverse(*envmap.latlong_map(r32))
    assert back32.dtype == np.float32 and np.allclose(back32, r32, atol=1e-6)


def test_latlong_inverse_then_forward_is_the_identity_away_from_poles_and_seam():
    rng = np.random.default_rng(3)
    s = rng.uniform(1e-6, 1 - 1e-6, 2000)
    t = rng.uniform(1e-3, 1 - 1e-3, 2000)
    s2, t2 = envmap.latlong_map(envmap.latlong_map_inverse(s, t))
    assert np.allclose(s2, s, atol=1e-12) and np.allclose(t2, t, atol=1e-12)


# ---------------------------------------------------------------------------- demo style


def test_normal_map_follows_the_article_for_256():
    n = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0], [0.6, -0.8, 0], [2, 0, 0]])
    u, v = envmap.normal_map(n, 256, 256)
    assert np.allclose(u, [127, 255, 127, 0.6 * 128 + 127, 255])  # N.x*128 + 127
    assert np.allclose(v, [127, 127, 255, -0.8 * 128 + 127, 127])


def test_normal_map_off_by_one_is_clamped():
    # The article's formula gives -1 for n.x = -1: one texel before the map.
    u, v = envmap.normal_map([-1, -1, 0], 256, 256)  # normalised: -1/sqrt 2 each
    assert (u, v) == pytest.approx((-128 / SQRT2 + 127,) * 2)
    u, v = envmap.normal_map([[-1, 0, 0], [0, -1, 0]], 256, 64)
    assert u.tolist() == [0, 127] and v.tolist() == [31, 0]
    # An odd width: n.x = +1 still lands on the last texel.
    u, _ = envmap.normal_map([1, 0, 0], 255, 255)
    assert u == pytest.approx(254)


def test_normal_map_zero_normal_and_validation():
    u, v = envmap.normal_map(np.zeros(3, np.float32), 64, 32)
    assert (float(u), float(v)) == (31.0, 15.0) and np.asarray(u).dtype == np.float32
    with pytest.raises(ValueError):
        envmap.normal_map([0, 0, 1], 0, 64)


@small_settings
@given(vector_batches, st.integers(1, 4096), st.integers(1, 4096))
def test_normal_map_stays_inside_the_map(n, width, height):
    u, v = envmap.normal_map(n, width, height)
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(v))
    assert np.all((u >= 0) & (u <= width - 1)) and np.all((v >= 0) & (v <= height - 1))


# ---------------------------------------------------------------------------- baking

AXIS_COLOURS = np.array(
    [
        [1, 0, 0],
        [0, 1, 1],  # +X red, -X cyan
        [0, 1, 0],
        [1, 0, 1],  # +Y green, -Y magenta
        [0, 0, 1],
        [1, 1, 0],  # +Z blue, -Z yellow
    ],
    float,
)


def axis_env(directions: np.ndarray) -> np.ndarray:
    """Colour by dominant signed world axis, computed without envmap."""
    assert directions.dtype == np.float64 and directions.ndim == 2
    assert np.allclose(np.linalg.norm(directions, axis=1), 1)
    axis = np.argmax(np.abs(directions), axis=1)
    negative = directions[np.arange(len(directions)), axis] < 0
    return AXIS_COLOURS[2 * axis + negative]


def direction_env(directions: np.ndarray) -> np.ndarray:
    return (directions + 1) / 2


def to_uint8(colour) -> np.ndarray:
    return np.round(np.asarray(colour) * 255).astype(np.uint8)


def test_bake_cube_faces_puts_each_axis_on_its_face():
    faces = envmap.bake_cube_faces(axis_env, 8)
    assert faces.shape == (6, 8, 8, 3) and faces.dtype == np.uint8
    for k in range(6):
        assert np.all(faces[k] == to_uint8(AXIS_COLOURS[k])), envmap.CUBE_FACE_NAMES[k]


def test_bake_cube_faces_row_order_top_is_t_equal_one():
    size = 4
    faces = envmap.bake_cube_faces(direction_env, size)
    # +X top-left texel centre: s = 1/8, t = 7/8 -> sc = -3/4, tc = 3/4, and from the
    # spec's table (+X: sc = -rz, tc = -ry) the direction is (1, -3/4, 3/4).
    d = np.array([1, -0.75, 0.75]) / np.linalg.norm([1, -0.75, 0.75])
    assert np.array_equal(faces[0, 0, 0], to_uint8(direction_env(d)))
    # +Y bottom-right: s = 7/8, t = 1/8 -> (sc, tc) = (3/4, -3/4); +Y: sc = rx, tc = rz.
    d = np.array([0.75, 1, -0.75]) / np.linalg.norm([0.75, 1, -0.75])
    assert np.array_equal(faces[2, -1, -1], to_uint8(direction_env(d)))
    # Uploading rows reversed (first row = t = 0, as raw glTexImage2D wants) and looking
    # a direction up with cube_map gives back the direction's own colour.
    r = np.array([0.3, -0.9, 0.2])
    face, s, t = envmap.cube_map(r)
    gl_rows = faces[:, ::-1]
    texel = gl_rows[int(face), min(int(t * size), size - 1), min(int(s * size), size - 1)]
    centre = envmap.cube_face_direction(
        face, (np.floor(s * size) + 0.5) / size, (np.floor(t * size) + 0.5) / size
    )
    assert np.array_equal(texel, to_uint8(direction_env(centre)))


def test_bake_latlong_orientation():
    width, height = 16, 8
    image = envmap.bake_latlong(axis_env, width, height)
    assert image.shape == (height, width, 3) and image.dtype == np.uint8
    # Row 0 (top) is t near 1: theta near pi, the -z pole (yellow); the bottom row +z.
    assert np.all(image[0] == to_uint8(AXIS_COLOURS[5]))
    assert np.all(image[-1] == to_uint8(AXIS_COLOURS[4]))
    # On the equator rows s = 0 is +x, s = 1/4 is +y, 1/2 is -x, 3/4 is -y.
    equator = image[height // 2]
    for column, colour in ((0, 0), (4, 2), (8, 1), (12, 3)):
        assert np.array_equal(equator[column], to_uint8(AXIS_COLOURS[colour]))


def test_bake_sphere_map_uses_the_inverse_view_rotation():
    size = 32
    # A camera looking along world -x with +y up: side = forward x up = -z, so eye +x is
    # world -z, eye +y is world +y and eye +z (back towards the viewer) is world +x.
    view = math3d.look_at((0, 0, 0), (-1, 0, 0), (0, 1, 0))[:3, :3]
    assert np.allclose(view @ [1, 0, 0], [0, 0, 1]) and np.allclose(view @ [0, 0, -1], [1, 0, 0])
    image = envmap.bake_sphere_map(axis_env, size, view)
    assert image.shape == (size, size, 3) and image.dtype == np.uint8
    centre = image[size // 2, size // 2]
    assert np.array_equal(centre, to_uint8(AXIS_COLOURS[0]))  # eye +z = world +x
    # Texel centres outside the disc hold the rim value, eye (0, 0, -1) = world -x.
    assert np.array_equal(image[0, 0], to_uint8(AXIS_COLOURS[1]))
    # t grows upwards: the top-middle texel looks at eye +y-ish = world +y, green.
    assert np.array_equal(image[3, size // 2], to_uint8(AXIS_COLOURS[2]))
    # And s grows to the right: the right-middle texel looks at eye +x = world -z, yellow.
    assert np.array_equal(image[size // 2, size - 4], to_uint8(AXIS_COLOURS[5]))
    # Identity view: the image's right middle is eye +x = world +x.
    plain = envmap.bake_sphere_map(axis_env, size, np.eye(3))
    s = 0.5 + 1 / (2 * SQRT2)
    assert np.array_equal(plain[size // 2, int(s * size)], to_uint8(AXIS_COLOURS[0]))


def test_bake_sphere_map_texel_matches_sphere_map_of_its_direction():
    size = 16
    rotation = math3d.rotate(30, (1, 2, 3))[:3, :3]
    image = envmap.bake_sphere_map(direction_env, size, rotation)
    i, j = 5, 11
    s, t = (j + 0.5) / size, 1 - (i + 0.5) / size
    world = rotation.T @ envmap.sphere_map_inverse(s, t)
    assert np.array_equal(image[i, j], to_uint8(direction_env(world)))
    eye = rotation @ world
    assert (envmap.sphere_map(eye)) == pytest.approx((s, t), abs=1e-12)


def test_bake_validation():
    with pytest.raises(ValueError):
        envmap.bake_cube_faces(axis_env, 0)
    with pytest.raises(ValueError):
        envmap.bake_latlong(axis_env, 8, 2.5)  # type: ignore[arg-type]  # not whole, on purpose
    with pytest.raises(ValueError):
        envmap.bake_sphere_map(axis_env, 8, np.eye(4))
    with pytest.raises(ValueError):
        envmap.bake_cube_faces(lambda d: d[:, :2], 4)
