"""The accuracy sweep's scoring, configurations and reporting, on made-up numbers and the
scene files (no GL)."""

from __future__ import annotations

import math
import sys
from dataclasses import replace

import numpy as np
import pytest

from mirrorlab import accuracy, flip
from mirrorlab.options import apply_options
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import BoxProxy, DistanceSearch
from mirrorlab.techniques import names_where, technique_names
from tests.scenekit import curved_reflector, planar_reflector


def test_image_error_scores_only_the_masked_pixels():
    truth = np.zeros((4, 4, 3), dtype=np.uint8)
    image = truth.copy()
    image[0, 0] = (20, 0, 0)  # off by 20 in one channel
    image[3, 3] = (255, 255, 255)  # outside the mask: ignored
    mask = np.zeros((4, 4), dtype=bool)
    mask[:2, :2] = True
    error = accuracy.image_error(image, truth, mask)
    assert error.mae == pytest.approx(20 / 12)  # 4 pixels x 3 channels
    assert error.share_off == pytest.approx(0.25)
    assert error.psnr == pytest.approx(10 * math.log10(255**2 / (400 / 12)))
    assert error.p95 == pytest.approx(np.percentile([20, 0, 0, 0], 95))


def test_a_pixel_is_off_only_beyond_ten_levels():
    truth = np.zeros((1, 2, 3), dtype=np.uint8)
    image = truth.copy()
    image[0, 0] = (accuracy.OFF_BY, 0, 0)
    image[0, 1] = (0, 0, accuracy.OFF_BY + 1)
    error = accuracy.image_error(image, truth, np.ones((1, 2), bool))
    assert error.share_off == pytest.approx(0.5)


def test_identical_images_score_zero_and_an_empty_mask_scores_nothing():
    image = np.full((3, 3, 3), 7, dtype=np.uint8)
    same = accuracy.image_error(image, image, np.ones((3, 3), bool))
    assert same.psnr == math.inf and same.mae == 0.0 and same.pixels == 9
    empty = accuracy.image_error(image, image * 0, np.zeros((3, 3), bool))
    assert empty.empty and empty.pixels == 0
    assert all(math.isnan(v) for v in (empty.mae, empty.p95, empty.psnr, empty.share_off))


def test_a_viewpoint_with_no_reflector_pixels_is_said_so_never_zero_error():
    def row(technique, viewpoint, mae, pixels):
        nan = math.nan
        return accuracy.SweepRow("s", technique, 0, viewpoint, mae, mae, nan, mae, 5.0, nan, pixels)

    rows = [
        row("raytrace", "inside", math.nan, 0),
        row("cube", "inside", math.nan, 0),
        row("cube", "outside", 2.0, 100),
        row("sphere", "inside", math.nan, 0),
    ]
    summary = {r.technique: r for r in accuracy.summarise(rows)}
    assert summary["cube"].mae == 2.0 and summary["cube"].worst_viewpoint == "outside"
    assert math.isnan(summary["sphere"].mae) and math.isnan(summary["raytrace"].mae)
    table = accuracy.summary_table(list(summary.values()))
    text = accuracy.format_text(table)
    assert "no reflector pixels" in text
    by_name = {line[0]: line for line in table[1:]}
    assert by_name["sphere"][2] == accuracy.NO_REFLECTOR_PIXELS
    assert "0.00" not in by_name["sphere"] and "0.00" not in by_name["raytrace"]
    back = accuracy.rows_from_csv(accuracy.rows_to_csv(rows))
    assert [r.pixels for r in back] == [0, 0, 100, 0] and math.isnan(back[1].mae)


def rows():
    make = accuracy.SweepRow
    return [
        make("lab", "ortho-copy", 64, "a", 4.0, 30.0, 20.0, 0.2, 5.0, 4.0),
        make("lab", "ortho-copy", 64, "b", 2.0, 10.0, 25.0, 0.1, 7.0, 6.0),
        make("lab", "stencil", 0, "a", 0.0, 0.0, math.inf, 0.0, 3.0, math.nan),
        make("lab", "stencil", 0, "b", 0.1, 1.0, 50.0, 0.0, 4.0, math.nan),
        make("sphere-sky", "stencil", 0, "a", 9.0, 9.0, 9.0, 0.9, 9.0, 9.0),
    ]


