"""The scene model in numpy: the robot's world matrices, the lab's mirror and capture
camera, transforms, the ``with_*`` changes and keyframe animation."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab.scene.animation import interpolate
from mirrorlab.scene.graph import Node, SceneGraph
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import (
    NEAR_MARGIN,
    Camera,
    PlanarReflector,
    RobotObject,
    Scene,
    Transform,
    ortho_capture_for,
)
from mirrorlab.scene.robot import (
    HAND_OFFSET,
    JOINT_NAMES,
    hand_center,
    robot_graph,
    robot_parts,
    scene_parts,
)
from tests.imagecheck import mirror_image_point

LAB_CORNERS = [(-7, -3, -6), (-7, 5, -6), (-7, 5, 2), (-7, -3, 2)]


def point(node, local=(0, 0, 0)):
    return (node.world_matrix() @ np.array([*local, 1.0]))[:3]


def graph_at(angles):
    return robot_graph(RobotObject(angles=angles))


# --------------------------------------------------------------------------- the robot


def test_robot_at_zero_angles_stacks_straight_up():
    g = graph_at((0, 0, 0))
    assert np.allclose(point(g["base"]), (0, -2, 0))
    assert np.allclose(point(g["lower_arm"]), (0, -2, 0))
    assert np.allclose(point(g["upper_arm"]), (0, 2, 0))  # lower arm is 4 long
    assert np.allclose(
        hand_center(RobotObject(angles=(0, 0, 0))), np.array((0, 2, 0)) + HAND_OFFSET
    )


def test_robot_world_matrices_for_given_angles_by_hand():
    g = graph_at((90, 90, 0))
    # Base frame: x_b = world -z, y_b = world y, z_b = world +x, origin (0,-2,0).
    # Lower arm rotated +90 about z_b: its y axis points along -x_b = world +z.
    assert np.allclose(point(g["upper_arm"]), (0, -2, 4))
    # Upper arm unrotated relative to lower arm; its tip at local y 3.2 is 7.2 along +z.
    assert np.allclose(point(g["upper_arm"], (0, 3.2, 0)), (0, -2, 7.2))
    # The hand's +z offset (0.45) is along z_b = world +x.
    assert np.allclose(hand_center(RobotObject(angles=(90, 90, 0))), (0.45, -2, 7.2))


def test_upper_arm_angle_bends_only_the_upper_arm():
    g = graph_at((0, 0, -90))
    assert np.allclose(point(g["upper_arm"]), (0, 2, 0))
    # -90 about z turns the upper arm's +y into +x.
    assert np.allclose(point(g["upper_arm"], (0, 3.2, 0)), (3.2, 2, 0))


def test_the_robots_transform_places_the_whole_arm():
    placed = RobotObject(
        angles=(0, 0, 0), transform=Transform(position=(1.0, 0.0, -3.5), rotation=(0, 90, 0))
    )
    base = hand_center(RobotObject(angles=(0, 0, 0)))
    # Turned 90 degrees about y: the hand's +z offset becomes +x, then moved.
    expected = np.array([base[2], base[1], -base[0]]) + np.array([1.0, 0.0, -3.5])
    assert np.allclose(hand_center(placed), expected)


def test_world_matrix_cache_is_invalidated_for_the_subtree_only():
    g = graph_at((0, 0, 0))
    base_before = g["base"].world_matrix()
    hand_before = g["hand"].world_matrix()[:3, 3].copy()
    revision = g.revision
    g.set_angle("lower_arm", 30)
    assert g.revision == revision + 1
    assert g["base"].world_matrix() is base_before  # cached, untouched
    assert not np.allclose(g["hand"].world_matrix()[:3, 3], hand_before)
    g.set_angle("lower_arm", 30)
    assert g.revision == revision + 1  # no change, no new revision


def test_scene_graph_rejects_bad_joint_input():
    g = graph_at((0, 0, 0))
    with pytest.raises(ValueError, match="no joint"):
        g.set_angle("hand", 10)
    with pytest.raises(ValueError, match="finite"):
        g.set_angle("base", float("nan"))
    with pytest.raises(KeyError, match="elbo"):
        g["elbo"]
    with pytest.raises(ValueError, match="duplicate"):
        root = Node("a")
        root.add(Node("a"))
        SceneGraph(root)
    lab = load_scene("lab20")
    with pytest.raises(ValueError, match="3 finite numbers"):
        lab.with_angles((1, 2))
    with pytest.raises(ValueError, match="3 finite numbers"):
        lab.with_angles((1, float("inf"), 2))
    with pytest.raises(ValueError, match="has no robot to pose"):
        load_scene("cone").with_angles((1, 2, 3))


def test_the_lab_scene_draws_the_robots_parts_and_the_frame():
    lab = load_scene("lab20")
    parts = scene_parts(lab)
    assert [p.name for p in parts] == [
        "robot.base",
        "robot.shoulder",
        "robot.lower_arm",
        "robot.elbow",
        "robot.upper_arm",
        "robot.hand",
        "mirror_frame",
    ]
    assert lab.robot is not None
    graph = robot_graph(lab.robot)
    assert all(
        graph[name].angle == angle
        for name, angle in zip(JOINT_NAMES, (-35.0, 30.0, -75.0), strict=True)
    )
    (base,) = [p for p in parts if p.name == "robot.base"]
    assert isinstance(base.texture, Path) and base.texture.name == "metal.png"
    (hand,) = [p for p in parts if p.name == "robot.hand"]
    assert np.allclose(hand.model[:3, 3], hand_center(lab.robot))


angle = st.floats(-720.0, 720.0, allow_nan=False)


@given(
    st.tuples(angle, angle, angle),
    st.tuples(*[st.floats(-1e4, 1e4)] * 3),
    st.tuples(angle, angle, angle),
    st.tuples(*[st.floats(0.01, 100.0)] * 3),
)
def test_the_robots_parts_are_its_graphs_to_the_last_bit(angles, position, rotation, scale):
    """The parts drawn for a pose (worked out without building a graph) are those of the
    robot's scene graph: names, meshes, looks, and every matrix bit for bit."""
    robot = RobotObject(
        angles=angles, transform=Transform(position=position, rotation=rotation, scale=scale)
    )
    graph = robot_graph(robot)
    nodes = [node for node in graph.nodes() if node.mesh]
    parts = robot_parts(robot)
    assert [part.name for part in parts] == [f"robot.{node.name}" for node in nodes]
    for part, node in zip(parts, nodes, strict=True):
        assert part.model.tobytes() == node.world_matrix().tobytes()
        assert part.color == node.color
        assert part.mesh.name == f"{node.mesh}.obj"
        assert (part.texture is None) == (node.texture is None)


