"""``texture_size = "footprint"``: the lab's ortho capture sized to the mirror's footprint
on screen (rounded up to whole steps), in scene files and options, planned and
re-captured when its size changes. Numpy only."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from mirrorlab.options import OptionError, apply_options
from mirrorlab.plan import TextureState, plan_frame, reflector_footprint
from mirrorlab.scene.loader import SceneError, from_document, load_scene, scene_to_document
from mirrorlab.scene.model import FOOTPRINT_STEP, Camera
from mirrorlab.views import camera_view
from tests.scenekit import planar_reflector
from tests.twins import techniques_named

SIZE = (160, 120)


def footprint_lab(**changes):
    return apply_options(load_scene("lab20"), {"env_size": "footprint", **changes})


def capture_sizes(scene, state, size=SIZE) -> list[tuple[int, int]]:
    plan = plan_frame(scene, size, state)
    for step in plan.ran:
        if step.reflector is not None:
            state.record(step)
    return [p.views[0].view.size for p in plan.ran if p.name == "capture"]


def test_a_footprint_texture_is_the_glasss_pixel_rectangle_in_whole_steps():
    scene = footprint_lab()
    assert scene.reflector("mirror").texture_size == "footprint"
    (size,) = capture_sizes(scene, TextureState())
    bounds = reflector_footprint(scene.reflector("mirror"), camera_view(scene.camera, SIZE)).bounds
    assert bounds is not None
    assert size[0] % FOOTPRINT_STEP == 0 and size[1] % FOOTPRINT_STEP == 0
    assert bounds[2] <= size[0] < bounds[2] + FOOTPRINT_STEP
    assert bounds[3] <= size[1] < bounds[3] + FOOTPRINT_STEP
    assert size != SIZE  # not the window's size, as the lab's default capture is


def test_it_is_captured_again_when_its_size_changes_not_when_the_viewer_moves_a_hair():
    scene = footprint_lab()
    state = TextureState()
    first = capture_sizes(scene, state)
    eye = scene.camera.eye
    hair = replace(scene, camera=replace(scene.camera, eye=(eye[0] + 1e-3, eye[1], eye[2])))
    assert capture_sizes(hair, state) == []  # the same size: the same capture
    closer = replace(scene, camera=Camera(eye=(2.0, 2.0, 1.0), target=(-7.0, 1.0, -2.0)))
    (size,) = capture_sizes(closer, state)
    assert size[0] > first[0][0] and size[1] > first[0][1]


def test_scene_files_and_options_take_footprint_for_ortho_only():
    lab = load_scene("lab20")
    document = scene_to_document(lab)
    document["reflectors"][0]["texture_size"] = "footprint"
    scene = from_document(document, lab.source)
    assert planar_reflector(scene, "mirror").texture_size == "footprint"
    assert from_document(scene_to_document(scene), lab.source) == scene  # it round-trips
    document["reflectors"][0]["technique"] = "reflected"
    document["reflectors"][0].pop("ortho", None)
    owners = re.escape(techniques_named(lambda t: t.own_camera))
    assert "'ortho'" in owners
    with pytest.raises(
        SceneError,
        match=rf'reflectors\[0\]\.texture_size: "footprint" applies to {owners}.*not \'reflected\'',
    ):
        from_document(document, lab.source)
    document["reflectors"][0].update(technique="ortho", texture_size="huge")
    with pytest.raises(
        SceneError,
        match=r"reflectors\[0\]\.texture_size: expected a whole "
        r'number or "footprint", got \'huge\'',
    ):
        from_document(document, lab.source)
    # --method drops a footprint size the new technique cannot take, keeps a number;
    # asked for both at once, the size is refused with the option's name
    footprinted = footprint_lab()
    switched = apply_options(footprinted, {"method": "reflected"})
    assert planar_reflector(switched, "mirror").texture_size is None
    kept = apply_options(footprinted, {"method": "ortho"})
    assert planar_reflector(kept, "mirror").texture_size == "footprint"
    with pytest.raises(OptionError, match=rf"--env-size.*applies to {owners}"):
        footprint_lab(method="reflected")
    numbered = apply_options(load_scene("lab20"), {"env_size": 64, "method": "reflected"})
    assert planar_reflector(numbered, "mirror").texture_size == 64
    with pytest.raises(OptionError, match="--env-size"):
        apply_options(load_scene("lab20"), {"env_size": "tiny"})