def test_summary_averages_errors_and_takes_median_times_per_technique_and_size():
    summary = accuracy.summarise(rows())
    assert [(s.scene, s.technique, s.map_size) for s in summary] == [
        ("lab", "ortho-copy", 64),
        ("lab", "stencil", 0),
        ("sphere-sky", "stencil", 0),
    ]
    ortho, stencil, _ = summary
    assert ortho.mae == 3.0 and ortho.wall_ms == 6.0 and ortho.worst_viewpoint == "a"
    assert math.isnan(stencil.gpu_ms) and stencil.worst_viewpoint == "b"
    table = accuracy.summary_table(summary[:2])
    assert table[2][1] == "-" and table[2][6] == "-"
    text = accuracy.format_text(table)
    assert text.splitlines()[0].startswith("technique") and "ortho-copy" in text
    markdown = accuracy.format_markdown(table)
    assert markdown.count("\n") == 3 and markdown.splitlines()[1].startswith("|---")


def test_the_plot_draws_the_distance_search_over_its_steps_as_one_line():
    make = accuracy.SweepRow
    sweep = [
        make("s", technique, size, "v", mae, 0.0, 30.0, 0.1, ms, ms)
        for technique, size, mae, ms in (
            ("cube-live", 256, 14.0, 30.0),
            ("cube-live distance", 64, 5.0, 20.0),
            ("cube-live distance", 256, 4.0, 40.0),
            ("cube-live distance 16+2", 256, 3.5, 60.0),
            ("cube-live distance 2+0", 256, 9.0, 33.0),
        )
    ]
    series = accuracy._series(accuracy.summarise(sweep))
    assert list(series) == [
        "cube-live",
        "cube-live distance",
        "cube-live distance by steps (map 256)",
    ]
    steps = series["cube-live distance by steps (map 256)"]
    assert [note for _, note in steps] == ["2+0", "8+2", "16+2"]
    assert [note for _, note in series["cube-live distance"]] == ["64", "256"]


def test_csv_has_a_header_and_one_line_per_row():
    text = accuracy.rows_to_csv(rows())
    lines = text.strip().splitlines()
    assert lines[0].startswith("scene,technique,map_size,viewpoint,mae")
    assert len(lines) == 6 and ",inf," in lines[3]