def test_a_joint_at_minus_zero_turns_as_its_graph_does():
    """-0.0 and 0.0 are equal keys to a cache but, about some axes, rotations that differ in
    a zero's sign: each pose's parts are still its graph's, bit for bit, whichever came
    first."""
    for angles in ((0.0, 0.0, 0.0), (-0.0, -0.0, -0.0), (0.0, -0.0, 0.0)):
        robot = RobotObject(angles=angles)
        nodes = [node for node in robot_graph(robot).nodes() if node.mesh]
        for part, node in zip(robot_parts(robot), nodes, strict=True):
            assert part.model.tobytes() == node.world_matrix().tobytes(), angles


def test_a_robot_with_a_joint_angle_that_is_not_finite_is_refused():
    with pytest.raises(ValueError, match="finite"):
        robot_parts(RobotObject(angles=(0.0, float("nan"), 0.0)))


# --------------------------------------------------------------------------- the mirror


def lab_mirror() -> PlanarReflector:
    """The lab scene's flat mirror."""
    mirror = load_scene("lab20").reflector("mirror")
    assert isinstance(mirror, PlanarReflector)
    return mirror


def test_capture_camera_uses_the_labs_numbers():
    capture = lab_mirror().ortho_capture
    assert capture.extents == (-6, 2, -3, 5, 0, 15)
    assert np.allclose(capture.view(), math3d.look_at((-7, 0, 0), (0, 0, 0), (0, 1, 0)))
    assert np.allclose(capture.projection(), math3d.ortho(-6, 2, -3, 5, 0, 15))


def test_mirror_is_the_labs_quad_facing_the_robot():
    mirror = load_scene("lab20").reflector("mirror")
    assert isinstance(mirror, PlanarReflector) and mirror.technique == "ortho"
    assert np.allclose(mirror.corners, LAB_CORNERS)
    assert np.allclose(mirror.normal, (1, 0, 0))
    assert np.allclose(mirror.center, (-7, 1, -2))
    assert np.allclose(mirror.plane, (1, 0, 0, 7))
    assert np.allclose(mirror.texcoords(), [(0, 0), (0, 1), (1, 1), (1, 0)])


@given(st.floats(-3, 5), st.floats(-6, 2))
def test_a_point_on_the_mirror_maps_to_the_quads_texture_coordinate(y, z):
    mirror = lab_mirror()
    p = np.array([-7.0, y, z])
    capture = mirror.ortho_capture
    clip = math3d.transform_points(capture.projection() @ capture.view(), p)
    st_capture = (clip[:2] / clip[3] + 1.0) / 2.0  # NDC -> texture coordinates
    assert np.allclose(st_capture, ((z + 6) / 8, (y + 3) / 8), atol=1e-12)
    # A capture derived from the corners shows the glass the same way.
    derived = ortho_capture_for(mirror.corner_array, mirror.normal)
    clip = math3d.transform_points(derived.projection() @ derived.view(), p)
    assert np.allclose((clip[:2] / clip[3] + 1.0) / 2.0, st_capture, atol=1e-12)


def test_capture_depth_range_covers_from_mirror_to_fifteen_units_out():
    capture = lab_mirror().ortho_capture
    vp = capture.projection() @ capture.view()
    for x, ndc_z in ((-7, -1.0), (8, 1.0)):
        clip = math3d.transform_points(vp, np.array([x, 0.0, 0.0]))
        assert clip[2] / clip[3] == pytest.approx(ndc_z)


