"""Matrix helpers against hand-derived values and invariants."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from mirrorlab import math3d

finite = st.floats(-50, 50, allow_nan=False)


def test_capture_view_matches_hand_derived_look_at():
    # gluLookAt((-7,0,0), (0,0,0), (0,1,0)): forward +x, side = forward x up = +z,
    # so eye x is world z, eye y is world y, eye -z is world +x, origin 7 units ahead.
    expected = np.array([[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, -7], [0, 0, 0, 1]], float)
    assert np.allclose(math3d.look_at((-7, 0, 0), (0, 0, 0), (0, 1, 0)), expected)


def test_capture_ortho_matches_glortho_formula():
    # glOrtho(-6, 2, -3, 5, 0, 15): scale 2/8 in x and y, -2/15 in z; offsets
    # -(r+l)/(r-l) = 0.5, -(t+b)/(t-b) = -0.25, -(f+n)/(f-n) = -1.
    expected = np.array([[0.25, 0, 0, 0.5], [0, 0.25, 0, -0.25], [0, 0, -2 / 15, -1], [0, 0, 0, 1]])
    assert np.allclose(math3d.ortho(-6, 2, -3, 5, 0, 15), expected)


def test_perspective_maps_near_and_far_planes_to_ndc_bounds():
    p = math3d.perspective(60, 1.5, 0.5, 40)
    for z, ndc in ((-0.5, -1.0), (-40.0, 1.0)):
        clip = p @ np.array([0, 0, z, 1.0])
        assert clip[2] / clip[3] == pytest.approx(ndc)
    top = p @ np.array([0, np.tan(np.radians(30)) * 2, -2, 1.0])
    assert top[1] / top[3] == pytest.approx(1.0)


@given(
    st.floats(-720, 720),
    st.tuples(finite, finite, finite).filter(lambda a: np.linalg.norm(a) > 1e-3),
)
def test_rotation_is_proper_and_fixes_its_axis(angle, axis):
    r = math3d.rotate(angle, axis)[:3, :3]
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-9)
    assert np.linalg.det(r) == pytest.approx(1.0)
    assert np.allclose(
        r @ np.asarray(axis), axis, atol=1e-9 * max(1.0, float(np.linalg.norm(axis)))
    )


def test_rotation_is_right_handed():
    assert np.allclose(math3d.rotate(90, (0, 0, 1))[:3, 0], (0, 1, 0))
    assert np.allclose(math3d.rotate(90, (0, 1, 0))[:3, 2], (1, 0, 0))


@pytest.mark.parametrize(
    "call",
    [
        lambda: math3d.look_at((1, 2, 3), (1, 2, 3), (0, 1, 0)),
        lambda: math3d.look_at((0, 5, 0), (0, 0, 0), (0, 1, 0)),
        lambda: math3d.rotate(10, (0, 0, 0)),
        lambda: math3d.ortho(1, 1, 0, 1, 0, 1),
        lambda: math3d.perspective(45, 1, 0, 10),
    ],
)
def test_degenerate_inputs_raise_clear_errors(call):
    with pytest.raises(ValueError):
        call()


def test_project_to_pixels_puts_view_centre_in_image_centre_and_y_down():
    view = math3d.look_at((0, 0, 10), (0, 0, 0), (0, 1, 0))
    vp = math3d.perspective(45, 2.0, 0.1, 100) @ view
    pts = math3d.project_to_pixels(vp, np.array([[0, 0, 0], [0, 1, 0]], float), 200, 100)
    assert np.allclose(pts[0, :2], (100, 50))
    assert pts[1, 1] < 50  # world up is image up, i.e. smaller row


def test_reflection_matrix_mirrors_points_across_the_lab_mirror():
    plane = math3d.plane_through((-7.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    reflect = math3d.reflection_matrix(plane)
    points = np.array([[0.0, 1.0, 2.0], [-7.0, 3.0, -1.0], [-9.5, 0.0, 0.0]])
    moved = math3d.transform_points(reflect, points)[:, :3]
    np.testing.assert_allclose(moved, [[-14.0, 1.0, 2.0], [-7.0, 3.0, -1.0], [-4.5, 0.0, 0.0]])
    assert np.linalg.det(reflect) == pytest.approx(-1.0)
    np.testing.assert_allclose(reflect @ reflect, np.eye(4), atol=1e-12)


@given(
    st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3),
    st.floats(-10, 10),
)
def test_reflection_matrix_fixes_the_plane_and_flips_its_normal(normal, offset):
    plane = math3d.plane_through(np.asarray(normal) * offset, normal)
    reflect = math3d.reflection_matrix(plane)
    n = plane[:3]
    on_plane = -plane[3] * n
    np.testing.assert_allclose(math3d.transform_points(reflect, on_plane)[:3], on_plane, atol=1e-9)
    np.testing.assert_allclose(reflect[:3, :3] @ n, -n, atol=1e-12)


def test_plane_through_rejects_a_zero_normal():
    with pytest.raises(ValueError, match="non-zero"):
        math3d.plane_through((0, 0, 0), (0, 0, 0))


def test_oblique_projection_clips_exactly_on_the_plane_and_keeps_x_and_y():
    projection = math3d.perspective(45.0, 1.5, 0.1, 100.0)
    # A plane 5 units ahead, tilted: normal towards -z (away from the eye) and a bit +x.
    normal = np.array([0.3, -0.1, -1.0])
    normal /= np.linalg.norm(normal)
    point = np.array([0.0, 0.0, -5.0])
    plane = np.append(normal, -normal @ point)
    oblique = math3d.oblique_projection(projection, plane)
    np.testing.assert_allclose(oblique[[0, 1, 3]], projection[[0, 1, 3]])
    # A point on the plane lands on the near clip plane: z_clip = -w_clip.
    tangent = np.cross(normal, [0.0, 1.0, 0.0])
    for p in (point, point + 0.7 * tangent):
        clip = oblique @ np.append(p, 1.0)
        assert clip[2] == pytest.approx(-clip[3], abs=1e-9)
    beyond = oblique @ np.append(point + 0.5 * normal, 1.0)
    before = oblique @ np.append(point - 0.5 * normal, 1.0)
    assert -beyond[3] < beyond[2]  # kept (in front of the plane)
    assert before[2] < -before[3]  # clipped


def test_oblique_projection_refuses_a_plane_through_the_eye():
    projection = math3d.perspective(45.0, 1.0, 0.1, 100.0)
    with pytest.raises(ValueError, match="eye"):
        math3d.oblique_projection(projection, np.array([1.0, 0.0, 0.0, 0.0]))


FLIP_X = np.diag([-1.0, 1.0, 1.0, 1.0])


@settings(max_examples=200, deadline=None)
@given(
    normal=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, -0.05)),
    distance=st.floats(0.2, 20.0),
    flip=st.booleans(),
    shift=st.floats(-0.5, 0.5),
    seed=st.integers(0, 2**31 - 1),
)
@example(normal=(-1.0, 0.0, -0.0625), distance=15.0, flip=False, shift=0.5, seed=0)  # no view
def test_the_oblique_projection_keeps_everything_of_the_view_beyond_its_plane(
    normal, distance, flip, shift, seed
):
    """Lengyel's far plane goes through the view volume's corner opposite the new near
    plane, so nothing of the old volume beyond the plane is cut. The corner is picked in
    clip space: with x flipped (the world seen in a mirror) or an off-centre frustum the
    eye-space signs pick the wrong one, and the far plane cuts through the view."""
    projection = math3d.perspective(50.0, 1.3, 0.1, 40.0)
    projection[0, 2] = shift  # off-centre
    if flip:
        projection = FLIP_X @ projection
    n = np.asarray(normal)
    n /= np.linalg.norm(n)
    plane = np.append(n, -distance)  # the eye (origin) behind it: d < 0
    inverse = np.linalg.inv(projection)
    corners = np.array([[x, y, z, 1.0] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    corners = corners @ inverse.T
    if not np.max((corners / corners[:, 3:]) @ plane) > 0.0:
        # the whole view volume lies before the plane: no projection keeps anything
        with pytest.raises(ValueError, match="leaves nothing"):
            math3d.oblique_projection(projection, plane)
        return
    oblique = math3d.oblique_projection(projection, plane)
    rng = np.random.default_rng(seed)
    ndc = rng.uniform(-1.0, 1.0, size=(400, 3))
    points = np.column_stack([ndc, np.ones(len(ndc))]) @ inverse.T
    points = points / points[:, 3:]
    beyond = points @ plane > 1e-9
    clip = points[beyond] @ oblique.T
    assert np.all(clip[:, 2] <= clip[:, 3] * (1 + 1e-9) + 1e-9)
    assert np.all(clip[:, 2] >= -clip[:, 3] * (1 + 1e-9) - 1e-9)
