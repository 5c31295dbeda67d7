"""The three rasterised mirrors against the ray-traced ground truth, on llvmpipe.

The scene is the shipped ``lab20``, its mirror's technique chosen with the ``method``
option and drawn by the one renderer (the ``scene_renderer`` fixture); the truth is
:func:`mirrorlab.raytrace.trace_scene` of the same scene.

Tolerance throughout: a pixel agrees when every channel is within 10/255 of
the tracer's. Both sample pixel centres with the same shading, so the exact
techniques (reflected, stencil) agree almost everywhere; what is left is
texture filtering and silhouette pixels.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.data import data_path
from mirrorlab.gl.context import check_gl_errors
from mirrorlab.options import apply_options
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.model import Camera, MeshObject, PlanarReflector, Scene, Transform
from mirrorlab.scene.robot import hand_center
from mirrorlab.views import camera_view, reflected_capture_view
from tests.gl.frames import draw
from tests.imagecheck import assert_region_close, red_dominant, save_failure, share_within
from tests.scenekit import vec3

SIZE = 160
MIRROR_CENTER = np.array([-7.0, 1.0, -2.0])
HAND_MESH = data_path("models") / "hand.obj"


def viewer_at(degrees: float, distance: float, fovy: float = 45.0, height: float = 0.0):
    """A viewer ``distance`` from the mirror's centre, ``degrees`` off its normal (turned
    about the vertical towards +z), looking at the centre."""
    angle = math.radians(degrees)
    eye = MIRROR_CENTER + distance * np.array([math.cos(angle), height, math.sin(angle)])
    return Camera(eye=vec3(eye), target=vec3(MIRROR_CENTER), fovy=fovy)


def lab(camera: Camera | None = None, angles=None) -> Scene:
    """The shipped lab scene seen by ``camera``, its robot posed at ``angles``."""
    scene = mirrorlab.load_scene("lab20")
    if angles is not None:
        scene = scene.with_angles(angles)
    return scene if camera is None else replace(scene, camera=camera)


def render(renderer, scene, method, capture="copy", env_size=None, size=SIZE):
    """``scene`` with its mirror drawn by ``method``: the frame, the capture texture the
    frame used (None for stencil) and the frame's stats."""
    configured = apply_options(scene, {"method": method, "capture": capture, "env_size": env_size})
    image, stats = draw(renderer, configured, (size, size))
    check_gl_errors(f"{method} frame")
    environment = None
    (mirror_draw,) = stats.plan.top.draws
    if mirror_draw.mode == "texture":
        environment = renderer.pass_for("mirror").captures.texture(mirror_draw.slot).read()
    return image, environment, stats


def trace(scene, size=SIZE):
    return trace_scene(scene, (size, size))


OFF_NORMAL = {
    "30 deg": viewer_at(30, 16),
    "60 deg": viewer_at(60, 16),
    "75 deg low": viewer_at(-75, 14, height=-0.3),
    "close": viewer_at(15, 3, fovy=60, height=0.1),
    "default": Camera(),
}


@pytest.mark.parametrize("method", ["reflected", "stencil"])
@pytest.mark.parametrize("view", sorted(OFF_NORMAL))
def test_exact_methods_agree_with_the_ray_tracer(scene_renderer, method, view):
    """99% of mirror pixels within 10/255 (texture size = frame size for reflected)."""
    scene = lab(OFF_NORMAL[view])
    truth = trace(scene)
    assert truth.reflective_mask.sum() > 200, "the mirror should fill part of the frame"
    image, _, _ = render(scene_renderer, scene, method)
    assert_region_close(
        f"{method}_{view}",
        image,
        truth.to_uint8(),
        truth.reflective_mask,
        channel_tolerance=10,
        min_fraction_within=0.99,
    )
    # Outside the mirror every method draws the same scene as the tracer.
    assert share_within(image, truth.to_uint8(), ~truth.reflective_mask, 10) > 0.995


def test_ortho_is_right_head_on_from_afar_and_wrong_at_sixty_degrees(scene_renderer):
    far = lab(viewer_at(0, 80, fovy=8))
    truth = trace(far)
    image, _, _ = render(scene_renderer, far, "ortho")
    assert_region_close(
        "ortho_head_on_far",
        image,
        truth.to_uint8(),
        truth.reflective_mask,
        channel_tolerance=10,
        min_fraction_within=0.98,
    )
    oblique = lab(viewer_at(60, 16))
    truth = trace(oblique)
    image, _, _ = render(scene_renderer, oblique, "ortho")
    within = share_within(image, truth.to_uint8(), truth.reflective_mask, 10)
    assert within < 0.95, f"ortho at 60 deg should visibly differ, but {within:.1%} agree"


