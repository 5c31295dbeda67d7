"""``mirrorlab bench accuracy --quick``, ``mirrorlab render`` with each technique and the
scene options, ``mirrorlab plan`` and ``render --frames --stats``, end to end on llvmpipe
(the CLI through :func:`mirrorlab.cli.main`)."""

from __future__ import annotations

import csv
import json
import re
import shutil
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab import flip
from mirrorlab.accuracy import (
    SweepSettings,
    erode,
    is_truth,
    lab_panel,
    lab_techniques,
    lab_viewpoints,
    panel_configurations,
    sphere_panels,
    sweep_rows,
)
from mirrorlab.cli import main
from mirrorlab.data import data_path, scenes_dir
from mirrorlab.passes.envmap import CubeMapped
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.backgrounds import CUBE_FACE_FILES
from mirrorlab.scene.loader import load_scene
from mirrorlab.techniques import register, technique, technique_names, techniques, unregister
from tests.imagecheck import assert_images_close

CORRECTIONS = ("box", "sphere", "distance")
"""The parallax corrections the quick sweep measures: its panels' two proxies, the search."""

SKY_CUBE = data_path("textures") / "sky_cube"


def png(path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB"))


# --------------------------------------------------------------------------- bench


def test_quick_accuracy_sweep_writes_table_csv_and_plot(tmp_path, capsys):
    assert main(["bench", "accuracy", "--quick", "--out-dir", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "technique" in out.out and "reflected-fbo" in out.out and "cube-live" in out.out
    # What the quick sweep measures, from its settings: the lab mirror at 2 viewpoints and
    # the sphere alone in the sky, among its objects and in the room, 1 view each; at each,
    # the ray tracer and every configuration of the scene's techniques (every registered
    # technique of its reflectors' kinds: tests/unit/test_accuracy.py checks the list).
    quick = SweepSettings.quick()
    assert quick.sizes == (64, 128) and quick.viewpoints == ("head-on far", "60 deg")
    assert quick.steps == ()
    panels = [lab_panel(quick), *sphere_panels(quick)]
    total = sweep_rows(panels, quick)
    # one progress bar (tqdm, on stderr), and it reached its end: a step per row, and one
    # more per viewpoint for scoring its frames (2 lab views, 3 sphere scenes)
    steps = total + sum(len(panel.viewpoints) for panel in panels)
    assert f"{steps}/{steps}" in out.err, out.err[-400:]
    with open(tmp_path / "accuracy.csv") as stream:
        table = list(csv.DictReader(stream))
    assert len(table) == total
    by_key = {(r["scene"], r["technique"], r["map_size"], r["viewpoint"]): r for r in table}
    assert len(by_key) == total  # one row per configuration and viewpoint
    for panel in panels:
        measured = {r["technique"] for r in table if r["scene"] == panel.name}
        configured = {label for label, _ in panel_configurations(panel, quick)}
        assert {t for t in measured if not is_truth(t)} == configured, panel.name
        kinds = {r.kind for r in panel.scene.reflectors}
        methods = {o["method"] for _, o in panel_configurations(panel, quick)}
        assert methods == {n for kind in kinds for n in technique_names(kind)}, panel.name
    assert {r["viewpoint"] for r in table if r["scene"] == "lab"} == set(quick.viewpoints)
    assert set(quick.viewpoints) <= set(lab_viewpoints())
    assert float(by_key[("lab", "raytrace", "0", "60 deg")]["mae"]) == 0.0
    ortho = float(by_key[("lab", "ortho-copy", "128", "60 deg")]["mae"])
    reflected = float(by_key[("lab", "reflected-copy", "128", "60 deg")]["mae"])
    stencil = float(by_key[("lab", "stencil", "0", "60 deg")]["mae"])
    assert reflected < 0.2 * ortho and stencil < 0.2 * ortho
    # ortho's error is its geometry's, whatever its texture's size: the footprint's too
    footprint = float(by_key[("lab", "ortho-copy footprint", "0", "60 deg")]["mae"])
    assert abs(footprint - ortho) < 0.1 * ortho
    sky = {
        r["technique"]: float(r["mae"])
        for r in table
        if r["scene"] == "sphere-sky" and r["map_size"] == "128"
    }
    assert sky["sphere"] < sky["normal"] and sky["cube"] < sky["normal"]
    room = {
        r["technique"]: float(r["share_off"])
        for r in table
        if r["scene"] == "sphere-room" and r["map_size"] == "128"
    }
    # in the room, the room as the proxy, or what the capture saw: each technique measured
    # with a box proxy (every one that takes a parallax correction and a proxy)
    boxed = [label.removesuffix(" box") for label in room if label.endswith(" box")]
    assert "cube-live" in boxed
    for name in boxed:
        assert room[name] > 0.2, (name, room)
        assert room[f"{name} box"] < 0.05 * room[name], (name, room)
        assert room[f"{name} distance"] < 0.05 * room[name], (name, room)
    # FLIP beside the old figures (or, without flip-evaluator, empty, and the table says
    # why); no shipped technique falls back to a probe, so no miss share
    scored = [r for r in table if not r["technique"].startswith("raytrace")]
    if flip.available():
        assert all(0.0 <= float(r["flip"]) < 1.0 for r in scored)
        # the exact techniques at the frame's size look like the truth; ortho does not
        ortho_flip = float(by_key[("lab", "ortho-copy", "128", "60 deg")]["flip"])
        assert ortho_flip > 0.01 > float(by_key[("lab", "reflected-copy", "128", "60 deg")]["flip"])
        assert {r["flip"] for r in table if r["technique"].startswith("raytrace")} == {"0.0"}
    else:
        assert all(r["flip"] == "" for r in table) and "FLIP is empty" in out.out
    assert all(r["miss_share"] == "" for r in table) and "miss share" not in out.out
    # each scene's Pareto frontier is named: configurations of that scene, cheapest first
    assert out.out.count("Pareto frontier") == len(panels)
    assert all(float(r["wall_ms"]) > 0 for r in table)
    markdown = (tmp_path / "accuracy.md").read_text()
    lines = markdown.splitlines()
    assert sum(line.startswith("| technique |") for line in lines) == 4  # 4 scenes
    assert sum(line.startswith("| wall ms | technique |") for line in lines) == 4  # frontiers
    # Re-making the report from the CSV measures nothing and gives the same tables.
    (tmp_path / "accuracy.md").unlink()
    again = tmp_path / "again"
    assert (
        main(
            [
                "bench",
                "accuracy",
                "--from-csv",
                str(tmp_path / "accuracy.csv"),
                "--out-dir",
                str(again),
            ]
        )
        == 0
    )
    assert (again / "accuracy.md").read_text().split("\n", 1)[1] == markdown.split("\n", 1)[1]
    assert (again / "accuracy.png").exists() and not (again / "accuracy.csv").exists()
    with Image.open(tmp_path / "accuracy.png") as plot:
        assert plot.size[0] > 400 and np.asarray(plot.convert("L")).std() > 10


def test_accuracy_sweep_of_a_scene_file(tmp_path, capsys, monkeypatch):
    """``--scene FILE`` measures every technique the file's reflectors can take, from its
    own camera: two_mirrors has planar mirrors only."""
    monkeypatch.chdir(scenes_dir().parent)
    assert (
        main(
            [
                "bench",
                "accuracy",
                "--quick",
                "--scene",
                "scenes/two_mirrors.toml",
                "--out-dir",
                str(tmp_path),
            ]
        )
        == 0
    )
    out = capsys.readouterr()
    total = 1 + len(lab_techniques(SweepSettings.quick().sizes))
    steps = total + 1  # and one step to score the viewpoint's frames
    assert f"{steps}/{steps}" in out.err, out.err[-400:]
    with open(tmp_path / "accuracy.csv") as stream:
        table = list(csv.DictReader(stream))
    assert len(table) == total
    assert {r["scene"] for r in table} == {"two_mirrors"}
    assert {r["viewpoint"] for r in table} == {"camera"}
    measured = {r["technique"] for r in table}
    assert measured == {"raytrace", *(label for label, _ in lab_techniques((128,)))}
    assert {"stencil", "reflected-copy", "reflected-fbo", "ortho-fbo footprint"} <= measured
    # The exact techniques, two bounces deep, at the frame's size: 99% of the mirrors'
    # pixels within 10/255 of the ray tracer.
    rows = {(r["technique"], r["map_size"]): r for r in table}
    for key in (("stencil", "0"), ("reflected-copy", "128"), ("reflected-fbo", "128")):
        assert float(rows[key]["share_off"]) <= 0.01, (key, rows[key])
    assert (tmp_path / "accuracy.md").exists() and (tmp_path / "accuracy.png").exists()


def test_a_sweep_from_inside_the_sphere_reports_no_reflector_pixels(tmp_path, capsys):
    """From inside the chrome sphere no pixel shows a reflector (it is seen from outside
    only): every row says so, none reports zero error."""
    scene = tmp_path / "inside.toml"
    source = (
        (scenes_dir() / "chrome_sphere.toml")
        .read_text()
        .replace("eye = [1.3, 2.0, 7.4]", "eye = [0.1, 0.05, 0.2]")
        .replace("target = [0.0, 0.1, 0.0]", "target = [0.0, 0.1, 3.0]")
        .replace("near = 0.2", "near = 0.05")
        .replace('"../', f'"{scenes_dir().parent}/')
    )
    scene.write_text(source)
    assert (
        main(
            [
                "bench",
                "accuracy",
                "--scene",
                str(scene),
                "--frame",
                "32",
                "--sizes",
                "16",
                "--frames",
                "1",
                "--out-dir",
                str(tmp_path / "out"),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    with open(tmp_path / "out" / "accuracy.csv") as stream:
        table = list(csv.DictReader(stream))
    assert len(table) > 5
    assert all(r["mae"] == "" and r["pixels"] == "0" for r in table)
    lines = [
        line
        for line in out.splitlines()
        if line.startswith(("raytrace", "cube", "sphere", "latlong"))
    ]
    assert lines and all("no reflector pixels" in line for line in lines), out
    assert not re.search(r"\b0\.00\b", out)


class RightHalfFallback(CubeMapped):
    """A static cube map that says it filled the right half of every view from a
    fallback: what a technique with a probe (screen-space reflections) reports."""

    def fallback_mask(self, draw, view) -> np.ndarray:
        width, height = view.size
        mask = np.zeros((height, width), dtype=bool)
        mask[:, width // 2 :] = True
        return mask


def test_a_technique_with_a_fallback_gets_its_miss_share(tmp_path, capsys):
    """The sweep reports, for a technique whose pass reports the pixels it filled from its
    fallback (any technique: one registered here), the share of the reflector's scored
    pixels that fell back; the others have none (an empty cell, ``-`` in the table)."""
    entry = replace(
        technique("cube"), name="cube-halfback", pass_class=f"{__name__}:RightHalfFallback"
    )
    register(entry)
    try:
        out_dir = tmp_path / "out"
        args = ["--frame", "32", "--sizes", "16", "--frames", "1", "--out-dir", str(out_dir)]
        scene = str(scenes_dir() / "chrome_sphere.toml")
        assert main(["bench", "accuracy", "--scene", scene, *args]) == 0
    finally:
        unregister(entry.name)
    out = capsys.readouterr().out
    with open(out_dir / "accuracy.csv") as stream:
        table = {r["technique"]: r for r in csv.DictReader(stream)}
    truth = trace_scene(load_scene("chrome_sphere"), (32, 32), 4)
    scored = erode(truth.reflective_mask, 1)  # as the sweep scores a curved reflector
    right = scored[:, 16:].sum() / scored.sum()
    assert 0.3 < right < 0.7
    assert float(table["cube-halfback"]["miss_share"]) == pytest.approx(right)
    assert all(r["miss_share"] == "" for name, r in table.items() if name != "cube-halfback")
    # the same pictures as the cube map's: the same errors
    for figure in ("mae", "flip", "share_off"):
        assert table["cube-halfback"][figure] == table["cube"][figure]
    assert "cube-halfback" in out and "miss share" in out
    rows = [
        [cell.strip() for cell in line.strip("|").split("|")]
        for line in (out_dir / "accuracy.md").read_text().splitlines()
        if line.startswith("| ")
    ]
    header = rows[0]
    cells = {  # the table of configurations (not the frontier's, of other columns)
        row[0]: dict(zip(header, row, strict=True)) for row in rows[1:] if len(row) == len(header)
    }
    assert cells["cube-halfback"]["miss share"] == f"{right:.1%}"
    assert cells["cube"]["miss share"] == "-"


def test_bench_refuses_a_file_as_its_folder_and_unknown_benchmarks(tmp_path, capsys):
    blocker = tmp_path / "taken"
    blocker.write_text("keep me")
    with pytest.raises(SystemExit) as stopped:  # argparse's own refusal: usage, then why
        main(["bench", "sprint"])
    assert stopped.value.code == 2
    assert "invalid choice: 'sprint' (choose from 'accuracy', 'speed')" in (capsys.readouterr().err)
    assert main(["bench", "accuracy", "--quick", "--out-dir", str(blocker)]) == 2
    assert main(["bench", "accuracy", "--sizes", "64,zero"]) == 2
    assert main(["bench", "accuracy", "--from-csv", str(blocker)]) == 2
    assert main(["bench", "accuracy", "--scene", "moon"]) == 2
    cone = str(scenes_dir() / "spheremap_cone.toml")
    assert main(["bench", "accuracy", "--scene", cone, "--scene", "cone"]) == 2
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 5 and "--out-dir" in errors[0]
    assert "--sizes" in errors[1] and "--from-csv" in errors[2]
    assert "moon" in errors[3] and "unknown scene" in errors[3]
    assert "--scene: two scenes named 'spheremap_cone'" in errors[4]
    assert blocker.read_text() == "keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken"]


# --------------------------------------------------------------------------- render


@pytest.mark.parametrize(
    "scene, method",
    [  # each technique once (one for either kind on the lab's mirror)
        *(("lab20", m) for m in technique_names("planar")),
        *(("chrome_sphere", t.name) for t in techniques("curved") if not t.serves("planar")),
    ],
)
def test_render_command_draws_each_technique(tmp_path, capsys, scene, method):
    out = tmp_path / f"{method}.png"
    assert main(["render", scene, "--method", method, "--size", "64x48", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert str(out) in said and scene in said and "camera" in said
    image = png(out)
    assert image.shape == (48, 64, 3) and image.std() > 5
    # the command draws what the API draws
    assert np.array_equal(image, mirrorlab.render(scene, size=(64, 48), method=method))


def test_render_command_draws_the_ray_traced_truth(tmp_path, capsys):
    out = tmp_path / "truth.png"
    assert main(["render", "--raytrace", "--size", "64x48", "--out", str(out)]) == 0
    assert "drawn by raytrace" in capsys.readouterr().out
    truth = png(out)
    assert np.array_equal(truth, mirrorlab.render(size=(64, 48), method="raytrace"))
    # and the exact techniques agree with it
    for method in ("reflected", "stencil"):
        assert_images_close(
            f"cli_truth_{method}",
            mirrorlab.render(size=(64, 48), method=method),
            truth,
            channel_tolerance=10,
            min_fraction_within=0.99,
            max_mean_abs=1.0,
        )


def test_exact_methods_through_the_api_match_the_ray_tracer():
    truth = mirrorlab.render(size=(96, 96), method="raytrace")
    for method in ("reflected", "stencil"):
        image = mirrorlab.render(size=(96, 96), method=method)
        assert_images_close(
            f"api_{method}",
            image,
            truth,
            channel_tolerance=10,
            min_fraction_within=0.99,
            max_mean_abs=1.0,
        )
    fbo = mirrorlab.render(size=(96, 96), method="reflected", capture="fbo", env_size=64)
    copy = mirrorlab.render(size=(96, 96), method="reflected", env_size=64)
    assert np.array_equal(fbo, copy)


@pytest.mark.parametrize(
    "args, option",
    [
        (["--method", "mirror"], "--method"),
        (["--capture", "blit"], "--capture"),
        (["--env-size", "-3"], "--env-size"),
        (["--env-size", "9000"], "--env-size"),
        (["sphere", "--map-size", "2"], "--map-size"),
        (["sphere", "--method", "mirror"], "--method"),
        (["sphere", "--cube-faces", str(data_path("models"))], "--cube-faces"),
        (["cone", "--set", "camera.fovy=0"], "--set"),
        (["robot_wave", "--frames", "30"], "--frames"),
    ],
)
def test_render_command_refuses_bad_technique_options(tmp_path, capsys, args, option):
    out = tmp_path / "x.png"
    assert main(["render", "--out", str(out), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and option in error
    assert not out.exists()


@pytest.mark.parametrize(
    "args, option",
    [
        (["no_mirror", "--method", "stencil"], "--method"),
        (["no_mirror", "--env-size", "64"], "--env-size"),
        (["cone", "--method", "stencil"], "--method"),
        (["cone", "--capture", "fbo"], "--capture"),
        (["lab20", "--method", "cube"], "--method"),
        (["lab20", "--map-size", "64"], "--map-size"),
        (["sphere", "--angles", "0,0,0"], "--angles"),
    ],
)
def test_render_command_refuses_options_the_scene_has_nothing_for(tmp_path, capsys, args, option):
    out = tmp_path / "x.png"
    assert main(["render", "--out", str(out), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and option in error
    scene = mirrorlab.load_scene(args[0]).name
    assert scene in error, "the message should say which scene lacks it"
    assert not out.exists()


@pytest.mark.parametrize("args", [["--scene", "moon"], ["moon"]])
def test_render_command_refuses_an_unknown_scene(tmp_path, capsys, args):
    out = tmp_path / "x.png"
    assert main(["render", "--out", str(out), *args]) == 2
    error = capsys.readouterr().err.strip()
    assert error.count("\n") == 0 and "moon" in error and "unknown scene" in error
    assert "lab20" in error  # and names the scenes there are
    assert not out.exists()


@pytest.mark.parametrize(
    "args",
    [
        ["cone"],
        ["sphere", "--method", "cube-live", "--map-size", "32"],
        ["sphere", "--method", "latlong", "--camera", "0,0,5"],
        ["sphere", "--method", "cube", "--cube-faces", str(SKY_CUBE)],
        ["mirror_and_sphere"],
    ],
)
def test_render_command_draws_the_environment_map_scenes(tmp_path, capsys, args):
    out = tmp_path / "env.png"
    assert main(["render", *args, "--size", "64x64", "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    image = png(out)
    assert image.shape == (64, 64, 3) and image.std() > 5


def rolled_faces(folder):
    """The sky cube's six pictures in reverse order (px <- nz, nx <- pz, ...)."""
    folder.mkdir()
    for stem, other in zip(CUBE_FACE_FILES, reversed(CUBE_FACE_FILES), strict=True):
        shutil.copy(SKY_CUBE / f"{other}.png", folder / f"{stem}.png")
    return folder


def test_a_cube_map_from_six_images_draws_what_the_baked_cube_draws(tmp_path, monkeypatch):
    """The shipped faces are the baked sky, so the two static cubes must agree exactly."""
    monkeypatch.chdir(data_path("textures").parent)
    from_files, baked, rolled = (tmp_path / f"{n}.png" for n in ("files", "baked", "rolled"))
    common = ["--method", "cube", "--size", "96x96"]
    assert (
        main(
            [
                "render",
                "sphere",
                *common,
                "--cube-faces",
                "textures/sky_cube",
                "--out",
                str(from_files),
            ]
        )
        == 0
    )
    assert main(["render", "sphere", *common, "--map-size", "256", "--out", str(baked)]) == 0
    assert np.array_equal(png(from_files), png(baked))
    # Six other pictures change the reflection and the sky behind it.
    assert (
        main(
            [
                "render",
                "sphere",
                *common,
                "--cube-faces",
                str(rolled_faces(tmp_path / "rolled_faces")),
                "--out",
                str(rolled),
            ]
        )
        == 0
    )
    changed = np.abs(png(rolled).astype(int) - png(baked).astype(int)).max(axis=-1) > 30
    assert np.mean(changed) > 0.3


def test_api_renders_the_environment_map_scenes():
    sphere = mirrorlab.render(size=(48, 48), scene="sphere", method="cube")
    cone = mirrorlab.render(size=(48, 48), scene="cone")
    assert sphere.shape == cone.shape == (48, 48, 3) and not np.array_equal(sphere, cone)
    assert sphere.std() > 5 and cone.std() > 5
    with pytest.raises(ValueError, match="method"):
        mirrorlab.render(size=(48, 48), method="cube")  # the lab has no curved reflector
    faces = mirrorlab.render(size=(48, 48), scene="sphere", method="cube", cube_faces=str(SKY_CUBE))
    assert np.array_equal(faces, sphere)


# --------------------------------------------------------------------------- plan, stats


def test_plan_command_explains_what_runs(capsys):
    assert main(["plan", "--method", "reflected"]) == 0
    text = capsys.readouterr().out
    # frame 0 captures the mirror for the viewer; frame 1 (nothing moved) reuses it
    frames = re.split(r"^frame \d+: ", text, flags=re.M)[1:]
    assert len(frames) == 2
    assert "run  capture mirror (reflected" in frames[0]
    assert "skip capture mirror (reflected" in frames[1]
    assert "run  camera" in frames[0] and "run  camera" in frames[1]
    assert main(["plan", "--camera", "-12,2,-2", "--target", "0,0,0"]) == 0
    text = capsys.readouterr().out
    assert "capture" not in text and "behind" in text
    assert "draw mirror in camera: back" in text


def test_plan_command_json_parses_and_matches_the_scene(capsys):
    assert main(["plan", "robot_wave", "--frames", "8", "--json", "--size", "64x64"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["scene"] == "robot_wave" and document["size"] == [64, 64]
    frames = document["frames"]
    assert [f["frame"] for f in frames] == list(range(8))
    for frame in frames:
        assert frame["passes"][-1]["pass"] == "camera" and frame["passes"][-1]["runs"]
        assert [d["reflector"] for d in frame["draws"]] == ["mirror"]
    captured = [
        f["frame"] for f in frames if any(p["pass"] == "capture" and p["runs"] for p in f["passes"])
    ]
    assert captured == capture_frames(8)


def capture_frames(count: int) -> list[int]:
    """The robot_wave frames among the first ``count`` whose mirror must be captured: the
    first, and each whose pose differs from the one before (from the scene file)."""
    scene = mirrorlab.load_scene("robot_wave")
    poses = [scene.at_frame(f).content_key() for f in range(count)]
    return [f for f in range(count) if f == 0 or poses[f] != poses[f - 1]]


def test_render_stats_report_the_passes_of_each_frame(tmp_path, capsys):
    expected = capture_frames(8)
    # still for frames 0-4 (keyframes 0 and 4 agree), moving from frame 5 on
    assert expected[:2] == [0, 5] and 1 not in expected and 4 not in expected
    out = tmp_path / "last.png"
    assert (
        main(
            [
                "render",
                "robot_wave",
                "--frames",
                "8",
                "--stats",
                "--size",
                "64x64",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    reported = dict(re.findall(r"^frame (\d+): ran (.*?) \(", text, flags=re.M))
    assert sorted(int(f) for f in reported) == list(range(8))
    for frame in range(8):
        ran = reported[str(frame)]
        if frame in expected:
            assert ran == "capture:mirror, camera", (frame, ran)
        else:
            assert ran == "camera; skipped capture:mirror", (frame, ran)
    runs = len(expected) * 2 + (8 - len(expected))
    assert f"planned: {runs} passes run and {8 - len(expected)} skipped over 8 frames" in text
    comparison = [line for line in text.splitlines() if line.startswith("--no-plan")]
    assert len(comparison) == 1
    assert f"{2 * 8} passes run" in comparison[0]
    assert f"saved {8 - len(expected)} passes" in comparison[0]
    assert png(out).shape == (64, 64, 3)
    # the plan is lossless: each frame is the --no-plan frame, and the report says so
    assert len(re.findall(r"the same as --no-plan\)$", text, flags=re.M)) == 8
    assert "frames are the same, pixel for pixel, in all 8 frames" in text


def test_render_stats_say_how_many_pixels_the_lossy_rule_changes(tmp_path, capsys):
    # the lab's mirror seen from 300 units: a few pixels, drawn plain under --tiny-pixels
    out = tmp_path / "far.png"
    args = [
        "render",
        "lab20",
        "--camera",
        "300,1,-2",
        "--target",
        "-7,1,-2",
        "--set",
        "camera.far=1000",
        "--size",
        "64x64",
        "--frames",
        "2",
        "--stats",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    assert "frames are the same, pixel for pixel, in all 2 frames" in capsys.readouterr().out
    assert main([*args, "--tiny-pixels", "16"]) == 0
    text = capsys.readouterr().out
    changed = re.search(r"frames differ in 2 of 2 frames: (\d+) pixels in all", text)
    assert changed and int(changed.group(1)) > 0, text
    assert "pixels differ from --no-plan)" in text
    assert (
        main(
            [
                "plan",
                "lab20",
                "--camera",
                "300,1,-2",
                "--target",
                "-7,1,-2",
                "--set",
                "camera.far=1000",
                "--size",
                "64x64",
                "--tiny-pixels",
                "16",
            ]
        )
        == 0
    )
    assert "lossy" in capsys.readouterr().out


def test_render_out_dir_writes_one_png_per_frame(tmp_path, capsys):
    out_dir = tmp_path / "frames"
    out = tmp_path / "last.png"
    assert (
        main(
            [
                "render",
                "robot_wave",
                "--frames",
                "8",
                "--size",
                "64x64",
                "--out",
                str(out),
                "--out-dir",
                str(out_dir),
            ]
        )
        == 0
    )
    assert "wrote 8 frames" in capsys.readouterr().out
    # the frames, and the hidden record of how they were made (a rerun resumes by it)
    names = sorted(p.name for p in out_dir.iterdir() if not p.name.startswith("."))
    assert (out_dir / ".robot_wave.mirrorlab-batch.json").is_file()
    assert names == [f"robot_wave_{f:04d}.png" for f in range(8)]
    pictures = [png(out_dir / name) for name in names]
    assert np.array_equal(pictures[-1], png(out))
    # the robot holds still to frame 4 and moves after
    assert np.array_equal(pictures[0], pictures[4])
    assert not np.array_equal(pictures[4], pictures[5])
    with mirrorlab.Renderer(size=(64, 64)) as renderer:
        assert np.array_equal(pictures[6], renderer.render("robot_wave", frame=6))
