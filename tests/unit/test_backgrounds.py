"""The environment-mapping scenes in numpy: their surroundings, reflector and choices."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab import math3d
from mirrorlab.envmap import bake_sphere_map, sphere_map_inverse
from mirrorlab.scene.envscenes import (
    CONE_CAMERA,
    ENV_SCENES,
    ENVMAP_METHODS,
    SUN_DIRECTION,
    build_cone_scene,
    build_env_scene,
    build_sphere_scene,
    check_method,
    sky_environment,
)
from mirrorlab.scene.mesh import load_texture

directions = st.tuples(*(st.floats(-1.0, 1.0, allow_nan=False),) * 3).filter(
    lambda v: np.linalg.norm(v) > 1e-3)


@settings(max_examples=200, deadline=None)
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
    assert np.abs(sky_environment(np.array([[1.0, 0.35, 0.2]]))[0]
                  - (0.95, 0.15, 0.12)).max() < 0.02  # the red balloon


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


def test_cone_surroundings_make_the_launch_picture_its_own_sphere_map():
    # The textbook uses the picture as the sphere map as it is; the scene's environment
    # is defined so that a sphere map baked from it for the fixed viewer is the picture.
    scene = build_cone_scene()
    picture = load_texture("launch").astype(int)
    size = picture.shape[0]
    baked = bake_sphere_map(scene.environment, size, CONE_CAMERA.view()[:3, :3]).astype(int)
    t, s = np.mgrid[0:size, 0:size]
    radius = np.hypot((s + 0.5) / size - 0.5, 0.5 - (t + 0.5) / size)
    inside = radius < 0.45  # the rim squeezes a whole hemisphere: leave it out
    diff = np.abs(baked - picture).max(axis=-1)[inside]
    assert np.mean(diff <= 2) > 0.99 and diff.max() <= 12


def test_cone_scene_has_the_backdrop_and_keeps_the_cone_out_of_the_graph():
    scene = build_cone_scene(0.5)
    meshes = [n.mesh for n in scene.graph.nodes() if n.mesh]
    assert meshes == ["backdrop"]
    assert scene.reflector.mesh == "cone"
    assert scene.sphere_texture == "launch"
    assert np.allclose(scene.reflector.position, (0.0, 0.5, 0.0))
    # the light hits the backdrop head on with ambient + diffuse = 1: true colours
    assert scene.ambient + scene.diffuse == pytest.approx(1.0)
    assert np.allclose(scene.light_direction, (0, 0, 1))


def test_sphere_scene_objects_can_be_left_out():
    full, empty = build_sphere_scene(), build_sphere_scene(objects=False)
    assert sum(1 for n in full.graph.nodes() if n.mesh) == 5
    assert sum(1 for n in empty.graph.nodes() if n.mesh) == 0
    assert full.reflector.mesh == "env_sphere"
    assert np.allclose(full.reflector.center(), 0.0)


def test_moving_the_reflector_moves_its_centre_and_bumps_the_revision():
    scene = build_cone_scene(0.0)
    before, centre = scene.revision, scene.reflector.center()
    scene.move_reflector((0.0, -0.5, 0.0))
    assert scene.revision == before + 1
    assert np.allclose(scene.reflector.center() - centre, (0.0, -0.5, 0.0))
    scene.move_reflector((0.0, 0.0, 0.0))
    assert scene.revision == before + 1  # nothing moved, nothing to redo
    with pytest.raises(ValueError, match="3 finite numbers"):
        scene.move_reflector((0.0, np.nan, 0.0))


def test_cone_points_at_the_viewer_and_up():
    model = build_cone_scene().reflector.model_matrix()
    apex = math3d.transform_points(model, np.array([0.0, 2.4, 0.0]))[:3]
    base = math3d.transform_points(model, np.zeros(3))[:3]
    axis = (apex - base) / np.linalg.norm(apex - base)
    assert axis[2] > 0.5 and axis[1] > 0.3  # towards +z (the camera) and up


def test_names_are_checked_with_a_message_listing_the_choices():
    assert check_method("latlong") == "latlong"
    assert len(ENVMAP_METHODS) == 7
    with pytest.raises(ValueError, match="'cubemap'; expected one of sphere, sphere-vertex"):
        check_method("cubemap")
    assert {build_env_scene(name).name for name in ENV_SCENES} == set(ENV_SCENES)
    with pytest.raises(ValueError, match="scene 'robot'; expected one of cone, sphere"):
        build_env_scene("robot")


def test_sphere_map_inverse_and_the_sky_agree_on_what_is_behind_the_viewer():
    # sanity of the conventions the GL tests rely on: the sphere map's rim means eye-space
    # (0, 0, -1), which for the cone's viewer is world -z (the backdrop's side)
    rim = sphere_map_inverse(np.array([1.0]), np.array([0.5]))[0]
    world = CONE_CAMERA.view()[:3, :3].T @ rim
    assert world[2] < -0.99


def test_scenes_and_the_renderer_module_import_no_opengl():
    import subprocess
    import sys

    code = ("import mirrorlab.scene.envscenes, mirrorlab.envmap_renderer, sys\n"
            "print(' '.join(sorted(sys.modules)))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            check=True).stdout.split()
    assert not {m for m in loaded if m.split(".")[0] in ("OpenGL", "glfw")}


def test_shipped_cube_faces_are_the_baked_sky_and_upright(tmp_path):
    from PIL import Image

    from mirrorlab.envmap import bake_cube_faces
    from mirrorlab.paths import REPO_DIR
    from mirrorlab.scene.envscenes import load_cube_faces, sky_environment

    folder = REPO_DIR / "textures" / "sky_cube"
    faces = load_cube_faces(folder)
    assert faces.shape == (6, 256, 256, 3) and faces.dtype == np.uint8
    assert np.array_equal(faces, bake_cube_faces(sky_environment, 256))
    # Upright files: on the side faces the sky (blue) is at the top, the ground below.
    for stem in ("px", "nx", "pz", "nz"):
        picture = np.asarray(Image.open(folder / f"{stem}.png").convert("RGB")).astype(int)
        top, bottom = picture[:40].mean(axis=(0, 1)), picture[-40:].mean(axis=(0, 1))
        assert top[2] > top[0] + 40 and bottom[2] < bottom[0] + 10, stem


def test_cube_faces_are_refused_with_the_file_named(tmp_path):
    import shutil

    from PIL import Image

    from mirrorlab.paths import REPO_DIR
    from mirrorlab.scene.envscenes import load_cube_faces

    with pytest.raises(ValueError, match=r"px\.png is missing"):
        load_cube_faces(tmp_path)
    for stem in ("px", "nx", "py", "ny", "pz", "nz"):
        shutil.copy(REPO_DIR / "textures" / "sky_cube" / f"{stem}.png", tmp_path)
    Image.new("RGB", (64, 32)).save(tmp_path / "ny.png")
    with pytest.raises(ValueError, match=r"ny\.png is 64x32, expected a square"):
        load_cube_faces(tmp_path)
    Image.new("RGB", (64, 64)).save(tmp_path / "ny.png")
    with pytest.raises(ValueError, match=r"ny\.png is 64x64, expected 256x256"):
        load_cube_faces(tmp_path)
    (tmp_path / "ny.png").write_text("not a picture")
    with pytest.raises(ValueError, match=r"ny\.png cannot be read"):
        load_cube_faces(tmp_path)