def test_without_matplotlib_no_plot_is_written(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert not accuracy.plot_summary(accuracy.summarise(rows()), tmp_path / "p.png", "t")
    assert not (tmp_path / "p.png").exists()


def test_the_viewpoints_look_at_the_mirror_from_its_front():
    mirror = planar_reflector(load_scene("lab20"), "mirror")
    for name, camera in accuracy.lab_viewpoints().items():
        assert camera.eye[0] > -7.0, name
        assert camera.target == (-7.0, 1.0, -2.0)
        assert np.allclose(camera.target, mirror.center)
        assert float((np.asarray(camera.eye) - mirror.center) @ mirror.normal) > 0, name


def test_csv_round_trip_keeps_every_field():
    again = accuracy.rows_from_csv(accuracy.rows_to_csv(rows()))
    assert len(again) == len(rows())
    for before, after in zip(rows(), again, strict=True):
        assert (before.scene, before.technique, before.map_size, before.viewpoint) == (
            after.scene,
            after.technique,
            after.map_size,
            after.viewpoint,
        )
        for name in ("mae", "p95", "psnr", "share_off", "wall_ms", "gpu_ms"):
            a, b = getattr(before, name), getattr(after, name)
            assert (math.isnan(a) and math.isnan(b)) or a == b  # exact: shortest repr


def test_a_csv_with_other_columns_is_refused():
    with pytest.raises(ValueError, match="expected the columns"):
        accuracy.rows_from_csv("technique,mae\nx,1\n")
    with pytest.raises(ValueError, match="line 2"):
        accuracy.rows_from_csv(accuracy.rows_to_csv(rows()).replace(",64,", ",sixty-four,", 1))


def test_erode_shrinks_a_mask_by_whole_pixels():
    mask = np.zeros((9, 9), dtype=bool)
    mask[1:8, 1:8] = True  # a 7 x 7 square
    assert np.array_equal(accuracy.erode(mask, 0), mask)
    once = accuracy.erode(mask, 1)
    assert once.sum() == 25 and once[2:7, 2:7].all()
    assert accuracy.erode(mask, 3).sum() == 1 and accuracy.erode(mask, 3)[4, 4]
    assert not accuracy.erode(mask, 4).any()
    edge = np.ones((3, 3), dtype=bool)  # outside the image counts as False
    assert accuracy.erode(edge, 1).sum() == 1


def test_planar_configurations_cover_every_capture_mode_and_size_plus_stencil():
    """... and, for ortho (a capture camera of its own), a texture the size of the
    mirror's footprint on screen, with each capture mode."""
    configs = accuracy.lab_techniques((64, 128))
    labels = [label for label, _ in configs]
    assert labels == (
        ["ortho-copy"] * 2
        + ["ortho-copy footprint"]
        + ["ortho-fbo"] * 2
        + ["ortho-fbo footprint"]
        + ["reflected-copy"] * 2
        + ["reflected-fbo"] * 2
        + ["stencil"]
    )
    assert [o.get("env_size") for _, o in configs[:2]] == [64, 128]
    lab = load_scene("lab20")
    for label, options in configs:
        mirror = planar_reflector(apply_options(lab, options), "mirror")
        assert mirror.technique == label.split("-")[0]
        if label != "stencil":
            assert mirror.capture == options["capture"]
            assert mirror.texture_size == options["env_size"]


def corrected() -> tuple[str, ...]:
    """The curved techniques that take a parallax correction."""
    return names_where(lambda t: t.kind == "curved" and t.parallax)


def test_curved_configurations_stop_at_the_largest_map_the_sweep_bakes():
    configs = accuracy.curved_techniques((64, 2048))
    assert corrected(), "the live cube map at least takes a correction"
    assert [label for label, _ in configs] == [
        *technique_names("curved"),
        *(
            f"{name} distance{steps}"
            for name in corrected()
            for steps in ("", " 2+0", " 4+1", " 16+2", " 32+4")
        ),
    ]
    assert all(o["map_size"] == 64 for _, o in configs)
    assert accuracy.ENVMAP_MAX_SIZE < 2048
    sphere = load_scene("chrome_sphere")
    for label, options in configs:
        reflector = curved_reflector(apply_options(sphere, options), "sphere")
        assert reflector.technique == label.split()[0]
        if label in corrected():  # the plain one has no correction
            assert reflector.parallax is None
        elif "distance" in label:
            steps = label.split()[-1] if label[-1].isdigit() else accuracy.DEFAULT_STEPS
            assert reflector.parallax == DistanceSearch(*map(int, steps.split("+")))


def test_the_live_cube_map_is_measured_with_each_proxy_and_each_step_count():
    proxies = (("box", "box:-4,-2,-4,4,4,4"), ("sphere", "sphere:3"))
    configs = accuracy.curved_techniques((64, 256, 512), proxies, ("4+1", "8+2"))
    for name in corrected():
        labels = [(label, o["map_size"]) for label, o in configs if label.startswith(f"{name} ")]
        assert labels == [
            (f"{name} box", 64),
            (f"{name} box", 256),
            (f"{name} box", 512),
            (f"{name} sphere", 64),
            (f"{name} sphere", 256),
            (f"{name} sphere", 512),
            (f"{name} distance", 64),
            (f"{name} distance", 256),
            (f"{name} distance", 512),
            (f"{name} distance 4+1", 256),
        ]
        room = load_scene("sphere_room")
        boxed = apply_options(room, dict(next(o for label, o in configs if label == f"{name} box")))
        assert curved_reflector(boxed, "sphere").parallax == BoxProxy(
            (-4.0, -2.0, -4.0), (4.0, 4.0, 4.0)
        )
    assert accuracy.search_map_size((64, 128)) == 128
    assert accuracy.search_map_size((512, 1024)) == 512


def test_proxies_are_the_box_around_the_objects_and_the_sphere_inside_it():
    assert accuracy.proxies_for(load_scene("sphere_room")) == (
        ("box", "box:-4,-2,-4,4,4,4"),
        ("sphere", "sphere:3"),
    )  # the room; 3 to the floor
    box, sphere = accuracy.proxies_for(load_scene("chrome_sphere"))
    assert box[1].startswith("box:-2.81") and sphere == ("sphere", "sphere:2")
    bare = load_scene("chrome_sphere")
    assert accuracy.proxies_for(replace(bare, objects=())) == ()
    assert accuracy.proxies_for(load_scene("lab20")) == ()


def test_a_scene_gets_the_configurations_of_its_kinds_of_reflector():
    sizes = (64,)
    labels = {
        name: [label for label, _ in accuracy.scene_techniques(load_scene(name), sizes, steps=())]
        for name in ("lab20", "chrome_sphere", "mirror_and_sphere", "no_mirror")
    }
    assert labels["lab20"] == [label for label, _ in accuracy.lab_techniques(sizes)]
    assert labels["chrome_sphere"] == [
        *technique_names("curved"),
        *(f"{name} distance" for name in corrected()),
    ]
    assert labels["mirror_and_sphere"] == labels["lab20"] + labels["chrome_sphere"]
    assert labels["no_mirror"] == []


def test_panels_of_the_sweep():
    quick = accuracy.SweepSettings.quick()
    lab = accuracy.lab_panel(quick)
    assert quick.viewpoints is not None
    assert list(lab.viewpoints) == list(quick.viewpoints)
    assert lab.scene == load_scene("lab20") and lab.supersample == 1
    with pytest.raises(ValueError, match="unknown viewpoint 'nowhere'"):
        accuracy.lab_panel(accuracy.SweepSettings(viewpoints=("nowhere",)))
    sky, objects, room = accuracy.sphere_panels(accuracy.SweepSettings())
    assert sky.scene.objects == () and objects.scene.objects != ()
    assert list(sky.viewpoints) == ["default", "close"] and sky.supersample == 4
    assert list(accuracy.sphere_panels(quick)[0].viewpoints) == ["default"]
    # the sky alone is measured with the proxies of the sphere among its objects
    assert sky.proxies == objects.proxies == accuracy.proxies_for(load_scene("sphere"))
    assert room.scene == load_scene("sphere_room") and room.name == "sphere-room"
    assert room.proxies == accuracy.proxies_for(room.scene) and (room.supersample, room.inset) == (
        4,
        1,
    )
    cone = accuracy.file_panel(load_scene("cone"))
    assert (cone.supersample, cone.inset) == (4, 1)
    assert cone.viewpoints == {"camera": load_scene("cone").camera}
    assert cone.proxies == accuracy.proxies_for(load_scene("cone"))
    assert accuracy.file_panel(load_scene("two_mirrors")).supersample == 1


def test_the_report_is_remade_from_a_saved_csv_without_measuring(tmp_path):
    saved = tmp_path / "saved.csv"
    saved.write_text(accuracy.rows_to_csv(rows()))
    said: list[str] = []
    out = tmp_path / "report"
    assert (
        accuracy.run_command(accuracy.SweepSettings.quick(), "all", out, saved, say=said.append)
        == 0
    )
    markdown = (out / "accuracy.md").read_text()
    assert "from saved.csv" in markdown and markdown.count("| ortho-copy | 64 |") == 1
    assert not (out / "accuracy.csv").exists()  # nothing measured, nothing re-written
    assert said[-1].startswith("wrote ") and "accuracy.md" in said[-1]
    (tmp_path / "bad.csv").write_text("technique,mae\n")
    with pytest.raises(ValueError, match=r"--from-csv: .*bad\.csv: expected the columns"):
        accuracy.run_command(accuracy.SweepSettings.quick(), "all", out, tmp_path / "bad.csv")
    with pytest.raises(ValueError, match="--from-csv: cannot read"):
        accuracy.run_command(accuracy.SweepSettings.quick(), "all", out, tmp_path / "none.csv")


@pytest.mark.skipif(not flip.available(), reason=str(flip.MISSING))
def test_flip_is_averaged_over_the_region_only_and_zero_for_identical_pictures():
    rng = np.random.default_rng(3)
    truth = rng.integers(0, 256, (32, 48, 3), dtype=np.uint8)
    image = truth.copy()
    image[:, 24:] = 255 - image[:, 24:]  # the right half is plainly wrong
    left = np.zeros((32, 48), bool)
    left[:, :20] = True  # away from the wrong half's edge, which FLIP's filters spread
    assert accuracy.image_error(truth, truth, np.ones((32, 48), bool)).flip == 0.0
    assert accuracy.image_error(image, truth, left).flip < 0.02
    assert accuracy.image_error(image, truth, ~left).flip > 0.3


def test_without_flip_evaluator_the_flip_figure_is_nan_and_the_reason_is_given(monkeypatch):
    monkeypatch.setattr(flip, "_evaluator", None)
    monkeypatch.setattr(flip, "MISSING", "no flip-evaluator here")
    image = np.zeros((4, 4, 3), np.uint8)
    assert math.isnan(accuracy.image_error(image, image, np.ones((4, 4), bool)).flip)
    assert flip.flip_map(image, image) is None and not flip.available()
