"""Planar mirrors that move: keyframes set a mirror's position (its centre) and rotation
(about its centre, from where its scene file puts it), its corners and its ortho camera
follow; the plan captures it again when it moves and hides it when it leaves the view."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.plan import TextureState, plan_frame
from mirrorlab.scene.loader import SceneError, dumps, loads
from mirrorlab.scene.model import PlanarReflector

TURNING = """
name = "turning_mirror"
max_bounces = 1
background = {{ sky = "procedural" }}
[camera]
eye = [12.0, 5.0, 9.0]
target = [-3.5, 1.0, -2.0]
[[objects]]
type = "robot"
[[reflectors]]
name = "mirror"
technique = "{technique}"
center = [-7.0, 1.0, -2.0]
normal = [1.0, 0.0, 0.0]
width = 8.0
height = 8.0
[animation]
frames = 8
[[animation.keyframes]]
frame = 0
reflectors.mirror = {{ position = [-7.0, 1.0, -40.0] }}
[[animation.keyframes]]
frame = 2
reflectors.mirror = {{ position = [-7.0, 1.0, -2.0], rotation = [0.0, 0.0, 0.0] }}
[[animation.keyframes]]
frame = 3
reflectors.mirror = {{ position = [-7.0, 1.0, -2.0], rotation = [0.0, 0.0, 0.0] }}
[[animation.keyframes]]
frame = 5
reflectors.mirror = {{ position = [-7.0, 1.0, -2.0], rotation = [0.0, -35.0, 0.0] }}
[[animation.keyframes]]
frame = 7
reflectors.mirror = {{ position = [-7.0, 1.0, 60.0], rotation = [20.0, -60.0, 0.0] }}
"""
"""A mirror that slides into view (frames 0-2), holds (2-3), turns about the vertical
(3-5), then turns further and slides out of view (5-7)."""


def turning(technique: str = "reflected"):
    return loads(TURNING.format(technique=technique))


def mirror_at(scene, frame: int) -> PlanarReflector:
    mirror = scene.at_frame(frame).reflector("mirror")
    assert isinstance(mirror, PlanarReflector)
    return mirror


def test_keyframes_move_and_turn_a_planar_mirror_and_its_corners_follow():
    scene = turning()
    rest = scene.reflector("mirror")
    assert np.allclose(mirror_at(scene, 2).corner_array, rest.corner_array)
    assert np.allclose(mirror_at(scene, 0).center, (-7.0, 1.0, -40.0))
    assert np.allclose(mirror_at(scene, 1).center, (-7.0, 1.0, -21.0))
    turned = mirror_at(scene, 5)
    angle = np.radians(35.0)
    assert np.allclose(turned.center, rest.center)
    assert np.allclose(turned.normal, (np.cos(angle), 0.0, np.sin(angle)))
    # a rigid turn: the same size and shape
    edges = np.linalg.norm(
        np.diff(turned.corner_array, axis=0, append=turned.corner_array[:1]), axis=1
    )
    assert np.allclose(edges, 8.0)
    halfway = mirror_at(scene, 4)
    assert np.allclose(halfway.normal, (np.cos(angle / 2), 0.0, np.sin(angle / 2)))


def test_an_ortho_mirrors_camera_follows_it():
    scene = turning("ortho")
    for frame in range(scene.frame_count):
        mirror = mirror_at(scene, frame)
        capture = mirror.ortho_capture
        forward = np.subtract(capture.target, capture.eye)
        assert np.allclose(forward / np.linalg.norm(forward), mirror.normal)
        assert np.allclose(mirror.texcoords(), [[0, 0], [0, 1], [1, 1], [1, 0]], atol=1e-9)
    document = TURNING.format(technique="ortho").replace(
        "height = 8.0",
        "height = 8.0\n[reflectors.ortho]\neye = [-7.0, 1.0, -2.0]\n"
        "target = [0.0, 1.0, -2.0]\nup = [0.0, 1.0, 0.0]\n"
        "extents = [-4.0, 4.0, -4.0, 4.0, 0.0, 15.0]",
    )
    explicit = loads(document)
    moved = mirror_at(explicit, 5)
    assert moved.ortho is not None
    assert np.allclose(moved.ortho.eye, moved.center)
    forward = np.subtract(moved.ortho.target, moved.ortho.eye)
    assert np.allclose(forward / np.linalg.norm(forward), moved.normal)


def test_a_moving_mirror_scene_round_trips_at_every_frame():
    scene = turning()
    again = loads(dumps(scene))
    assert again == scene
    for frame in range(scene.frame_count):
        assert again.at_frame(frame) == scene.at_frame(frame)


def test_a_planar_mirror_takes_no_scale_keyframe():
    with pytest.raises(SceneError, match=r"keyframes\[0\].reflectors.mirror.scale: a planar"):
        loads(
            TURNING.format(technique="stencil").replace(
                "position = [-7.0, 1.0, -40.0]", "scale = [2.0, 2.0, 2.0]"
            )
        )


def test_the_plan_captures_a_moving_mirror_again_and_hides_it_out_of_view():
    scene = turning("reflected")
    state = TextureState()
    modes, captured = [], []
    for frame in range(scene.frame_count):
        plan = plan_frame(scene.at_frame(frame), (64, 64), state)
        for step in plan.ran:
            if step.reflector is not None:
                state.record(step)
        modes.append(plan.top.draws[0].mode)
        captured.append(any(p.name == "capture" and p.runs for p in plan.passes))
    assert modes[0] == "hidden" and modes[-1] in ("hidden", "back")
    assert not captured[0] and not captured[-1]
    assert modes[2:6] == ["texture"] * 4
    # frames 2 and 3 hold the mirror still (and the camera): the capture is kept
    assert captured[2] and not captured[3] and captured[4] and captured[5]
