"""Which reflector is under the mouse, in numpy: a ray through the pixel against each
reflector; and window coordinates scaled to framebuffer pixels on a high-DPI screen."""

from __future__ import annotations

import numpy as np
import pytest

import mirrorlab
from mirrorlab import math3d
from mirrorlab.app.picking import framebuffer_pixel, pick_reflector, pixel_ray
from tests.scenekit import curved_reflector, planar_reflector


def project(scene, point, size):
    camera = scene.camera
    x, y, _ = math3d.project_to_pixels(
        camera.projection(size[0] / size[1]) @ camera.view(),
        np.asarray(point, dtype=np.float64),
        *size,
    )
    return float(x), float(y)


def test_the_ray_through_a_pixel_passes_through_what_projects_there():
    scene = mirrorlab.load_scene("lab20")
    size = (320, 200)
    point = np.array([-7.0, 2.0, -1.0])
    origin, direction = pixel_ray(scene.camera, size, project(scene, point, size))
    along = float((point - origin) @ direction)
    assert np.allclose(origin + along * direction, point, atol=1e-9)


@pytest.mark.parametrize("size", [(320, 240), (100, 300)])
def test_picks_the_nearest_reflector_under_the_pixel(size):
    scene = mirrorlab.load_scene("mirror_and_sphere")
    mirror, sphere = planar_reflector(scene, "mirror"), curved_reflector(scene, "sphere")
    # The sphere stands in front of the mirror's middle: it wins there.
    assert pick_reflector(scene, size, project(scene, sphere.center(), size)) == 1
    corner = mirror.corner_array[0] * 0.9 + mirror.center * 0.1
    assert pick_reflector(scene, size, project(scene, corner, size)) == 0
    outside = mirror.corner_array[0] * 1.3 - mirror.center * 0.3
    assert pick_reflector(scene, size, project(scene, outside, size)) is None
    assert pick_reflector(mirrorlab.load_scene("no_mirror"), size, (10, 10)) is None


def test_a_mirror_seen_from_behind_is_still_picked_by_its_quad():
    scene = mirrorlab.load_scene("mirror_behind_camera")
    assert pick_reflector(scene, (64, 64), (32, 32)) is None  # behind the viewer


def test_window_coordinates_become_framebuffer_pixels_on_a_high_dpi_screen():
    # A 400 x 300 window whose framebuffer has 2 x 2 pixels for each window unit.
    assert framebuffer_pixel((100.0, 75.0), (400, 300), (800, 600)) == (200.0, 150.0)
    assert framebuffer_pixel((100.0, 75.0), (400, 300), (400, 300)) == (100.0, 75.0)
    assert framebuffer_pixel((-1.0, 5.0), (400, 300), (800, 600)) is None
    assert framebuffer_pixel((400.0, 5.0), (400, 300), (800, 600)) is None
    assert framebuffer_pixel((5.0, 5.0), (0, 0), (0, 0)) is None
    # The same point of the scene is picked either way.
    scene = mirrorlab.load_scene("mirror_and_sphere")
    sphere = project(scene, curved_reflector(scene, "sphere").center(), (800, 600))
    cursor = (sphere[0] / 2, sphere[1] / 2)
    pixel = framebuffer_pixel(cursor, (400, 300), (800, 600))
    assert pixel is not None
    assert pick_reflector(scene, (800, 600), pixel) == 1
