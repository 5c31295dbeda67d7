"""Backgrounds in numpy (the procedural sky, pictures as sphere maps, cube faces) and the
shipped environment-map scenes, the cone and the chrome sphere."""

from __future__ import annotations

import shutil
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from mirrorlab import math3d
from mirrorlab.data import data_path
from mirrorlab.envmap import bake_cube_faces, bake_sphere_map, sphere_map_inverse
from mirrorlab.options import OptionError, apply_options
from mirrorlab.scene.backgrounds import (
    CUBE_FACE_FILES,
    SUN_DIRECTION,
    cube_faces_environment,
    environment_of,
    image_sampler,
    load_cube_faces,
    load_picture,
    sky_environment,
    sphere_image_environment,
)
from mirrorlab.scene.loader import SceneError, load_scene
from mirrorlab.scene.model import Background, CurvedReflector, MeshObject
from tests.scenekit import curved_reflector
from tests.twins import reflector_choices

SKY_CUBE = data_path("textures") / "sky_cube"
LAUNCH = data_path("textures") / "launch.png"

directions = st.tuples(*(st.floats(-1.0, 1.0, allow_nan=False),) * 3).filter(
    lambda v: np.linalg.norm(v) > 1e-3
)


# --------------------------------------------------------------------------- the sky


@settings(max_examples=200)
@given(directions)
def test_sky_is_a_finite_colour_in_range_for_any_direction(direction):
    colour = sky_environment(np.array([direction]))
    assert colour.shape == (1, 3)
    assert np.isfinite(colour).all() and colour.min() >= 0.0 and colour.max() <= 1.0


def test_sky_ignores_the_length_of_the_direction():
    d = np.random.default_rng(1).normal(size=(500, 3))
    assert np.allclose(sky_environment(d), sky_environment(d * 7.5))


def test_sky_has_its_features_where_they_were_put():
    sun = sky_environment(SUN_DIRECTION[None])[0]
    high_sky = sky_environment(np.array([[-0.3, 0.9, -0.3]]))[0]
    ground = sky_environment(np.array([[0.0, -1.0, 0.0]]))[0]
    assert sun.min() > 0.75  # near white
    assert high_sky[2] > high_sky[0] + 0.3  # blue
    assert ground[2] < 0.5  # earthy, not sky
    assert (
        np.abs(sky_environment(np.array([[1.0, 0.35, 0.2]]))[0] - (0.95, 0.15, 0.12)).max() < 0.02
    )  # the red balloon


