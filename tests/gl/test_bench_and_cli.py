"""``mirrorlab bench accuracy --quick`` and the render command's technique options, end to
end on llvmpipe."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab.cli import main
from tests.imagecheck import assert_images_close


def test_quick_accuracy_sweep_writes_table_csv_and_plot(tmp_path, capsys):
    assert main(["bench", "accuracy", "--quick", "--out-dir", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "technique" in out.out and "reflected-fbo" in out.out and "cube-live" in out.out
    # the progress bars reached their ends: lab 2 viewpoints x (ray tracer + 2 methods x
    # 2 captures x 2 sizes + stencil); spheres 2 views x (ray tracer + 7 maps x 2 sizes)
    assert "20/20" in out.err and "30/30" in out.err
    with open(tmp_path / "accuracy.csv") as stream:
        table = list(csv.DictReader(stream))
    assert len(table) == 50
    by_key = {(r["scene"], r["technique"], r["map_size"], r["viewpoint"]): r for r in table}
    assert float(by_key[("lab", "raytrace", "0", "60 deg")]["mae"]) == 0.0
    ortho = float(by_key[("lab", "ortho-copy", "128", "60 deg")]["mae"])
    reflected = float(by_key[("lab", "reflected-copy", "128", "60 deg")]["mae"])
    stencil = float(by_key[("lab", "stencil", "0", "60 deg")]["mae"])
    assert reflected < 0.2 * ortho and stencil < 0.2 * ortho
    sky = {r["technique"]: float(r["mae"]) for r in table
           if r["scene"] == "sphere-sky" and r["map_size"] == "128"}
    assert set(sky) == {"sphere", "sphere-vertex", "sphere-texgen", "cube", "cube-live",
                        "latlong", "normal"}
    assert sky["sphere"] < sky["normal"] and sky["cube"] < sky["normal"]
    assert all(float(r["wall_ms"]) > 0 for r in table)
    markdown = (tmp_path / "accuracy.md").read_text()
    assert markdown.count("| technique |") == 3
    # Re-making the report from the CSV measures nothing and gives the same tables.
    (tmp_path / "accuracy.md").unlink()
    again = tmp_path / "again"
    assert main(["bench", "accuracy", "--from-csv", str(tmp_path / "accuracy.csv"),
                 "--out-dir", str(again)]) == 0
    assert (again / "accuracy.md").read_text().split("\n", 1)[1] == markdown.split("\n", 1)[1]
    assert (again / "accuracy.png").exists() and not (again / "accuracy.csv").exists()
    with Image.open(tmp_path / "accuracy.png") as plot:
        assert plot.size[0] > 400 and np.asarray(plot.convert("L")).std() > 10


def test_bench_refuses_a_file_as_its_folder_and_unknown_benchmarks(tmp_path, capsys):
    blocker = tmp_path / "taken"
    blocker.write_text("keep me")
    assert main(["bench", "accuracy", "--quick", "--out-dir", str(blocker)]) == 2
    assert main(["bench", "speed"]) == 2
    assert main(["bench", "accuracy", "--sizes", "64,zero"]) == 2
    assert main(["bench", "accuracy", "--from-csv", str(blocker)]) == 2
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 4 and "--out-dir" in errors[0] and "accuracy" in errors[1]
    assert "--sizes" in errors[2] and "--from-csv" in errors[3]
    assert blocker.read_text() == "keep me"


@pytest.mark.parametrize("method", ["reflected", "stencil", "raytrace"])
def test_render_command_draws_each_method(tmp_path, method, capsys):
    out = tmp_path / f"{method}.png"
    assert main(["render", "--method", method, "--size", "96x96", "--out", str(out)]) == 0
    assert method in capsys.readouterr().out
    with Image.open(out) as image:
        assert image.size == (96, 96)


def test_exact_methods_through_the_api_match_the_ray_tracer():
    truth = mirrorlab.render(size=(96, 96), method="raytrace")
    for method in ("reflected", "stencil"):
        image = mirrorlab.render(size=(96, 96), method=method)
        assert_images_close(f"api_{method}", image, truth, channel_tolerance=10,
                            min_fraction_within=0.99, max_mean_abs=1.0)
    fbo = mirrorlab.render(size=(96, 96), method="reflected", capture="fbo",
                           environment_size=64)
    copy = mirrorlab.render(size=(96, 96), method="reflected", environment_size=64)
    assert np.array_equal(fbo, copy)


@pytest.mark.parametrize("args, option", [
    (["--method", "mirror"], "--method"),
    (["--capture", "blit"], "--capture"),
    (["--env-size", "-3"], "--env-size"),
    (["--env-size", "9000"], "--env-size"),
])
def test_render_command_refuses_bad_technique_options(tmp_path, capsys, args, option):
    out = tmp_path / "x.png"
    assert main(["render", "--out", str(out), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and option in error
    assert not out.exists()


@pytest.mark.parametrize("args", [
    ["--scene", "cone"],
    ["--scene", "sphere", "--envmap", "cube-live", "--map-size", "32"],
    ["--scene", "sphere", "--envmap", "latlong", "--camera", "0,0,5"],
    ["--scene", "sphere", "--envmap", "cube", "--cube-faces", "textures/sky_cube"],
])
def test_render_command_draws_the_environment_map_scenes(tmp_path, capsys, args):
    out = tmp_path / "env.png"
    assert main(["render", *args, "--size", "64x64", "--out", str(out)]) == 0
    assert "scene" in capsys.readouterr().out
    with Image.open(out) as image:
        assert image.size == (64, 64) and np.asarray(image).std() > 5


@pytest.mark.parametrize("args, option", [
    (["--scene", "cone", "--method", "stencil"], "--method"),
    (["--envmap", "cube"], "--envmap"),
    (["--scene", "sphere", "--envmap", "mirror"], "--envmap"),
    (["--scene", "sphere", "--cone-height", "1"], "--cone-height"),
    (["--scene", "cone", "--cone-height", "7"], "--cone-height"),
    (["--scene", "sphere", "--map-size", "2"], "--map-size"),
    (["--scene", "moon"], "--scene"),
    (["--scene", "sphere", "--cube-faces", "models"], "--cube-faces"),
    (["--scene", "cone", "--cube-faces", "textures/sky_cube"], "--cube-faces"),
])
def test_render_command_refuses_options_that_do_not_fit_the_scene(tmp_path, capsys, args,
                                                                  option):
    out = tmp_path / "x.png"
    assert main(["render", "--out", str(out), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and option in error
    assert not out.exists()


def test_a_cube_map_from_six_images_draws_what_the_baked_cube_draws(tmp_path):
    """The shipped faces are the baked sky, so the two static cubes must agree exactly."""
    from mirrorlab.envmap_renderer import render_envmap_frame
    from mirrorlab.paths import REPO_DIR
    from mirrorlab.scene.envscenes import load_cube_faces

    faces = load_cube_faces(REPO_DIR / "textures" / "sky_cube")
    from_files = render_envmap_frame("sphere", "cube", (96, 96), cube_faces=faces).image
    baked = render_envmap_frame("sphere", "cube", (96, 96), map_size=256).image
    assert np.array_equal(from_files, baked)
    # Six other pictures change the reflection and the sky behind it.
    rolled = render_envmap_frame("sphere", "cube", (96, 96), cube_faces=faces[::-1]).image
    assert np.mean(np.abs(rolled.astype(int) - baked.astype(int)).max(axis=-1) > 30) > 0.3


def test_api_renders_the_environment_map_scenes():
    sphere = mirrorlab.render(size=(48, 48), scene="sphere", envmap="cube")
    cone = mirrorlab.render(size=(48, 48), scene="cone")
    assert sphere.shape == cone.shape == (48, 48, 3) and not np.array_equal(sphere, cone)
    with pytest.raises(ValueError, match="envmap"):
        mirrorlab.render(size=(48, 48), envmap="cube")
    from mirrorlab.paths import REPO_DIR

    faces = mirrorlab.render(size=(48, 48), scene="sphere", envmap="cube",
                             cube_faces=str(REPO_DIR / "textures" / "sky_cube"))
    assert np.array_equal(faces, sphere)


def test_plan_command_explains_what_runs(capsys):
    assert main(["plan", "--method", "reflected"]) == 0
    assert main(["plan", "--camera", "-12,2,-2", "--target", "0,0,0"]) == 0
    text = capsys.readouterr().out
    assert "run  reflected-capture" in text and "skip reflected-capture" in text
    assert "behind" in text
