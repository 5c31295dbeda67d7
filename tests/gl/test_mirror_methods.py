"""The three rasterised mirrors against the ray-traced ground truth, on llvmpipe.

Tolerance throughout: a pixel agrees when every channel is within 10/255 of
the tracer's. Both sample pixel centres with the same shading, so the exact
techniques (reflected, stencil) agree almost everywhere; what is left is
texture filtering and silhouette pixels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mirrorlab import math3d
from mirrorlab.gl.context import check_gl_errors
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.passes.reflected import reflected_view_projection
from mirrorlab.raytrace import lab_ray_scene
from mirrorlab.renderer import Renderer
from mirrorlab.scene.graph import Node, SceneGraph
from mirrorlab.scene.robot import Camera, LabScene, build_lab_scene, build_world
from tests.imagecheck import assert_region_close, red_dominant, save_failure, share_within

SIZE = 160
MIRROR_CENTER = np.array([-7.0, 1.0, -2.0])


def viewer_at(degrees: float, distance: float, fovy: float = 45.0, height: float = 0.0):
    """A viewer ``distance`` from the mirror's centre, ``degrees`` off its normal (turned
    about the vertical towards +z), looking at the centre."""
    angle = math.radians(degrees)
    eye = MIRROR_CENTER + distance * np.array([math.cos(angle), height, math.sin(angle)])
    return Camera(eye=tuple(eye), target=tuple(MIRROR_CENTER), fovy=fovy)


def render(registry, scene, camera, method, capture="copy", env_size=None, size=SIZE):
    framebuffer = Framebuffer(registry, size, size)
    renderer = Renderer(registry, scene, method, capture,
                        None if env_size is None else (env_size, env_size))
    stats = renderer.render(framebuffer, camera)
    image = framebuffer.read()
    environment = renderer.read_environment()
    check_gl_errors(f"{method} frame")
    renderer.release()
    framebuffer.release()
    return image, environment, stats


def trace(scene, camera, size=SIZE):
    return lab_ray_scene(scene).render(camera.view(), camera.projection(1.0), (size, size))


OFF_NORMAL = {
    "30 deg": viewer_at(30, 16),
    "60 deg": viewer_at(60, 16),
    "75 deg low": viewer_at(-75, 14, height=-0.3),
    "close": viewer_at(15, 3, fovy=60, height=0.1),
    "default": Camera(),
}


@pytest.mark.parametrize("method", ["reflected", "stencil"])
@pytest.mark.parametrize("view", sorted(OFF_NORMAL))
def test_exact_methods_agree_with_the_ray_tracer(registry, method, view):
    """99% of mirror pixels within 10/255 (texture size = frame size for reflected)."""
    scene, camera = build_lab_scene(), OFF_NORMAL[view]
    truth = trace(scene, camera)
    assert truth.reflective_mask.sum() > 200, "the mirror should fill part of the frame"
    image, _, _ = render(registry, scene, camera, method)
    assert_region_close(f"{method}_{view}", image, truth.to_uint8(), truth.reflective_mask,
                        channel_tolerance=10, min_fraction_within=0.99)
    # Outside the mirror every method draws the same scene as the tracer.
    assert share_within(image, truth.to_uint8(), ~truth.reflective_mask, 10) > 0.995


def test_ortho_is_right_head_on_from_afar_and_wrong_at_sixty_degrees(registry):
    scene = build_lab_scene()
    far = viewer_at(0, 80, fovy=8)
    truth = trace(scene, far)
    image, _, _ = render(registry, scene, far, "ortho")
    assert_region_close("ortho_head_on_far", image, truth.to_uint8(), truth.reflective_mask,
                        channel_tolerance=10, min_fraction_within=0.98)
    oblique = viewer_at(60, 16)
    truth = trace(scene, oblique)
    image, _, _ = render(registry, scene, oblique, "ortho")
    within = share_within(image, truth.to_uint8(), truth.reflective_mask, 10)
    assert within < 0.95, f"ortho at 60 deg should visibly differ, but {within:.1%} agree"


def mirror_point_of_pixel(camera: Camera, xy: np.ndarray, size: int) -> np.ndarray:
    """Where the viewing ray through pixel ``xy`` (x right, y down) meets the plane x = -7."""
    inverse = np.linalg.inv(camera.projection(1.0) @ camera.view())
    ndc = np.array([xy[0] / size * 2 - 1, 1 - xy[1] / size * 2])
    near, far = (inverse @ np.array([*ndc, z, 1.0]) for z in (-1.0, 1.0))
    near, far = near[:3] / near[3], far[:3] / far[3]
    step = (-7.0 - near[0]) / (far[0] - near[0])
    return near + step * (far - near)


@pytest.mark.parametrize("degrees", [-20, -35])
def test_ortho_displaces_the_reflected_hand_by_d_tan_theta(registry, degrees):
    """The ortho capture shows the hand where a perpendicular from it meets the mirror;
    the true reflection (ray tracer) is d * tan(theta) further along the mirror, for a
    viewer far away at theta off the normal and the hand d in front of the glass."""
    scene = build_lab_scene((-60.0, 40.0, -70.0))  # hand 6.1 in front of the glass
    hand = scene.hand_center()
    distance = hand[0] + 7.0
    camera = viewer_at(degrees, 90, fovy=9)
    truth = trace(scene, camera, size=256)
    image, _, _ = render(registry, scene, camera, "ortho", size=256)
    centres = {}
    for name, picture in (("ortho", image), ("truth", truth.to_uint8())):
        red = red_dominant(picture) & truth.reflective_mask
        if red.sum() < 10:
            save_failure(f"displacement_{degrees}_{name}", image=picture)
            pytest.fail(f"no reflected hand found in the {name} image")
        rows, cols = np.nonzero(red)
        centres[name] = mirror_point_of_pixel(camera, (cols.mean() + 0.5, rows.mean() + 0.5),
                                              256)
    foot = np.array([-7.0, hand[1], hand[2]])
    assert np.linalg.norm(centres["ortho"] - foot) < 0.25
    shift = np.linalg.norm(centres["truth"] - centres["ortho"])
    expected = distance * math.tan(math.radians(abs(degrees)))
    assert shift == pytest.approx(expected, rel=0.12), (distance, degrees)


def scene_with_intruders() -> LabScene:
    """The lab scene plus a green box straddling the mirror plane and a magenta box wholly
    behind it (both from the hand mesh, a box, scaled up)."""
    world = build_world()
    world.add(Node("straddler", offset=math3d.translate((-7.0, -1.0, -4.0))
                   @ math3d.scale((2.5, 2.5, 2.5)), mesh="hand", color=(0.1, 0.9, 0.1)))
    world.add(Node("behind", offset=math3d.translate((-9.5, 1.0, -1.0))
                   @ math3d.scale((3.0, 3.0, 3.0)), mesh="hand", color=(0.9, 0.1, 0.9)))
    scene = LabScene(graph=SceneGraph(world))
    scene.set_angles((-35.0, 30.0, -75.0))
    return scene


def magenta(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., i].astype(int) for i in range(3))
    return (r > 2 * g + 20) & (b > 2 * g + 20)


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
def test_nothing_behind_the_mirror_shows_in_its_reflection(registry, method):
    scene = scene_with_intruders()
    camera = viewer_at(40, 14)
    truth = trace(scene, camera)
    mask = truth.reflective_mask
    image, _, _ = render(registry, scene, camera, method)
    behind = magenta(image) & mask
    if behind.any():
        save_failure(f"behind_{method}", image=image, truth=truth.to_uint8())
    assert not behind.any(), f"{int(behind.sum())} magenta pixels in the mirror"
    if method != "ortho":
        # The straddling box's front half is reflected, its back half is not.
        assert_region_close(f"straddler_{method}", image, truth.to_uint8(), mask,
                            channel_tolerance=10, min_fraction_within=0.99)
        green = (image[..., 1] > 2 * image[..., 0].astype(int) + 20) & mask
        assert green.sum() > 20, "the straddling box's front half should be reflected"


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
def test_a_viewer_behind_the_mirror_sees_only_its_backing(registry, method):
    scene = build_lab_scene()
    camera = Camera(eye=(-15.0, 2.0, -1.0), target=(-7.0, 1.0, -2.0))
    truth = trace(scene, camera)
    assert not truth.reflective_mask.any()
    image, _, stats = render(registry, scene, camera, method)
    assert [p.name for p in stats.passes if not p.runs] == (
        ["stencil-reflection"] if method == "stencil" else [stats.passes[0].name])
    assert share_within(image, truth.to_uint8(), np.ones((SIZE, SIZE), bool), 10) > 0.995


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
@pytest.mark.parametrize("offset", [0.0, 1e-7, 1e-3])
def test_a_viewer_in_or_next_to_the_mirror_plane_is_harmless(registry, method, offset):
    """No GL error, no exception, a normal-looking frame: in the plane the reflection
    is skipped; a hair in front, the oblique projection still has finite entries."""
    scene = build_lab_scene()
    camera = Camera(eye=(-7.0 + offset, 1.5, 9.0), target=(-7.0 + offset, 1.0, -2.0))
    if offset > 0:
        matrix = reflected_view_projection(camera, scene.mirror, 1.0)
        assert np.all(np.isfinite(matrix))
    image, _, _ = render(registry, scene, camera, method)
    truth = trace(scene, camera)
    assert share_within(image, truth.to_uint8(), np.ones((SIZE, SIZE), bool), 10) > 0.99


def test_reflected_view_refuses_the_eye_in_the_mirror_plane():
    camera = Camera(eye=(-7.0, 1.5, 9.0), target=(-7.0, 1.0, -2.0))
    with pytest.raises(ValueError, match="eye"):
        reflected_view_projection(camera, build_lab_scene().mirror, 1.0)


@pytest.mark.parametrize("method", ["ortho", "reflected"])
@pytest.mark.parametrize("env_size", [None, 96, 256])
def test_copy_and_fbo_capture_give_the_same_image(registry, method, env_size):
    scene, camera = build_lab_scene(), viewer_at(35, 15)
    copied, copied_env, _ = render(registry, scene, camera, method, "copy", env_size)
    drawn, drawn_env, _ = render(registry, scene, camera, method, "fbo", env_size)
    expected_side = env_size or SIZE
    assert copied_env.shape == drawn_env.shape == (expected_side, expected_side, 3)
    assert np.array_equal(copied_env, drawn_env)
    assert np.array_equal(copied, drawn)


def test_a_larger_reflected_texture_is_closer_to_the_truth(registry):
    scene, camera = build_lab_scene(), viewer_at(30, 16)
    truth = trace(scene, camera)
    shares = []
    for env_size in (32, 64, SIZE):
        image, _, _ = render(registry, scene, camera, "reflected", env_size=env_size)
        shares.append(share_within(image, truth.to_uint8(), truth.reflective_mask, 10))
    assert shares[0] < shares[1] < shares[2], shares