def mirror_point_of_pixel(camera: Camera, xy: tuple[float, float], size: int) -> np.ndarray:
    """Where the viewing ray through pixel ``xy`` (x right, y down) meets the plane x = -7."""
    inverse = np.linalg.inv(camera.projection(1.0) @ camera.view())
    ndc = np.array([xy[0] / size * 2 - 1, 1 - xy[1] / size * 2])
    near, far = (inverse @ np.array([*ndc, z, 1.0]) for z in (-1.0, 1.0))
    near, far = near[:3] / near[3], far[:3] / far[3]
    step = (-7.0 - near[0]) / (far[0] - near[0])
    return near + step * (far - near)


@pytest.mark.parametrize("degrees", [-20, -35])
def test_ortho_displaces_the_reflected_hand_by_d_tan_theta(scene_renderer, degrees):
    """The ortho capture shows the hand where a perpendicular from it meets the mirror;
    the true reflection (ray tracer) is d * tan(theta) further along the mirror, for a
    viewer far away at theta off the normal and the hand d in front of the glass."""
    camera = viewer_at(degrees, 90, fovy=9)
    scene = lab(camera, angles=(-60.0, 40.0, -70.0))  # hand 6.1 in front of the glass
    assert scene.robot is not None
    hand = hand_center(scene.robot)
    distance = hand[0] + 7.0
    truth = trace(scene, size=256)
    image, _, _ = render(scene_renderer, scene, "ortho", size=256)
    centres = {}
    for name, picture in (("ortho", image), ("truth", truth.to_uint8())):
        red = red_dominant(picture) & truth.reflective_mask
        if red.sum() < 10:
            save_failure(f"displacement_{degrees}_{name}", image=picture)
            pytest.fail(f"no reflected hand found in the {name} image")
        rows, cols = np.nonzero(red)
        centres[name] = mirror_point_of_pixel(camera, (cols.mean() + 0.5, rows.mean() + 0.5), 256)
    foot = np.array([-7.0, hand[1], hand[2]])
    assert np.linalg.norm(centres["ortho"] - foot) < 0.25
    shift = np.linalg.norm(centres["truth"] - centres["ortho"])
    expected = distance * math.tan(math.radians(abs(degrees)))
    assert shift == pytest.approx(expected, rel=0.12), (distance, degrees)


def scene_with_intruders(camera: Camera) -> Scene:
    """The lab scene plus a green box straddling the mirror plane and a magenta box wholly
    behind it (both from the hand mesh, a box, scaled up)."""
    scene = lab(camera)
    straddler = MeshObject(
        "straddler",
        HAND_MESH,
        Transform(position=(-7.0, -1.0, -4.0), scale=(2.5, 2.5, 2.5)),
        color=(0.1, 0.9, 0.1),
    )
    behind = MeshObject(
        "behind",
        HAND_MESH,
        Transform(position=(-9.5, 1.0, -1.0), scale=(3.0, 3.0, 3.0)),
        color=(0.9, 0.1, 0.9),
    )
    return replace(scene, objects=(*scene.objects, straddler, behind))


def magenta(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., i].astype(int) for i in range(3))
    return (r > 2 * g + 20) & (b > 2 * g + 20)


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
def test_nothing_behind_the_mirror_shows_in_its_reflection(scene_renderer, method):
    scene = scene_with_intruders(viewer_at(40, 14))
    truth = trace(scene)
    mask = truth.reflective_mask
    image, _, _ = render(scene_renderer, scene, method)
    behind = magenta(image) & mask
    if behind.any():
        save_failure(f"behind_{method}", image=image, truth=truth.to_uint8())
    assert not behind.any(), f"{int(behind.sum())} magenta pixels in the mirror"
    if method != "ortho":
        # The straddling box's front half is reflected, its back half is not.
        assert_region_close(
            f"straddler_{method}",
            image,
            truth.to_uint8(),
            mask,
            channel_tolerance=10,
            min_fraction_within=0.99,
        )
        green = (image[..., 1] > 2 * image[..., 0].astype(int) + 20) & mask
        assert green.sum() > 20, "the straddling box's front half should be reflected"


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
def test_a_viewer_behind_the_mirror_sees_only_its_backing(scene_renderer, method):
    scene = lab(Camera(eye=(-15.0, 2.0, -1.0), target=(-7.0, 1.0, -2.0)))
    truth = trace(scene)
    assert not truth.reflective_mask.any()
    image, _, stats = render(scene_renderer, scene, method)
    # No capture is planned at all (nor skipped), and the mirror draws only its back.
    assert [p.name for p in stats.plan.passes] == ["camera"]
    assert [d.mode for d in stats.plan.top.draws] == ["back"]
    assert share_within(image, truth.to_uint8(), np.ones((SIZE, SIZE), bool), 10) > 0.995


