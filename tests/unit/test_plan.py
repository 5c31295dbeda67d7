"""Frame planning: capture only when the scene, the size or the side of the mirror call for it."""

from mirrorlab.plan import CaptureState, plan_frame
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
