"""The lab scene in numpy: robot world matrices, capture camera, mirror texture coordinates."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab.scene.graph import Node, SceneGraph
from mirrorlab.scene.robot import HAND_OFFSET, build_lab_scene
from tests.imagecheck import mirror_image_point


def point(node, local=(0, 0, 0)):
    return (node.world_matrix() @ np.array([*local, 1.0]))[:3]


def test_robot_at_zero_angles_stacks_straight_up():
    scene = build_lab_scene((0, 0, 0))
    g = scene.graph
    assert np.allclose(point(g["base"]), (0, -2, 0))
    assert np.allclose(point(g["lower_arm"]), (0, -2, 0))
    assert np.allclose(point(g["upper_arm"]), (0, 2, 0))  # lower arm is 4 long
    assert np.allclose(scene.hand_center(), np.array((0, 2, 0)) + HAND_OFFSET)


def test_robot_world_matrices_for_given_angles_by_hand():
    # base 90 about y: local +z -> world +x; lower arm 90 about z: its +y -> -x of the
    # base frame, i.e. world: base frame x is world -z... worked out step by step below.
    scene = build_lab_scene((90, 90, 0))
    g = scene.graph
    # Base frame: x_b = world -z, y_b = world y, z_b = world +x, origin (0,-2,0).
    # Lower arm rotated +90 about z_b: its y axis points along -x_b = world +z.
    assert np.allclose(point(g["upper_arm"]), (0, -2, 4))
    # Upper arm unrotated relative to lower arm; its tip at local y 3.2 is 7.2 along +z.
    assert np.allclose(point(g["upper_arm"], (0, 3.2, 0)), (0, -2, 7.2))
    # The hand's +z offset (0.45) is along z_b = world +x.
    assert np.allclose(scene.hand_center(), (0.45, -2, 7.2))


def test_upper_arm_angle_bends_only_the_upper_arm():
    scene = build_lab_scene((0, 0, -90))
    g = scene.graph
    assert np.allclose(point(g["upper_arm"]), (0, 2, 0))
    # -90 about z turns the upper arm's +y into +x.
    assert np.allclose(point(g["upper_arm"], (0, 3.2, 0)), (3.2, 2, 0))


def test_world_matrix_cache_is_invalidated_for_the_subtree_only():
    scene = build_lab_scene((0, 0, 0))
    g = scene.graph
    base_before = g["base"].world_matrix()
    hand_before = scene.hand_center()
    revision = g.revision
    g.set_angle("lower_arm", 30)
    assert g.revision == revision + 1
    assert g["base"].world_matrix() is base_before  # cached, untouched
    assert not np.allclose(scene.hand_center(), hand_before)
    g.set_angle("lower_arm", 30)
    assert g.revision == revision + 1  # no change, no new revision


def test_scene_graph_rejects_bad_joint_input():
    scene = build_lab_scene()
    with pytest.raises(ValueError, match="no joint"):
        scene.graph.set_angle("hand", 10)
    with pytest.raises(ValueError, match="finite"):
        scene.graph.set_angle("base", float("nan"))
    with pytest.raises(KeyError, match="elbo"):
        scene.graph["elbo"]
    with pytest.raises(ValueError, match="3 numbers"):
        scene.set_angles((1, 2))
    with pytest.raises(ValueError, match="duplicate"):
        root = Node("a")
        root.add(Node("a"))
        SceneGraph(root)


def test_capture_camera_uses_the_labs_numbers():
    capture = build_lab_scene().capture
    assert capture.extents == (-6, 2, -3, 5, 0, 15)
    assert np.allclose(capture.view(), math3d.look_at((-7, 0, 0), (0, 0, 0), (0, 1, 0)))
    assert np.allclose(capture.projection(), math3d.ortho(-6, 2, -3, 5, 0, 15))


def test_mirror_is_the_labs_quad_facing_the_robot():
    mirror = build_lab_scene().mirror
    assert np.allclose(mirror.corners, [(-7, -3, -6), (-7, 5, -6), (-7, 5, 2), (-7, -3, 2)])
    assert np.allclose(mirror.normal, (1, 0, 0))


@given(st.floats(-3, 5), st.floats(-6, 2))
def test_a_point_on_the_mirror_maps_to_the_quads_texture_coordinate(y, z):
    scene = build_lab_scene()
    p = np.array([-7.0, y, z])
    clip = math3d.transform_points(scene.capture.projection() @ scene.capture.view(), p)
    st_capture = (clip[:2] / clip[3] + 1.0) / 2.0  # NDC -> texture coordinates
    assert np.allclose(st_capture, scene.mirror.texcoord_at(p), atol=1e-12)
    assert np.allclose(scene.mirror.texcoord_at(p), ((z + 6) / 8, (y + 3) / 8))


def test_capture_depth_range_covers_from_mirror_to_fifteen_units_out():
    scene = build_lab_scene()
    vp = scene.capture.projection() @ scene.capture.view()
    for x, ndc_z in ((-7, -1.0), (8, 1.0)):
        clip = math3d.transform_points(vp, np.array([x, 0.0, 0.0]))
        assert clip[2] / clip[3] == pytest.approx(ndc_z)


def test_mirror_image_point_helper_is_consistent_with_texcoords():
    scene = build_lab_scene()
    hand = scene.hand_center()
    on_mirror = mirror_image_point(scene, hand)
    assert on_mirror[0] == pytest.approx(-7)
    assert np.allclose(on_mirror[1:], hand[1:])