@pytest.mark.parametrize("method", ["ortho", "reflected", "stencil"])
@pytest.mark.parametrize("offset", [0.0, 1e-7, 1e-3])
def test_a_viewer_in_or_next_to_the_mirror_plane_is_harmless(scene_renderer, method, offset):
    """No GL error, no exception, a normal-looking frame: in the plane the reflection
    is skipped; a hair in front, the oblique projection still has finite entries."""
    camera = Camera(eye=(-7.0 + offset, 1.5, 9.0), target=(-7.0 + offset, 1.0, -2.0))
    scene = lab(camera)
    mirror = scene.reflector("mirror")
    assert isinstance(mirror, PlanarReflector)
    capture = reflected_capture_view(camera_view(camera, (SIZE, SIZE)), mirror)
    if offset > 0:
        assert capture is not None
        assert np.all(np.isfinite(capture.projection))
        assert np.all(np.isfinite(capture.texture_matrix()))
    else:
        assert capture is None
    image, _, _ = render(scene_renderer, scene, method)
    truth = trace(scene)
    assert share_within(image, truth.to_uint8(), np.ones((SIZE, SIZE), bool), 10) > 0.99


def test_reflected_view_refuses_the_eye_in_the_mirror_plane():
    """No capture camera exists for an eye in the mirror's plane: the view says None
    (and the planner then draws no capture), never a matrix of NaN or infinity."""
    camera = Camera(eye=(-7.0, 1.5, 9.0), target=(-7.0, 1.0, -2.0))
    mirror = lab().reflector("mirror")
    assert isinstance(mirror, PlanarReflector)
    assert reflected_capture_view(camera_view(camera, (SIZE, SIZE)), mirror) is None


@pytest.mark.parametrize("method", ["ortho", "reflected"])
@pytest.mark.parametrize("env_size", [None, 96, 256])
def test_copy_and_fbo_capture_give_the_same_image(scene_renderer, method, env_size):
    scene = lab(viewer_at(35, 15))
    copied, copied_env, _ = render(scene_renderer, scene, method, "copy", env_size)
    drawn, drawn_env, _ = render(scene_renderer, scene, method, "fbo", env_size)
    expected_side = env_size or SIZE
    assert copied_env is not None and drawn_env is not None
    assert copied_env.shape == drawn_env.shape == (expected_side, expected_side, 3)
    assert np.array_equal(copied_env, drawn_env)
    assert np.array_equal(copied, drawn)


def test_a_larger_reflected_texture_is_closer_to_the_truth(scene_renderer):
    scene = lab(viewer_at(30, 16))
    truth = trace(scene)
    shares = []
    for env_size in (32, 64, SIZE):
        image, _, _ = render(scene_renderer, scene, "reflected", env_size=env_size)
        shares.append(share_within(image, truth.to_uint8(), truth.reflective_mask, 10))
    assert shares[0] < shares[1] < shares[2], shares


@pytest.mark.parametrize("capture", ["copy", "fbo"])
def test_an_ortho_capture_the_size_of_its_footprint_shows_what_the_window_sized_one_does(
    scene_renderer, capture
):
    """``texture_size = "footprint"``: the capture texture takes the planned size (the
    glass's pixel rectangle, in whole steps), and the mirror shows what it shows with the
    window-sized texture (ortho's error is its geometry's), to within filtering: 97% of
    its pixels within 24/255, the red hand among them."""
    scene = lab(viewer_at(30, 16))
    window, window_env, _ = render(scene_renderer, scene, "ortho", capture)
    footprint, footprint_env, stats = render(
        scene_renderer, scene, "ortho", capture, env_size="footprint"
    )
    (step,) = [p for p in stats.plan.ran if p.name == "capture"]
    width, height = step.views[0].view.size
    assert footprint_env.shape == (height, width, 3) and window_env.shape == (SIZE, SIZE, 3)
    assert width < SIZE and height < SIZE
    mask = trace(scene).reflective_mask
    assert red_dominant(footprint[mask]).sum() > 20
    assert_region_close(f"ortho_footprint_{capture}", footprint, window, mask, 24, 0.97)