def test_a_derived_capture_sits_on_the_glass_and_looks_out_along_its_normal():
    corners = ((0.0, 0.0, 0.0), (0.0, 2.0, 0.0), (3.0, 2.0, 0.0), (3.0, 0.0, 0.0))
    mirror = PlanarReflector("m", corners)  # seen from -z: counter-clockwise there
    assert np.allclose(mirror.normal, (0, 0, -1))
    capture = mirror.ortho_capture
    assert np.allclose(capture.eye, (1.5, 1.0, 0.0))
    assert np.allclose(capture.target, (1.5, 1.0, -1.0))
    assert np.allclose(mirror.texcoords(), [(0, 0), (0, 1), (1, 1), (1, 0)])


def test_mirror_image_point_helper_is_consistent_with_texcoords():
    scene = load_scene("lab20")
    assert scene.robot is not None
    hand = hand_center(scene.robot)
    on_mirror = mirror_image_point(lab_mirror(), hand)
    assert on_mirror[0] == pytest.approx(-7)
    assert np.allclose(on_mirror[1:], hand[1:])


# --------------------------------------------------------------------------- the model


def test_transform_scales_then_turns_x_y_z_then_moves():
    transform = Transform(position=(1, 2, 3), rotation=(90, 0, 0), scale=(2, 2, 2))
    assert np.allclose(
        math3d.transform_points(transform.matrix(), np.array([0, 1, 0.0]))[:3], (1, 2, 5)
    )
    turned = Transform(rotation=(90, 90, 0))  # x first: y -> z, then y: z -> x
    assert np.allclose(
        math3d.transform_points(turned.matrix(), np.array([0, 1, 0.0]))[:3], (1, 0, 0)
    )


def test_camera_matrices_and_their_refusals():
    camera = Camera(eye=(0, 0, 5), target=(0, 0, 0), fovy=90, near=1, far=10)
    assert np.allclose(camera.view(), math3d.look_at((0, 0, 5), (0, 0, 0), (0, 1, 0)))
    # The clipping near plane lies NEAR_MARGIN of near before near (see test_near_plane).
    assert np.allclose(
        camera.projection(2.0), math3d.perspective(90, 2.0, 1 - NEAR_MARGIN, 10), rtol=0, atol=1e-15
    )
    assert not np.allclose(
        camera.projection(2.0), math3d.perspective(90, 2.0, 1, 10), rtol=0, atol=1e-6
    )
    with pytest.raises(ValueError):
        Camera(eye=(1, 1, 1), target=(1, 1, 1)).view()


def test_scene_look_ups_and_changes_make_new_scenes():
    lab = load_scene("lab20")
    assert lab.object("robot") is lab.robot and lab.reflector("mirror") is lab.reflectors[0]
    with pytest.raises(KeyError, match="no object 'hand'; objects are robot, mirror_frame"):
        lab.object("hand")
    with pytest.raises(KeyError, match="no reflector 'glass'; reflectors are mirror"):
        lab.reflector("glass")
    red = lab.with_reflector("mirror", color=(1.0, 0.0, 0.0))
    assert red.reflector("mirror").color == (1.0, 0.0, 0.0) and lab.reflector("mirror").color != (
        1.0,
        0.0,
        0.0,
    )
    assert red.content_key() != lab.content_key()
    assert replace(lab, camera=Camera()).content_key() == lab.content_key()
    assert lab.frame_count == 1 and lab.at_frame(7) is lab
    assert Scene("empty").robot is None


# --------------------------------------------------------------------------- animation


def test_interpolate_is_linear_between_keys_and_holds_outside():
    keys = [(2, 10.0), (6, 30.0)]
    assert [interpolate(keys, f) for f in (0, 2, 3, 6, 9)] == [10.0, 10.0, 15.0, 30.0, 30.0]
    vectors = [(0, (0.0, 0.0, 0.0)), (4, (4.0, -8.0, 2.0))]
    assert interpolate(vectors, 1) == (1.0, -2.0, 0.5)


def robot_angles_at(scene: Scene, frame: int) -> tuple[float, float, float]:
    """The joint angles of ``scene``'s robot at ``frame``, in degrees."""
    robot = scene.at_frame(frame).robot
    assert robot is not None
    return robot.angles


def test_robot_wave_holds_then_moves_its_joints_between_keyframes():
    scene = load_scene("robot_wave")
    assert scene.frame_count == 24
    still = [robot_angles_at(scene, f) for f in range(5)]
    assert still == [(-35.0, 30.0, -75.0)] * 5
    assert robot_angles_at(scene, 8) == pytest.approx((-5.0, 20.0, -52.5))
    assert robot_angles_at(scene, 12) == (25.0, 10.0, -30.0)
    assert robot_angles_at(scene, 23) == (-60.0, 40.0, -100.0)
    assert scene.at_frame(8).camera == scene.camera
    assert scene.at_frame(8).reflectors == scene.reflectors
    for frame in (-1, 24):
        with pytest.raises(ValueError, match=r"outside the animation's 0\.\.\.23"):
            scene.at_frame(frame)