def test_sky_is_smooth_at_the_scale_of_a_pixel():
    # soft edges keep one ray per pixel and a filtered lookup in agreement: neighbours
    # 0.002 rad apart (less than a pixel of any test render) differ by little
    rng = np.random.default_rng(7)
    d = rng.normal(size=(20000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    step = rng.normal(size=(20000, 3))
    step -= (step * d).sum(axis=1, keepdims=True) * d
    step *= 0.002 / np.linalg.norm(step, axis=1, keepdims=True)
    jump = np.abs(sky_environment(d + step) - sky_environment(d)).max(axis=1)
    assert np.percentile(jump, 99.9) < 0.15, np.percentile(jump, 99.9)


def test_each_background_kind_becomes_its_environment():
    assert environment_of(Background(kind="sky")) is sky_environment
    plain = environment_of(Background(kind="color", color=(0.25, 0.5, 0.75)))
    assert np.array_equal(plain(np.array([[1.0, 0, 0], [0, -1.0, 0]])), [[0.25, 0.5, 0.75]] * 2)
    faces = environment_of(Background(kind="cube_faces", path=SKY_CUBE))
    d = np.random.default_rng(3).normal(size=(300, 3))
    # Faces baked from the sky at 256 texels: the sky again, to within the bake's blur.
    assert np.percentile(np.abs(faces(d) - sky_environment(d)).max(axis=1), 95) < 0.05
    assert environment_of(Background(kind="sky")) is environment_of(Background(kind="sky"))


# --------------------------------------------------------------------------- pictures


def test_image_sampler_hits_texel_centres_and_clamps_at_the_edges():
    image = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3) * 10
    sample = image_sampler(image)
    # Texel (column 2, image row 0) is at s = 2.5/3 and, row 0 being the top, t = 0.75.
    assert np.allclose(sample(np.array([2.5 / 3]), np.array([0.75])), image[0, 2] / 255.0)
    assert np.allclose(
        sample(np.array([5.0, -5.0]), np.array([-1.0, 2.0])),
        [image[1, 2] / 255.0, image[0, 0] / 255.0],
    )
    halfway = sample(np.array([1.0 / 3]), np.array([0.75]))  # between columns 0 and 1
    assert np.allclose(halfway, (image[0, 0] + image[0, 1]) / 2 / 255.0)


def test_a_picture_used_as_a_sphere_map_bakes_back_into_itself():
    picture = np.random.default_rng(5).integers(0, 256, size=(64, 64, 3), dtype=np.uint8)
    # a smooth picture, so that bilinear resampling changes little
    picture = np.asarray(
        Image.fromarray(picture).resize((8, 8)).resize((64, 64), Image.Resampling.BILINEAR)
    )
    view = math3d.look_at((1.0, 2.0, 5.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    environment = sphere_image_environment(picture, view)
    baked = bake_sphere_map(environment, 64, view[:3, :3]).astype(int)
    t, s = np.mgrid[0:64, 0:64]
    inside = np.hypot((s + 0.5) / 64 - 0.5, 0.5 - (t + 0.5) / 64) < 0.45
    assert np.abs(baked - picture.astype(int)).max(axis=-1)[inside].max() <= 3


def test_a_picture_that_cannot_be_read_is_named(tmp_path):
    bad = tmp_path / "broken.png"
    bad.write_text("not a picture")
    with pytest.raises(ValueError, match=r"broken\.png cannot be read as an image"):
        load_picture(bad)
    assert load_picture(LAUNCH).dtype == np.uint8 and load_picture(LAUNCH).ndim == 3


# --------------------------------------------------------------------------- cube faces


def test_shipped_cube_faces_are_the_baked_sky_and_upright():
    faces = load_cube_faces(SKY_CUBE)
    assert faces.shape == (6, 256, 256, 3) and faces.dtype == np.uint8
    assert np.array_equal(faces, bake_cube_faces(sky_environment, 256))
    # Upright files: on the side faces the sky (blue) is at the top, the ground below.
    for stem in ("px", "nx", "pz", "nz"):
        picture = np.asarray(Image.open(SKY_CUBE / f"{stem}.png").convert("RGB")).astype(int)
        top, bottom = picture[:40].mean(axis=(0, 1)), picture[-40:].mean(axis=(0, 1))
        assert top[2] > top[0] + 40 and bottom[2] < bottom[0] + 10, stem


def test_cube_faces_environment_looks_up_the_face_each_direction_points_at():
    faces = np.zeros((6, 4, 4, 3), dtype=np.uint8)
    for index in range(6):
        faces[index] = (index * 40, 255 - index * 40, 7)
    environment = cube_faces_environment(faces)
    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])
    expected = np.array([(i * 40, 255 - i * 40, 7) for i in range(6)]) / 255.0
    assert np.allclose(environment(axes * 3.0), expected)


def test_cube_faces_are_refused_with_the_file_named(tmp_path):
    with pytest.raises(ValueError, match=r"px\.png is missing"):
        load_cube_faces(tmp_path)
    for stem in CUBE_FACE_FILES:
        shutil.copy(SKY_CUBE / f"{stem}.png", tmp_path)
    Image.new("RGB", (64, 32)).save(tmp_path / "ny.png")
    with pytest.raises(ValueError, match=r"ny\.png is 64x32, expected a square"):
        load_cube_faces(tmp_path)
    Image.new("RGB", (64, 64)).save(tmp_path / "ny.png")
    with pytest.raises(ValueError, match=r"ny\.png is 64x64, expected 256x256 like px\.png"):
        load_cube_faces(tmp_path)
    (tmp_path / "ny.png").write_text("not a picture")
    with pytest.raises(ValueError, match=r"ny\.png cannot be read"):
        load_cube_faces(tmp_path)


# --------------------------------------------------------------------------- the cone


def test_cone_surroundings_make_the_launch_picture_its_own_sphere_map():
    # The textbook uses the picture as the sphere map as it is; the scene's background
    # is defined so that a sphere map baked from it for the fixed viewer is the picture.
    scene = load_scene("spheremap_cone")
    background = scene.background
    assert background.kind == "sphere_map" and background.path == LAUNCH.resolve()
    picture = load_picture(LAUNCH).astype(int)
    size = picture.shape[0]
    assert background.sphere_map_camera is not None
    rotation = background.sphere_map_camera.view()[:3, :3]
    baked = bake_sphere_map(environment_of(background), size, rotation).astype(int)
    t, s = np.mgrid[0:size, 0:size]
    radius = np.hypot((s + 0.5) / size - 0.5, 0.5 - (t + 0.5) / size)
    inside = radius < 0.45  # the rim squeezes a whole hemisphere: leave it out
    diff = np.abs(baked - picture).max(axis=-1)[inside]
    assert np.mean(diff <= 2) > 0.99 and diff.max() <= 12


def test_cone_scene_has_the_backdrop_and_the_cone_as_its_reflector():
    scene = load_scene("cone")
    assert scene == load_scene("spheremap_cone")
    (backdrop,) = scene.objects
    assert isinstance(backdrop, MeshObject) and backdrop.mesh.name == "backdrop.obj"
    assert backdrop.texture == LAUNCH.resolve()
    (cone,) = scene.reflectors
    assert isinstance(cone, CurvedReflector) and cone.mesh.name == "cone.obj"
    assert cone.technique == "sphere-texgen" and cone.source == LAUNCH.resolve()
    assert np.allclose(cone.transform.position, (0.0, 1.0, 0.0))
    # the light hits the backdrop head on with ambient + diffuse = 1: true colours
    (light,) = scene.lights
    assert scene.ambient + light.intensity == pytest.approx(1.0)
    assert np.allclose(light.direction, (0, 0, 1))


def test_cone_points_at_the_viewer_and_up():
    model = curved_reflector(load_scene("cone"), "cone").model_matrix()
    apex = math3d.transform_points(model, np.array([0.0, 2.4, 0.0]))[:3]
    base = math3d.transform_points(model, np.zeros(3))[:3]
    axis = (apex - base) / np.linalg.norm(apex - base)
    assert axis[2] > 0.5 and axis[1] > 0.3  # towards +z (the camera) and up


def test_moving_the_reflector_moves_its_centre_and_changes_what_captures_see():
    scene = load_scene("cone")
    cone = curved_reflector(scene, "cone")
    centre = cone.center()
    lowered = scene.with_reflector(
        "cone", transform=replace(cone.transform, position=(0.0, 0.5, 0.0))
    )
    assert np.allclose(curved_reflector(lowered, "cone").center() - centre, (0.0, -0.5, 0.0))
    assert lowered.content_key() != scene.content_key()
    same = scene.with_reflector("cone", transform=replace(cone.transform))
    assert same == scene and same.content_key() == scene.content_key()
    with pytest.raises(
        OptionError,
        match=r"--set: reflectors\[0\]\.position\[1\]: "
        r"expected a finite number, got nan",
    ):
        apply_options(scene, {"set": ["reflectors[0].position=[0.0, nan, 0.0]"]})


def test_sphere_map_inverse_and_the_cone_agree_on_what_is_behind_the_viewer():
    # sanity of the conventions the GL tests rely on: the sphere map's rim means eye-space
    # (0, 0, -1), which for the cone's viewer is world -z (the backdrop's side)
    rim = sphere_map_inverse(np.array([1.0]), np.array([0.5]))[0]
    camera = load_scene("cone").background.sphere_map_camera
    assert camera is not None
    world = camera.view()[:3, :3].T @ rim
    assert world[2] < -0.99


# --------------------------------------------------------------------------- the sphere


def test_sphere_scene_is_a_unit_chrome_sphere_among_five_objects_in_the_sky():
    scene = load_scene("sphere")
    assert scene == load_scene("chrome_sphere")
    assert scene.background == Background(kind="sky")
    (sphere,) = scene.reflectors
    assert isinstance(sphere, CurvedReflector)
    assert sphere.mesh.name == "env_sphere.obj" and np.allclose(sphere.center(), 0.0)
    assert [o.name for o in scene.objects] == [
        "pedestal",
        "red_block",
        "blue_ball",
        "yellow_pillar",
        "green_block",
    ]
    for item in scene.objects:  # each lies outside the sphere
        assert np.linalg.norm(item.transform.position) > 1.0, item.name
    bare = replace(scene, objects=())
    assert bare.content_key() != scene.content_key() and bare.reflectors == scene.reflectors


def test_methods_and_scene_names_are_checked_with_the_choices():
    assert (
        apply_options(load_scene("sphere"), {"method": "latlong"}).reflector("sphere").technique
        == "latlong"
    )
    for name in ("sphere", "lab"):  # a misspelt name is named, whatever the reflector
        with pytest.raises(OptionError) as info:
            apply_options(load_scene(name), {"method": "cubemap"})
        assert str(info.value) == (
            f"--method: reflectors[0].technique: expected one of {reflector_choices()}, got "
            "'cubemap' (did you mean 'cube'?)"
        )
    with pytest.raises(OptionError, match=r"--method: expected one of ortho, .* got 'cubemap'"):
        apply_options(load_scene("no_mirror"), {"method": "cubemap"})
    with pytest.raises(
        SceneError,
        match=r"unknown scene; expected a \.toml file or one of "
        r"chrome_sphere, lab20",
    ):
        load_scene("robot")
