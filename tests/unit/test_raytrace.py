"""The ground-truth tracer on tiny hand-made scenes whose answers are known exactly."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mirrorlab import math3d
from mirrorlab.raytrace import (
    MipChain,
    RayScene,
    RaySurface,
    mesh_surface,
    ray_scene,
    sample_bilinear,
    trace_scene,
)
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import Camera, Light
from mirrorlab.scene.robot import model_file
from tests.imagecheck import mirror_mask
from tests.scenekit import planar_reflector

LIGHT = np.array([0.0, 1.0, 0.0])
NO_LIGHT = [(LIGHT, (0.0, 0.0, 0.0))]


def quad(corners, color=(1.0, 1.0, 1.0), **extra) -> RaySurface:
    """A two-triangle quad; ``corners`` counter-clockwise seen from its front."""
    corners = np.asarray(corners, dtype=np.float64)
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    return RaySurface(
        vertices=corners,
        normals=np.tile(normal, (4, 1)),
        uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]),
        faces=np.array([[0, 1, 2], [0, 2, 3]]),
        color=color,
        **extra,
    )


FLOOR = [(-5, 0, 5), (5, 0, 5), (5, 0, -5), (-5, 0, -5)]  # faces +y
WALL = [(-5, -5, -3), (5, -5, -3), (5, 5, -3), (-5, 5, -3)]  # at z = -3, faces +z
MIRROR = [(-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)]  # at z = 2, faces -z


def test_a_lit_floor_has_the_rasterisers_lambert_colour():
    floor = quad(FLOOR, color=(0.5, 0.25, 1.0))
    light = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
    scene = RayScene([floor], [(light * 3.0, (0.7, 0.7, 0.7))], ambient=0.3, background=(0, 0, 0))
    colors, on_mirror = scene.trace(np.array([[0.0, 3.0, 0.0]]), np.array([[0.0, -1.0, 0.0]]))
    expected = np.array([0.5, 0.25, 1.0]) * (0.3 + 0.7 * light[1])
    np.testing.assert_allclose(colors[0], np.clip(expected, 0, 1), atol=1e-9)
    assert not on_mirror[0]


def test_lights_add_up_in_their_colours_and_light_from_behind_adds_nothing():
    floor = quad(FLOOR, color=(1.0, 1.0, 1.0))
    lights = [
        ((0, 1, 0), (0.2, 0.0, 0.0)),
        ((0, 1, 1), (0.0, 0.4, 0.0)),
        ((0, -1, 0), (0.0, 0.0, 0.9)),
    ]  # the last shines on the floor's back
    scene = RayScene([floor], lights, ambient=0.1, background=(0, 0, 0))
    colors, _ = scene.trace(np.array([[0.0, 3.0, 0.0]]), np.array([[0.0, -1.0, 0.0]]))
    np.testing.assert_allclose(colors[0], (0.1 + 0.2, 0.1 + 0.4 / np.sqrt(2), 0.1), atol=1e-9)


def test_a_mirror_shows_what_its_reflected_ray_meets():
    wall = quad(WALL, color=(0.0, 1.0, 0.0))
    mirror = quad(MIRROR, reflective=True, backing=(0.2, 0.2, 0.2))
    scene = RayScene([wall, mirror], NO_LIGHT, 1.0, background=(0, 0, 1.0))
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

    scene = RayScene([mirror], NO_LIGHT, 1.0, background=env)
    tilted = np.array([[0.0, 0.6, 0.8]])
    colors, _ = scene.trace(np.array([[0.0, -0.5, 0.0]]), tilted)
    reflected = np.array([0.0, 0.6, -0.8])  # the mirror's normal is along z
    np.testing.assert_allclose(colors[0], (reflected + 1) / 2, atol=1e-9)
    missed, _ = scene.trace(np.array([[0.0, 0.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    np.testing.assert_allclose(missed[0], (np.array([1.0, 0, 0]) + 1) / 2)


def test_no_bounces_left_means_the_mirror_is_a_plain_lit_surface():
    # As the rasteriser draws a reflector when max_bounces is used up: its colour, lit.
    wall = quad(WALL, color=(0.0, 1.0, 0.0))
    mirror = quad(MIRROR, color=(0.5, 0.25, 0.75), reflective=True)
    light = [((0.0, 0.0, -1.0), (0.2, 0.2, 0.2))]  # head on to the mirror's front (-z)
    scene = RayScene([wall, mirror], light, 0.5, background=(1.0, 0, 0))
    origin, ahead = np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]])
    colors, on_mirror = scene.trace(origin, ahead, bounces=0)
    np.testing.assert_allclose(colors[0], np.array([0.5, 0.25, 0.75]) * 0.7, atol=1e-9)
    assert on_mirror[0]
    np.testing.assert_allclose(scene.trace(origin, ahead, bounces=1)[0][0], (0, 0.5, 0))
    # Two facing mirrors: each bounce goes one reflection further.
    back = quad(
        [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1)], color=(0.0, 0.0, 1.0), reflective=True
    )  # at z = -1, facing +z
    pair = RayScene([mirror, back], light, 0.5, background=(1.0, 0, 0))
    first = pair.trace(origin, ahead, bounces=1)[0][0]
    np.testing.assert_allclose(first, (0.0, 0.0, 0.5))  # back's plain colour, unlit by -z
    np.testing.assert_allclose(
        pair.trace(origin, ahead, bounces=2)[0][0], np.array([0.5, 0.25, 0.75]) * 0.7, atol=1e-9
    )


def test_render_puts_a_centred_quad_in_the_middle_of_the_image():
    wall = quad(WALL, color=(1.0, 1.0, 1.0))
    scene = RayScene([wall], NO_LIGHT, 1.0, background=(0, 0, 0))
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
    np.testing.assert_allclose(
        half, 0.5 * (chain.sample(uv, np.array([1.0])) + chain.sample(uv, np.array([2.0])))
    )


def test_an_empty_scene_is_refused():
    with pytest.raises(ValueError, match="at least one surface"):
        RayScene([], NO_LIGHT, 1.0, (0, 0, 0))


def test_a_mesh_surface_is_moved_to_world_space_with_its_normals():
    model = math3d.translate((0.0, 5.0, 0.0)) @ math3d.scale((2.0, 1.0, 1.0))
    surface = mesh_surface(model_file("env_sphere"), model, color=(0.1, 0.2, 0.3))
    assert surface.color == (0.1, 0.2, 0.3) and not surface.reflective
    assert np.allclose(surface.vertices.mean(axis=0), (0.0, 5.0, 0.0), atol=0.05)
    assert np.allclose(np.abs(surface.vertices[:, 0] - 0.0).max(), 2.0, atol=0.01)
    # Normals follow the inverse transpose: on the stretched sphere they stay outward.
    outward = np.einsum("nd,nd->n", surface.normals, surface.vertices - (0.0, 5.0, 0.0))
    assert np.all(outward > 0)


def test_the_lab_scene_as_a_ray_scene():
    lab = load_scene("lab20")
    rays = ray_scene(lab)
    mirror = rays.surfaces[-1]
    assert mirror.reflective and np.allclose(
        mirror.vertices, planar_reflector(lab, "mirror").corners
    )
    assert mirror.backing == planar_reflector(lab, "mirror").backing
    assert len(rays.surfaces) == 7 + 1  # six robot parts and the frame, then the mirror
    (light,) = lab.lights
    assert np.allclose(rays.lights[0][1], np.asarray(light.color) * light.intensity)
    bright = ray_scene(replace(lab, lights=(Light(intensity=0.2), Light((0, -1, 0), 0.5))))
    assert len(bright.lights) == 2


def test_trace_scene_marks_each_pixel_with_the_reflector_it_meets_first():
    lab = load_scene("lab20")
    camera = Camera(eye=(6.0, 1.0, -2.0), target=(-7.0, 1.0, -2.0), fovy=60.0)
    scene = replace(lab, camera=camera, objects=())  # nothing in front of the glass
    width, height = 40, 30
    traced = trace_scene(scene, (width, height))
    inside = mirror_mask(planar_reflector(scene, "mirror"), camera, width, height, inset_px=1.0)
    assert inside.sum() > 150
    assert traced.reflector is not None
    assert np.all(traced.reflector[inside] == 0) and np.all(traced.reflective_mask[inside])
    assert np.all((traced.reflector == 0) == traced.reflective_mask)
    assert np.all(traced.reflector[~traced.reflective_mask] == -1)
    # The viewer sees the background reflected: the glass shows the background colour.
    assert np.allclose(traced.image[inside], lab.background.color)
    four = trace_scene(scene, (width, height), supersample=2)
    assert four.image.shape == (height, width, 3)
    # All four of a pixel's rays on the (convex) glass: so is the ray through its centre.
    assert np.all(four.reflective_mask[inside])
    assert not np.any(four.reflective_mask & ~traced.reflective_mask)
    with pytest.raises(ValueError, match="supersample must be a positive whole number"):
        trace_scene(scene, (4, 4), supersample=0)
