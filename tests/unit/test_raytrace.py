"""The ground-truth tracer on tiny hand-made scenes whose answers are known exactly."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.raytrace import MipChain, RayScene, RaySurface, sample_bilinear

LIGHT = np.array([0.0, 1.0, 0.0])


def quad(corners, color=(1.0, 1.0, 1.0), **extra) -> RaySurface:
    """A two-triangle quad; ``corners`` counter-clockwise seen from its front."""
    corners = np.asarray(corners, dtype=np.float64)
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    return RaySurface(vertices=corners, normals=np.tile(normal, (4, 1)),
                      uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
                      faces=np.array([[0, 1, 2], [0, 2, 3]]), color=color, **extra)


FLOOR = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]  # faces +y
WALL = [(-5, -5, -3), (5, -5, -3), (5, 5, -3), (-5, 5, -3)]  # at z = -3, faces +z
MIRROR = [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)]  # at z = 2, faces -z


def test_a_lit_floor_has_the_rasterisers_lambert_colour():
    floor = quad(FLOOR, color=(0.5, 0.25, 1.0))
    light = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
    scene = RayScene([floor], light, ambient=0.3, diffuse=0.7, background=(0, 0, 0))
    colors, on_mirror = scene.trace(np.array([[0.0, 3.0, 0.0]]), np.array([[0.0, -1.0, 0.0]]))
    expected = np.array([0.5, 0.25, 1.0]) * (0.3 + 0.7 * light[1])
    np.testing.assert_allclose(colors[0], np.clip(expected, 0, 1), atol=1e-9)
    assert not on_mirror[0]


def test_a_mirror_shows_what_its_reflected_ray_meets():
    wall = quad(WALL, color=(0.0, 1.0, 0.0))
    mirror = quad(MIRROR, reflective=True, backing=(0.2, 0.2, 0.2))
    scene = RayScene([wall, mirror], LIGHT, 1.0, 0.0, background=(0, 0, 1.0))
    # From z = 0 towards the mirror at z = 2: the reflection goes back towards the wall.
    colors, on_mirror = scene.trace(np.array([[0.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 1.0]]))
    np.testing.assert_allclose(colors[0], (0, 1, 0))
    assert on_mirror[0]
    # From behind (z = 5 looking at -z) the mirror shows its backing and is no mirror.
    colors, on_mirror = scene.trace(np.array([[0.0, 0.0, 5.0]]), np.array([[0.0, 0.0, -1.0]]))
    np.testing.assert_allclose(colors[0], (0.2, 0.2, 0.2))
    assert not on_mirror[0]


def test_escaping_rays_ask_the_environment_with_their_direction():
    mirror = quad(MIRROR, reflective=True)

    def env(directions):
        return (directions + 1.0) / 2.0

    scene = RayScene([mirror], LIGHT, 1.0, 0.0, background=env)
    tilted = np.array([[0.0, 0.6, 0.8]])
    colors, _ = scene.trace(np.array([[0.0, -0.5, 0.0]]), tilted)
    reflected = np.array([0.0, 0.6, -0.8])  # the mirror's normal is along z
    np.testing.assert_allclose(colors[0], (reflected + 1) / 2, atol=1e-9)
    missed, _ = scene.trace(np.array([[0.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    np.testing.assert_allclose(missed[0], (np.array([1.0, 0, 0]) + 1) / 2)


def test_no_bounces_left_means_the_mirror_shows_the_background():
    wall = quad(WALL, color=(0.0, 1.0, 0.0))
    mirror = quad(MIRROR, reflective=True)
    scene = RayScene([wall, mirror], LIGHT, 1.0, 0.0, background=(1.0, 0, 0))
    colors, _ = scene.trace(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]), bounces=0)
    np.testing.assert_allclose(colors[0], (1, 0, 0))


def test_render_puts_a_centred_quad_in_the_middle_of_the_image():
    from mirrorlab import math3d

    wall = quad(WALL, color=(1.0, 1.0, 1.0))
    scene = RayScene([wall], LIGHT, 1.0, 0.0, background=(0, 0, 0))
    view = math3d.look_at((0, 0, 10), (0, 0, 0), (0, 1, 0))
    projection = math3d.perspective(90.0, 1.0, 0.1, 100.0)
    image = scene.render(view, projection, (21, 21))
    # The wall spans x in [-5, 5] at 13 units: tan = 5/13, so 21 * (5/13) ~ 8 pixels
    # either side of the centre column are white.
    row = image.image[10, :, 0]
    white = np.nonzero(row > 0.5)[0]
    assert white.min() == 10 - 4 and white.max() == 10 + 4
    assert image.reflective_mask.sum() == 0


def test_bilinear_lookup_hits_texel_centres_exactly_and_wraps():
    texture = np.arange(4 * 4 * 3, dtype=np.uint8).reshape(4, 4, 3) * 5
    # Texel (column 1, GL row 2) has its centre at u = 1.5/4, v = 2.5/4; GL row 2 is
    # image row 4 - 1 - 2 = 1.
    value = sample_bilinear(texture, np.array([[1.5 / 4, 2.5 / 4]]))
    np.testing.assert_allclose(value[0], texture[1, 1] / 255.0)
    wrapped = sample_bilinear(texture, np.array([[1.5 / 4 + 3.0, 2.5 / 4 - 2.0]]))
    np.testing.assert_allclose(wrapped, value)


def test_mip_levels_are_box_averages_and_lod_blends_between_them():
    texture = np.zeros((4, 4, 3), dtype=np.uint8)
    texture[:2, :2] = 200
    chain = MipChain(texture)
    assert [lvl.shape[:2] for lvl in chain.levels] == [(4, 4), (2, 2), (1, 1)]
    np.testing.assert_allclose(chain.levels[2][0, 0], 50.0)
    uv = np.array([[0.5, 0.5]])
    np.testing.assert_allclose(chain.sample(uv, np.array([2.0])), [[50 / 255] * 3])
    half = chain.sample(uv, np.array([1.5]))
    np.testing.assert_allclose(half, 0.5 * (chain.sample(uv, np.array([1.0]))
                                            + chain.sample(uv, np.array([2.0]))))


def test_an_empty_scene_is_refused():
    with pytest.raises(ValueError, match="at least one surface"):
        RayScene([], LIGHT, 1.0, 0.0, (0, 0, 0))
