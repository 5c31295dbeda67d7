"""Frame planning: capture only when the scene, the size or the side of the mirror call for it."""

import pytest

from mirrorlab.plan import CaptureState, mirror_in_view, plan_frame
from mirrorlab.scene.robot import Camera, build_lab_scene

FRONT = Camera(eye=(10, 4, 3), target=(-7, 1, -2))
BEHIND = Camera(eye=(-12, 2, -2), target=(0, 0, 0))
IN_PLANE = Camera(eye=(-7, 2, 10), target=(-7, 1, -2))


def capture_of(plan):
    (capture,) = [p for p in plan if p.name == "capture"]
    return capture


def test_first_frame_captures_then_reuses_until_the_scene_changes():
    scene = build_lab_scene()
    assert capture_of(plan_frame(scene, FRONT, (64, 64), CaptureState())).runs
    done = CaptureState(scene.graph.revision, (64, 64))
    same = capture_of(plan_frame(scene, FRONT, (64, 64), done))
    assert not same.runs and "nothing changed" in same.reason
    other_viewer = Camera(eye=(9, 1, -1), target=(-7, 1, -2))
    assert not capture_of(plan_frame(scene, other_viewer, (64, 64), done)).runs
    assert capture_of(plan_frame(scene, FRONT, (80, 64), done)).runs
    scene.set_angles((0, 0, 0))
    changed = capture_of(plan_frame(scene, FRONT, (64, 64), done))
    assert changed.runs and "scene changed" in changed.reason


def test_no_capture_when_the_viewer_is_behind_or_in_the_mirror_plane():
    scene = build_lab_scene()
    for camera in (BEHIND, IN_PLANE):
        capture = capture_of(plan_frame(scene, camera, (64, 64), CaptureState()))
        assert not capture.runs and "behind" in capture.reason


def test_forced_capture_and_camera_pass_always_run():
    scene = build_lab_scene()
    done = CaptureState(scene.graph.revision, (64, 64))
    plan = plan_frame(scene, BEHIND, (64, 64), done, force_capture=True)
    assert [p.name for p in plan] == ["capture", "camera"] and all(p.runs for p in plan)


def plan_names(plan):
    return [(p.name, p.runs) for p in plan]


def test_reflected_capture_follows_the_viewer_and_the_scene():
    scene = build_lab_scene()
    first = plan_frame(scene, FRONT, (64, 64), CaptureState(), method="reflected")
    assert plan_names(first) == [("reflected-capture", True), ("camera", True)]
    done = CaptureState(scene.graph.revision, (64, 64), FRONT)
    assert not plan_frame(scene, FRONT, (64, 64), done, method="reflected")[0].runs
    moved = Camera(eye=(9, 1, -1), target=(-7, 1, -2))
    again = plan_frame(scene, moved, (64, 64), done, method="reflected")[0]
    assert again.runs and "viewer moved" in again.reason
    for camera in (BEHIND, IN_PLANE):
        skipped = plan_frame(scene, camera, (64, 64), CaptureState(), method="reflected")[0]
        assert not skipped.runs and "behind" in skipped.reason


def test_stencil_needs_no_capture_and_reflects_only_when_the_front_shows():
    scene = build_lab_scene()
    assert plan_names(plan_frame(scene, FRONT, (64, 64), CaptureState(), method="stencil")) == [
        ("camera", True), ("stencil-reflection", True)]
    behind = plan_frame(scene, BEHIND, (64, 64), CaptureState(), method="stencil")
    assert plan_names(behind) == [("camera", True), ("stencil-reflection", False)]


def test_no_capture_while_the_mirror_is_out_of_view():
    scene = build_lab_scene()
    # In front of the mirror but looking away from it, along +x.
    away = Camera(eye=(0, 1, 0), target=(10, 1, 0))
    assert not mirror_in_view(scene, away, 1.0)
    assert mirror_in_view(scene, FRONT, 1.0)
    for method in ("ortho", "reflected"):
        capture = plan_frame(scene, away, (64, 64), CaptureState(), method=method)[0]
        assert not capture.runs and "out of view" in capture.reason


def test_unknown_method_is_refused_with_the_names():
    with pytest.raises(ValueError, match="ortho, reflected, stencil"):
        plan_frame(build_lab_scene(), FRONT, (64, 64), CaptureState(), method="magic")
