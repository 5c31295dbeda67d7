"""The lab's two passes on real Mesa llvmpipe (headless EGL), checked against geometry
worked out in numpy from the lab's numbers."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab import math3d
from mirrorlab.gl.context import check_gl_errors
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer, read_pixels
from mirrorlab.renderer import Renderer
from mirrorlab.scene.graph import SceneGraph
from mirrorlab.scene.robot import (
    DEFAULT_ANGLES,
    MIRROR_BACKING,
    Camera,
    LabScene,
    OrthoCapture,
    build_lab_scene,
    build_robot,
)
from tests.imagecheck import (
    mirror_image_point,
    mirror_mask,
    mirror_point_at,
    near,
    red_dominant,
    save_failure,
    viewer_matrix,
)

SIZE = 192
VIEWERS = {
    "default": Camera(),
    "high-right": Camera(eye=(6, 9, 11), target=(-7, 1, -2)),
    "from-left": Camera(eye=(8, 3, -12), target=(-6, 1, -2)),
}


def render(registry, scene, camera, size=(SIZE, SIZE)):
    target = Framebuffer(registry, *size)
    renderer = Renderer(registry, scene)
    stats = renderer.render(target, camera)
    return target.read(), renderer, stats


def test_capture_equals_a_direct_render_from_the_capture_camera(registry):
    scene = build_lab_scene()
    _, renderer, _ = render(registry, scene, Camera())
    captured = renderer.read_environment()
    # Draw the same scene from the capture camera into a fresh framebuffer and read it.
    direct_target = Framebuffer(registry, SIZE, SIZE)
    direct_target.bind()
    GL.glViewport(0, 0, SIZE, SIZE)
    GL.glClearColor(*scene.background, 1.0)
    GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
    GL.glEnable(GL.GL_DEPTH_TEST)
    renderer.drawer.draw(scene.capture.projection() @ scene.capture.view())
    direct = read_pixels(SIZE, SIZE)
    assert captured.shape == (SIZE, SIZE, 3)
    if not np.array_equal(captured, direct):
        save_failure("capture_vs_direct", captured=captured, direct=direct)
        pytest.fail("ENVIRONMENT texture differs from a direct render from the capture camera")


def test_capture_shows_the_hand_where_the_ortho_camera_puts_it(registry):
    scene = build_lab_scene()
    _, renderer, _ = render(registry, scene, Camera())
    env = renderer.read_environment()
    hand = scene.hand_center()
    left, right, bottom, top = scene.capture.extents[:4]
    s, t = (hand[2] - left) / (right - left), (hand[1] - bottom) / (top - bottom)
    xy = np.array([s * SIZE, (1 - t) * SIZE])  # texture t=1 is the top image row
    assert red_dominant(near(env, xy, 3)).any(), f"no hand at {xy} in the capture"
    assert not red_dominant(near(env, np.array([(1 - s) * SIZE, xy[1]]), 3)).any()


def test_the_mirror_never_appears_in_its_own_capture(registry):
    # The lab's capture camera sits exactly on the mirror, where clipping alone may hide
    # the quad; step it one unit back so that a capture that drew the mirror would show
    # it (and leave out the frame behind the mirror, which would then be in view).
    scene = LabScene(graph=SceneGraph(build_robot()))
    scene.set_angles(DEFAULT_ANGLES)
    scene.capture = OrthoCapture(eye=(-8.0, 0.0, 0.0), extents=(-6, 2, -3, 5, 0, 16))
    target = Framebuffer(registry, SIZE, SIZE)
    renderer = Renderer(registry, scene)
    renderer.render(target, Camera())
    # Paint the environment magenta; if the capture drew the mirror quad (which fills
    # the whole capture view at its near plane) the magenta would come back.
    magenta = np.zeros((SIZE, SIZE, 3), np.uint8)
    magenta[..., 0] = magenta[..., 2] = 255
    renderer.environment.bind(0)
    GL.glTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, SIZE, SIZE, GL.GL_RGB,
                       GL.GL_UNSIGNED_BYTE, magenta)
    renderer.render(target, Camera(), force_capture=True)
    env = renderer.read_environment()
    is_magenta = (env[..., 0] > 200) & (env[..., 1] < 60) & (env[..., 2] > 200)
    assert not is_magenta.any(), f"{int(is_magenta.sum())} magenta pixels in the capture"
    # Seen from the capture camera the mirror shows its back, and it would cover the
    # whole view: the background and the robot's hand must both still be there.
    background = np.round(np.array(scene.background) * 255)
    is_background = np.abs(env.astype(int) - background).max(axis=-1) <= 1
    assert is_background.mean() > 0.5, "the capture is covered by something (the mirror?)"
    assert red_dominant(env).any(), "the robot's hand is hidden in the capture"
    backing = np.round(np.array(MIRROR_BACKING) * 255)
    assert not (np.abs(env.astype(int) - backing).max(axis=-1) <= 1).any()


@pytest.mark.parametrize("viewer", sorted(VIEWERS))
def test_mirror_shows_the_robot_mirrored_not_flipped(registry, viewer):
    scene = build_lab_scene()
    camera = VIEWERS[viewer]
    image, _, _ = render(registry, scene, camera)
    vp = viewer_matrix(camera, SIZE, SIZE)
    hand = scene.hand_center()
    s, t = scene.mirror.texcoord_at(mirror_image_point(scene, hand))
    expected = math3d.project_to_pixels(vp, mirror_image_point(scene, hand), SIZE, SIZE)
    flipped_s = math3d.project_to_pixels(vp, mirror_point_at(scene, 1 - s, t), SIZE, SIZE)
    flipped_t = math3d.project_to_pixels(vp, mirror_point_at(scene, s, 1 - t), SIZE, SIZE)
    # A flipped position is only telling where the mirror is visible there: not where
    # the robot itself stands in front of it on screen.
    mask = mirror_mask(scene, camera, SIZE, SIZE, inset_px=3)
    real_hand = math3d.project_to_pixels(vp, hand, SIZE, SIZE)
    checks = {name: xy for name, xy in (("s", flipped_s), ("t", flipped_t))
              if np.linalg.norm(xy[:2] - real_hand[:2]) > 12
              and mask[int(xy[1]) % SIZE, int(xy[0]) % SIZE]}
    assert checks, f"{viewer}: no flipped position is visible in the mirror to check"
    found = red_dominant(near(image, expected, 2)).any()
    wrong = [name for name, xy in checks.items() if red_dominant(near(image, xy, 2)).any()]
    if not found or wrong:
        save_failure(f"mirrored_{viewer}", frame=image)
    assert found, f"{viewer}: no reflected hand at pixel {expected[:2]}"
    assert not wrong, f"{viewer}: hand appears where a flip in {wrong} would put it"


def test_changing_a_joint_changes_the_robot_and_its_reflection(registry):
    scene = build_lab_scene()
    camera = Camera()
    before, renderer, _ = render(registry, scene, camera)
    target = Framebuffer(registry, SIZE, SIZE)
    scene.set_angles((scene.angles[0] + 40, *scene.angles[1:]))
    stats = renderer.render(target, camera)
    after = target.read()
    assert "capture" in stats.ran
    changed = np.abs(after.astype(int) - before.astype(int)).max(axis=-1) > 24
    in_mirror = mirror_mask(scene, camera, SIZE, SIZE)
    assert changed[in_mirror].sum() > 100, "the reflection did not follow the joint"
    assert changed[~in_mirror].sum() > 100, "the robot itself did not move"
    # and the reflected hand moved to where the new pose puts it
    hand_px = math3d.project_to_pixels(viewer_matrix(camera, SIZE, SIZE),
                                       mirror_image_point(scene, scene.hand_center()),
                                       SIZE, SIZE)
    assert red_dominant(near(after, hand_px, 2)).any()


def test_capture_is_reused_while_nothing_changes_and_the_frame_stays_right(registry):
    scene = build_lab_scene()
    camera = Camera()
    first, renderer, stats = render(registry, scene, camera)
    assert stats.ran == ["capture", "camera"]
    target = Framebuffer(registry, SIZE, SIZE)
    again = renderer.render(target, camera)
    assert again.ran == ["camera"]
    assert np.array_equal(target.read(), first)


def test_viewer_behind_the_mirror_sees_its_backing_and_no_capture_runs(registry):
    scene = build_lab_scene()
    camera = Camera(eye=(-16, 2, -2), target=(0, 1, -2))
    image, _, stats = render(registry, scene, camera)
    assert stats.ran == ["camera"]
    mask = mirror_mask(scene, camera, SIZE, SIZE, inset_px=3)
    assert mask.sum() > 500
    assert not red_dominant(image[mask]).any()


def test_frame_leaves_no_gl_error_and_counts_its_draw_calls(registry):
    scene = build_lab_scene()
    _, _, stats = render(registry, scene, Camera())
    check_gl_errors("a lab frame")
    parts = sum(1 for n in scene.graph.nodes() if n.mesh)
    assert stats.draw_calls == parts * 2 + 1  # capture, camera, mirror quad


def test_non_square_frames_capture_at_the_frame_size(registry):
    scene = build_lab_scene()
    image, renderer, _ = render(registry, scene, Camera(), size=(160, 96))
    assert image.shape == (96, 160, 3)
    assert renderer.read_environment().shape == (96, 160, 3)


def test_renderer_release_frees_every_gl_object_it_made(gl_context):
    before = len(gl_context.resources)
    renderer = Renderer(gl_context.resources, build_lab_scene())
    made = len(gl_context.resources) - before
    assert made >= 8  # programs, meshes, METAL, ENVIRONMENT, mirror quad
    renderer.release()
    renderer.release()  # idempotent
    assert len(gl_context.resources) == before
