"""The lab's two passes on real Mesa llvmpipe (headless EGL), checked against geometry
worked out in numpy from the lab's numbers.

The scene is the shipped ``lab20`` (the robot, its METAL base, the mirror frame and the
``ortho`` mirror with the lab's capture camera), drawn by the one renderer
(:class:`mirrorlab.renderer.SceneRenderer`, the ``scene_renderer`` fixture).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab import math3d
from mirrorlab.gl.context import check_gl_errors
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.passes.base import apply_view_state
from mirrorlab.passes.planar import CapturingMirror
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import Camera, OrthoCapture, PlanarReflector, RobotObject, Scene
from mirrorlab.scene.robot import hand_center, scene_parts
from mirrorlab.views import ortho_capture_view
from tests.gl.frames import draw
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


def lab(camera: Camera | None = None) -> Scene:
    """The shipped lab scene, seen by ``camera`` (default: the scene's own)."""
    scene = mirrorlab.load_scene("lab20")
    return scene if camera is None else replace(scene, camera=camera)


def robot_and_mirror(scene: Scene) -> Scene:
    """``scene`` without the mirror's frame: the robot and the mirror alone."""
    return replace(scene, objects=tuple(o for o in scene.objects if isinstance(o, RobotObject)))


def mirror_of(scene: Scene) -> PlanarReflector:
    mirror = scene.reflector("mirror")
    assert isinstance(mirror, PlanarReflector)
    return mirror


def hand_of(scene: Scene) -> np.ndarray:
    assert scene.robot is not None
    return hand_center(scene.robot)


def capture_texture(renderer: SceneRenderer, stats) -> np.ndarray:
    """The capture texture the last frame's camera view drew the mirror with."""
    (mirror_draw,) = stats.plan.top.draws
    assert mirror_draw.mode == "texture", mirror_draw
    mirror_pass = renderer.pass_for("mirror")
    assert isinstance(mirror_pass, CapturingMirror)
    return mirror_pass.captures.texture(mirror_draw.slot).read()


def texcoord_at(mirror: PlanarReflector, point: np.ndarray) -> tuple[float, float]:
    """The ortho capture's texture coordinate (s, t) of the world ``point``."""
    capture = mirror.ortho_capture
    clip = math3d.transform_points(capture.projection() @ capture.view(), point)
    s, t = (clip[:2] / clip[3] + 1.0) / 2.0
    return float(s), float(t)


def test_capture_equals_a_direct_render_from_the_capture_camera(scene_renderer):
    scene = lab()
    _, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    assert stats.ran == ["capture:mirror", "camera"]
    captured = capture_texture(scene_renderer, stats)
    # Draw the same objects from the capture camera into a fresh framebuffer and read it.
    view = ortho_capture_view(mirror_of(scene), (SIZE, SIZE))
    direct_target = Framebuffer(scene_renderer.registry, SIZE, SIZE)
    try:
        direct_target.bind()
        GL.glViewport(0, 0, SIZE, SIZE)
        GL.glClearColor(*scene.background.color, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        apply_view_state(view, 0)
        scene_renderer.drawer.draw(scene, view)
        direct = direct_target.read()
    finally:
        direct_target.release()
    assert captured.shape == (SIZE, SIZE, 3)
    if not np.array_equal(captured, direct):
        save_failure("capture_vs_direct", captured=captured, direct=direct)
        pytest.fail("the capture texture differs from a direct render from the capture camera")


def test_capture_shows_the_hand_where_the_ortho_camera_puts_it(scene_renderer):
    scene = lab()
    _, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    env = capture_texture(scene_renderer, stats)
    hand = hand_of(scene)
    left, right, bottom, top = mirror_of(scene).ortho_capture.extents[:4]
    assert (left, right, bottom, top) == (-6, 2, -3, 5)  # the lab's numbers
    s, t = (hand[2] - left) / (right - left), (hand[1] - bottom) / (top - bottom)
    xy = np.array([s * SIZE, (1 - t) * SIZE])  # texture t=1 is the top image row
    assert red_dominant(near(env, xy, 3)).any(), f"no hand at {xy} in the capture"
    assert not red_dominant(near(env, np.array([(1 - s) * SIZE, xy[1]]), 3)).any()


def test_the_mirror_never_appears_in_its_own_capture(scene_renderer):
    # The lab's capture camera sits exactly on the mirror, where clipping alone may hide
    # the quad; step it one unit back so that a capture that drew the mirror would show
    # it (and leave out the frame behind the mirror, which would then be in view).
    scene = robot_and_mirror(lab()).with_reflector(
        "mirror",
        ortho=OrthoCapture(
            eye=(-8.0, 0.0, 0.0),
            target=(0.0, 0.0, 0.0),
            up=(0.0, 1.0, 0.0),
            extents=(-6, 2, -3, 5, 0, 16),
        ),
    )
    _, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    slot = stats.plan.top.draws[0].slot
    texture = scene_renderer.pass_for("mirror").captures.texture(slot)
    # Paint the capture texture magenta; if the capture drew the mirror quad (which fills
    # the whole capture view at its near plane) the magenta would come back.
    magenta = np.zeros((SIZE, SIZE, 3), np.uint8)
    magenta[..., 0] = magenta[..., 2] = 255
    texture.bind(0)
    GL.glTexSubImage2D(
        GL.GL_TEXTURE_2D, 0, 0, 0, SIZE, SIZE, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, magenta
    )
    _, again = draw(scene_renderer, scene, (SIZE, SIZE), use_plan=False)  # capture afresh
    assert again.ran == ["capture:mirror", "camera"]
    env = capture_texture(scene_renderer, again)
    is_magenta = (env[..., 0] > 200) & (env[..., 1] < 60) & (env[..., 2] > 200)
    assert not is_magenta.any(), f"{int(is_magenta.sum())} magenta pixels in the capture"
    # Seen from the capture camera the mirror shows its back, and it would cover the
    # whole view: the background and the robot's hand must both still be there.
    background = np.round(np.array(scene.background.color) * 255)
    is_background = np.abs(env.astype(int) - background).max(axis=-1) <= 1
    assert is_background.mean() > 0.5, "the capture is covered by something (the mirror?)"
    assert red_dominant(env).any(), "the robot's hand is hidden in the capture"
    backing = np.round(np.array(mirror_of(scene).backing) * 255)
    assert not (np.abs(env.astype(int) - backing).max(axis=-1) <= 1).any()


@pytest.mark.parametrize("viewer", sorted(VIEWERS))
def test_mirror_shows_the_robot_mirrored_not_flipped(scene_renderer, viewer):
    camera = VIEWERS[viewer]
    scene = lab(camera)
    mirror = mirror_of(scene)
    image, _ = draw(scene_renderer, scene, (SIZE, SIZE))
    vp = viewer_matrix(camera, SIZE, SIZE)
    hand = hand_of(scene)
    s, t = texcoord_at(mirror, mirror_image_point(mirror, hand))
    expected = math3d.project_to_pixels(vp, mirror_image_point(mirror, hand), SIZE, SIZE)
    flipped_s = math3d.project_to_pixels(vp, mirror_point_at(mirror, 1 - s, t), SIZE, SIZE)
    flipped_t = math3d.project_to_pixels(vp, mirror_point_at(mirror, s, 1 - t), SIZE, SIZE)
    # A flipped position is only telling where the mirror is visible there: not where
    # the robot itself stands in front of it on screen.
    mask = mirror_mask(mirror, camera, SIZE, SIZE, inset_px=3)
    real_hand = math3d.project_to_pixels(vp, hand, SIZE, SIZE)
    checks = {
        name: xy
        for name, xy in (("s", flipped_s), ("t", flipped_t))
        if np.linalg.norm(xy[:2] - real_hand[:2]) > 12
        and mask[int(xy[1]) % SIZE, int(xy[0]) % SIZE]
    }
    assert checks, f"{viewer}: no flipped position is visible in the mirror to check"
    found = red_dominant(near(image, expected, 2)).any()
    wrong = [name for name, xy in checks.items() if red_dominant(near(image, xy, 2)).any()]
    if not found or wrong:
        save_failure(f"mirrored_{viewer}", frame=image)
    assert found, f"{viewer}: no reflected hand at pixel {expected[:2]}"
    assert not wrong, f"{viewer}: hand appears where a flip in {wrong} would put it"


def test_changing_a_joint_changes_the_robot_and_its_reflection(scene_renderer):
    scene = lab()
    camera = scene.camera
    before, _ = draw(scene_renderer, scene, (SIZE, SIZE))
    assert scene.robot is not None
    moved = scene.with_angles((scene.robot.angles[0] + 40, *scene.robot.angles[1:]))
    after, stats = draw(scene_renderer, moved, (SIZE, SIZE))
    assert "capture:mirror" in stats.ran
    mirror = mirror_of(moved)
    changed = np.abs(after.astype(int) - before.astype(int)).max(axis=-1) > 24
    in_mirror = mirror_mask(mirror, camera, SIZE, SIZE)
    assert changed[in_mirror].sum() > 100, "the reflection did not follow the joint"
    assert changed[~in_mirror].sum() > 100, "the robot itself did not move"
    # and the reflected hand moved to where the new pose puts it
    hand_px = math3d.project_to_pixels(
        viewer_matrix(camera, SIZE, SIZE), mirror_image_point(mirror, hand_of(moved)), SIZE, SIZE
    )
    assert red_dominant(near(after, hand_px, 2)).any()


def test_capture_is_reused_while_nothing_changes_and_the_frame_stays_right(scene_renderer):
    scene = lab()
    first, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    assert stats.ran == ["capture:mirror", "camera"]
    again, again_stats = draw(scene_renderer, scene, (SIZE, SIZE))
    assert again_stats.ran == ["camera"]
    assert again_stats.skipped == ["capture:mirror"]
    assert np.array_equal(again, first)


def test_viewer_behind_the_mirror_sees_its_backing_and_no_capture_runs(scene_renderer):
    # Without the frame (which stands behind the glass and would hide it from here).
    camera = Camera(eye=(-16, 2, -2), target=(0, 1, -2))
    scene = robot_and_mirror(lab(camera))
    image, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    assert stats.ran == ["camera"] and stats.skipped == []
    assert [d.mode for d in stats.plan.top.draws] == ["back"]
    mask = mirror_mask(mirror_of(scene), camera, SIZE, SIZE, inset_px=3)
    assert mask.sum() > 500
    assert not red_dominant(image[mask]).any()
    backing = np.round(np.array(mirror_of(scene).backing) * 255)
    is_backing = np.abs(image[mask].astype(int) - backing).max(axis=-1) <= 1
    if not is_backing.all():
        save_failure("behind_the_mirror", frame=image)
    assert is_backing.all(), f"{int((~is_backing).sum())} mirror pixels are not its backing"


def test_frame_leaves_no_gl_error_and_counts_its_draw_calls(scene_renderer, registry):
    """One multi-draw a pass (the base's texture comes first, the untextured parts join
    its run) and the mirror quad; drawn a call a part, the parts each view can see: the
    mirror's frame lies behind the capture camera, and is culled there."""
    from mirrorlab.renderer import SceneRenderer

    scene = lab()
    _, stats = draw(scene_renderer, scene, (SIZE, SIZE))
    check_gl_errors("a lab frame")
    assert scene_renderer.drawer.draw_path == "packed"
    assert stats.draw_calls == 3  # capture, camera, mirror quad
    per_draw = SceneRenderer(registry, draw_path="per-draw")
    try:
        _, stats = draw(per_draw, scene, (SIZE, SIZE))
    finally:
        per_draw.release()
    check_gl_errors("a lab frame drawn a call a part")
    parts = len(scene_parts(scene))
    assert stats.draw_calls == (parts - 1) + parts + 1


def test_non_square_frames_capture_at_the_frame_size(scene_renderer):
    image, stats = draw(scene_renderer, lab(), (160, 96))
    assert image.shape == (96, 160, 3)
    assert capture_texture(scene_renderer, stats).shape == (96, 160, 3)


def test_renderer_release_frees_every_gl_object_it_made(gl_context):
    registry = gl_context.resources
    before = len(registry)
    renderer = SceneRenderer(registry)
    draw(renderer, lab(), (64, 64))
    made = len(registry) - before
    assert made >= 8  # programs, meshes, METAL, the capture texture, the mirror quad
    renderer.release()
    renderer.release()  # idempotent
    assert len(registry) == before
