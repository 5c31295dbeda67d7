"""The accuracy sweep's scoring, configurations and reporting, on made-up numbers and the
scene files (no GL)."""

from __future__ import annotations

import math
import sys
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab import accuracy, flip
from mirrorlab.options import apply_options
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import CAPTURE_MODES, FOOTPRINT_TEXTURE, BoxProxy, DistanceSearch
from mirrorlab.techniques import technique_names, techniques
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
    gl_ms = table[0].index("GL ms")
    assert table[2][1] == "-" and table[2][gl_ms] == "-"
    assert "miss share" not in table[0]  # no technique here has a fallback
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
    """Every planar technique of the registry: one that captures a texture at each capture
    mode and size (and, with a capture camera of its own as ortho's, a texture the size
    of the mirror's footprint on screen, with each capture mode); one that captures
    nothing of its own (drawn in place, or from the view's own frame) once."""
    sizes = (64, 128)
    configs = accuracy.lab_techniques(sizes)
    expected: list[tuple[str, object]] = []
    for entry in techniques("planar"):
        if entry.texture not in accuracy.CAPTURED:
            continue
        for capture in CAPTURE_MODES:
            expected += [(f"{entry.name}-{capture}", size) for size in sizes]
            if entry.own_camera:
                expected.append((f"{entry.name}-{capture} footprint", FOOTPRINT_TEXTURE))
    expected += [(t.name, None) for t in techniques("planar") if t.texture not in accuracy.CAPTURED]
    assert [(label, o.get("env_size")) for label, o in configs] == expected
    assert {o["method"] for _, o in configs} == set(technique_names("planar"))
    # the shipped three among them: the derivation above is not of an empty registry
    assert {"ortho-copy footprint", "reflected-fbo", "stencil"} <= {label for label, _ in configs}
    lab = load_scene("lab20")
    for _, options in configs:
        mirror = planar_reflector(apply_options(lab, options), "mirror")
        assert mirror.technique == options["method"]
        if "capture" in options:
            assert mirror.capture == options["capture"]
            assert mirror.texture_size == options["env_size"]


def assert_curved_configurations(configs, sizes) -> None:
    """Every curved technique of the registry plain at each of ``sizes`` (in the registry's
    order, first), and every other configuration a parallax correction of a technique
    that takes one, labelled ``<technique> <correction>``, that the scene's options give
    as labelled."""
    plain = [(t.name, size) for t in techniques("curved") for size in sizes]
    assert [(label, o["map_size"]) for label, o in configs[: len(plain)]] == plain
    corrected = {t.name for t in techniques("curved") if t.parallax}
    sphere = load_scene("chrome_sphere")
    for index, (label, options) in enumerate(configs):
        reflector = curved_reflector(apply_options(sphere, options), "sphere")
        assert reflector.technique == options["method"]
        if index < len(plain):
            assert label == options["method"]
            assert reflector.parallax is None  # a live map plain: no correction
            continue
        name, correction = label.split(" ", 1)
        assert name == options["method"] and name in corrected, label
        assert options["parallax"] != "none", label
        if correction.startswith("distance"):
            steps = correction.split()[-1] if label[-1].isdigit() else accuracy.DEFAULT_STEPS
            assert reflector.parallax == DistanceSearch(*map(int, steps.split("+"))), label


def test_curved_configurations_stop_at_the_largest_map_the_sweep_bakes():
    configs = accuracy.curved_techniques((64, 2048))
    assert_curved_configurations(configs, (64,))
    assert accuracy.ENVMAP_MAX_SIZE < 2048
    assert all(o["map_size"] == 64 for _, o in configs)
    # the distance search's other step counts, at the one size there is
    others = [s for s in accuracy.DISTANCE_STEPS if s != accuracy.DEFAULT_STEPS]
    labels = {label for label, _ in configs}
    assert {f"cube-live distance {steps}" for steps in others} <= labels


def test_the_live_cube_map_is_measured_with_each_proxy_and_each_step_count():
    proxies = (("box", "box:-4,-2,-4,4,4,4"), ("sphere", "sphere:3"))
    configs = accuracy.curved_techniques((64, 256, 512), proxies, ("4+1", "8+2"))
    assert_curved_configurations(configs, (64, 256, 512))
    labels = [(label, o["map_size"]) for label, o in configs if label.startswith("cube-live ")]
    assert labels == [
        ("cube-live box", 64),
        ("cube-live box", 256),
        ("cube-live box", 512),
        ("cube-live sphere", 64),
        ("cube-live sphere", 256),
        ("cube-live sphere", 512),
        ("cube-live distance", 64),
        ("cube-live distance", 256),
        ("cube-live distance", 512),
        ("cube-live distance 4+1", 256),
    ]
    assert accuracy.search_map_size((64, 128)) == 128
    assert accuracy.search_map_size((512, 1024)) == 512
    room = load_scene("sphere_room")
    boxed = dict(configs)["cube-live box"]  # the last size's options
    assert curved_reflector(apply_options(room, boxed), "sphere").parallax == BoxProxy(
        (-4.0, -2.0, -4.0), (4.0, 4.0, 4.0)
    )


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
    # every curved technique, then (no proxies, no other steps) the distance search of
    # each that takes a parallax correction
    curved = technique_names("curved")
    assert labels["chrome_sphere"][: len(curved)] == list(curved)
    corrected = {f"{t.name} distance" for t in techniques("curved") if t.parallax}
    rest = labels["chrome_sphere"][len(curved) :]
    assert sorted(rest) == sorted(corrected) and "cube-live distance" in corrected
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


# ------------------------------------------------------------ FLIP, miss share, frontier


def measured_row(technique, size, viewpoint, mae, ms, flip=math.nan, miss=math.nan, psnr=30.0):
    return accuracy.SweepRow(
        "s", technique, size, viewpoint, mae, mae, psnr, mae / 10, ms, ms, 100, flip, miss
    )


def test_a_csv_from_before_each_later_column_still_loads():
    """The sweep's CSVs grew columns (pixels, then flip and miss_share): a CSV written before
    any of them loads, its missing figures NaN (pixels -1); the tables and plot then say
    FLIP is empty, never zero."""
    full = [measured_row("cube", 64, "a", 2.0, 5.0, flip=0.05, miss=0.25)]
    text = accuracy.rows_to_csv(full)
    header, line = text.splitlines()
    assert header.endswith(",pixels,flip,miss_share") and line.endswith(",100,0.05,0.25")
    names = header.split(",")
    for kept in range(accuracy.REQUIRED_COLUMNS, len(names) + 1):
        cut = "\n".join(",".join(row.split(",")[:kept]) for row in (header, line)) + "\n"
        (row,) = accuracy.rows_from_csv(cut)
        assert (row.technique, row.mae, row.wall_ms) == ("cube", 2.0, 5.0)
        assert row.pixels == (100 if kept > names.index("pixels") else -1)
        assert row.flip == 0.05 if kept > names.index("flip") else math.isnan(row.flip)
        assert row.miss_share == 0.25 if kept == len(names) else math.isnan(row.miss_share)
    with pytest.raises(ValueError, match="expected the columns"):
        accuracy.rows_from_csv(",".join(names[: accuracy.REQUIRED_COLUMNS - 1]) + "\n")
    swapped = [*names[:-2], names[-1], names[-2]]  # the later columns out of their order
    with pytest.raises(ValueError, match="expected the columns"):
        accuracy.rows_from_csv(",".join(swapped) + "\n" + line + "\n")
    with pytest.raises(ValueError, match="line 2: more cells"):
        accuracy.rows_from_csv(f"{header}\n{line},7\n")
    with pytest.raises(ValueError, match="line 2: no cell for 'miss_share'"):
        accuracy.rows_from_csv(f"{header}\n{line.rsplit(',', 1)[0]}\n")


def test_the_fallback_share_counts_only_the_scored_pixels():
    mask = np.zeros((4, 4), bool)
    mask[:, :2] = True  # 8 scored pixels
    fallback = np.zeros((4, 4), bool)
    fallback[:1, :] = True  # 2 of them fell back; the 2 outside the mask are not counted
    assert accuracy.fallback_share(fallback, mask) == pytest.approx(0.25)
    assert math.isnan(accuracy.fallback_share(None, mask))  # a technique without one
    assert math.isnan(accuracy.fallback_share(fallback, np.zeros((4, 4), bool)))
    with pytest.raises(ValueError, match="fallback mask of shape"):
        accuracy.fallback_share(fallback[:2], mask)
    truth = accuracy.Truth(np.zeros((4, 4, 3), np.uint8), mask, 1.0)
    frames = [accuracy.Frame(np.zeros((4, 4, 3), np.uint8), fallback), accuracy.Frame(truth.image)]
    (first, missed), (second, none) = accuracy.score_frames(truth, frames)
    assert missed == pytest.approx(0.25) and math.isnan(none)
    assert first.mae == second.mae == 0.0 and first.pixels == 8


def test_flip_and_miss_share_are_averaged_and_shown_where_there_are_any():
    rows = [
        measured_row("ssr-like", 0, "a", 2.0, 5.0, flip=0.1, miss=0.2, psnr=math.inf),
        measured_row("ssr-like", 0, "b", 4.0, 7.0, flip=0.3, miss=0.4, psnr=20.0),
        measured_row("cube", 64, "a", 1.0, 3.0, flip=0.05),
        measured_row("cube", 64, "b", math.nan, 3.0),  # no reflector pixels: left out
    ]
    ssr, cube = accuracy.summarise(rows)
    assert ssr.flip == pytest.approx(0.2) and ssr.miss_share == pytest.approx(0.3)
    # the PSNR of the mean squared error: an exact viewpoint and one at 20 dB -> 23.0 dB
    assert ssr.psnr == pytest.approx(20.0 + 10 * math.log10(2))
    assert cube.flip == 0.05 and math.isnan(cube.miss_share) and cube.psnr == 30.0
    table = accuracy.summary_table([ssr, cube])
    header = table[0]
    assert header[header.index("off >10") + 1 : header.index("wall ms")] == ["FLIP", "miss share"]
    by_name = {line[0]: dict(zip(header, line, strict=True)) for line in table[1:]}
    assert by_name["ssr-like"]["FLIP"] == "0.200" and by_name["ssr-like"]["miss share"] == "30.0%"
    assert by_name["cube"]["miss share"] == "-" and by_name["cube"]["PSNR dB"] == "30.0"
    assert accuracy.flip_note([ssr, cube], "why") is None
    assert math.isinf(accuracy.summarise(rows[:1])[0].psnr)


def test_without_flip_the_column_is_empty_and_the_table_says_why():
    rows = [measured_row("cube", 64, "a", 1.0, 3.0), measured_row("sphere", 64, "a", 2.0, 2.0)]
    truth = accuracy.SweepRow("s", "raytrace 4x4", 0, "a", 0.0, 0.0, math.inf, 0.0, 900.0, 1.0)
    summary = accuracy.summarise([truth, *rows])
    table = accuracy.summary_table(summary)
    flips = [line[table[0].index("FLIP")] for line in table[1:]]
    assert flips == ["", "", ""]  # empty, never a zero (the truth's too: not measured)
    note = accuracy.flip_note(summary, flip.MISSING or "flip-evaluator is missing")
    assert note is not None and note.startswith("FLIP is empty: ")
    front = accuracy.frontier(summary, "s")
    assert front.metric == "mae" and front.note == "by MAE, as FLIP is empty"
    assert [r.technique for r in front.rows] == ["sphere", "cube"]  # 2 ms, then 1/255
    assert "MAE" in accuracy.frontier_heading(front)


finite = st.floats(0.0, 1e3, allow_nan=False)


@settings(max_examples=60)
@given(st.lists(st.tuples(finite | st.just(math.nan), finite | st.just(math.nan)), max_size=25))
def test_the_pareto_front_is_exactly_the_points_nothing_beats(points):
    front = accuracy.pareto_front(points)

    def beats(a, b):
        return a[0] <= b[0] and a[1] <= b[1] and (a[0] < b[0] or a[1] < b[1])

    known = [i for i, p in enumerate(points) if not any(math.isnan(v) for v in p)]
    for i in known:
        beaten = any(beats(points[j], points[i]) for j in known)
        assert (i in front) == (not beaten), (i, points)
    assert set(front) <= set(known)
    assert [points[i] for i in front] == sorted(points[i] for i in front)


def test_the_frontier_names_the_technique_on_it_at_each_cost():
    rows = [
        measured_row("ortho", 64, "a", 4.0, 5.0, flip=0.20),
        measured_row("ortho", 512, "a", 4.0, 9.0, flip=0.19),  # slower, barely better
        measured_row("reflected", 64, "a", 0.5, 6.0, flip=0.02),
        measured_row("stencil", 0, "a", 0.1, 6.0, flip=0.03),  # as fast, worse FLIP
        measured_row("big", 0, "a", 0.0, 40.0, flip=0.001),
        accuracy.SweepRow("s", "raytrace", 0, "a", 0.0, 0.0, math.inf, 0.0, 900.0, 1.0, 100, 0.0),
    ]
    summary = accuracy.summarise(rows)
    front = accuracy.frontier(summary, "s")
    assert front.metric == "flip" and front.note is None
    assert [(r.technique, r.map_size) for r in front.rows] == [
        ("ortho", 64),
        ("reflected", 64),
        ("big", 0),
    ]  # the truth is the reference, never a point of it
    table = accuracy.frontier_table(front)
    assert table[1][:4] == ["5.00", "ortho", "64", "0.200"] and table[3][2] == "-"
    by_mae = accuracy.frontier(summarise_without_flip(summary), "s")
    assert [r.technique for r in by_mae.rows] == ["ortho", "stencil", "big"]
    partly = accuracy.frontier([replace(summary[0], flip=math.nan), *summary[1:]], "s")
    assert partly.metric == "mae"
    assert partly.note == "by MAE: 1 of 5 configurations have no FLIP figure"


def summarise_without_flip(summary):
    return [replace(r, flip=math.nan) for r in summary]


def test_the_report_names_the_frontier_and_why_flip_is_empty(tmp_path, monkeypatch):
    """A CSV from before the FLIP column: the tables' FLIP cells empty and the reason
    under them; each scene's frontier by MAE, in the printed text and in accuracy.md."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # the tables only: no plot
    old = tmp_path / "old.csv"
    columns = accuracy.REQUIRED_COLUMNS + 1  # up to "pixels"
    text = accuracy.rows_to_csv(rows())
    old.write_text("\n".join(",".join(line.split(",")[:columns]) for line in text.splitlines()))
    said: list[str] = []
    out = tmp_path / "report"
    assert accuracy.run_command(accuracy.SweepSettings.quick(), "all", out, old, said.append) == 0
    printed = "\n".join(said)
    assert printed.count("FLIP is empty: old.csv holds no FLIP figures") == 2  # lab, sphere-sky
    assert printed.count("Pareto frontier (MAE against median wall time") == 2
    frontier_lines = printed.split("Pareto frontier")[1].splitlines()
    assert any(line.split()[:2] == ["3.50", "stencil"] for line in frontier_lines)
    markdown = (out / "accuracy.md").read_text()
    assert markdown.count("FLIP is empty: old.csv") == 2 and "| 3.50 | stencil | - |" in markdown


@pytest.mark.skipif(not flip.available(), reason=str(flip.MISSING))
@settings(max_examples=12, derandomize=True)
@given(
    st.integers(0, 39),
    st.integers(0, 47),
    st.integers(1, 40),
    st.integers(1, 48),
    st.booleans(),
)
def test_flip_over_a_region_is_the_whole_pictures_map_there(top, left, height, width, scatter):
    """FLIP of the region and what lies within its reach (flip.REACH pixels) only, as the
    sweep computes it, is the whole pictures' FLIP map averaged over the region: for a
    region anywhere, at an edge or in a corner, whole or scattered."""
    rng = np.random.default_rng(top * 100 + left)
    truth = rng.integers(0, 256, (40, 48, 3), dtype=np.uint8)
    image = truth.copy()
    image[10:30, 12:40] = 255 - image[10:30, 12:40]
    mask = np.zeros((40, 48), bool)
    mask[top : top + height, left : left + width] = True
    if scatter:
        mask &= rng.random((40, 48)) < 0.3
    if not mask.any():
        assert math.isnan(flip.region_mean(image, truth, mask) or 0.0)
        return
    whole = flip.flip_map(image, truth)
    assert whole is not None
    assert flip.region_mean(image, truth, mask) == pytest.approx(whole[mask].mean(), abs=1e-6)


def test_a_sweep_takes_several_scenes_each_a_panel_of_its_own():
    quick = accuracy.SweepSettings.quick()
    cone, room = load_scene("cone"), load_scene("sphere_room")
    panels = accuracy.panels_for(["lab", cone, room], quick)
    assert [p.name for p in panels] == ["lab", cone.name, room.name]
    assert panels[1] == accuracy.file_panel(cone)
    assert [p.name for p in accuracy.panels_for("all", quick)] == [
        "lab",
        "sphere-sky",
        "sphere-objects",
        "sphere-room",
    ]
    assert accuracy.panels_for(cone, quick) == [accuracy.file_panel(cone)]
    with pytest.raises(ValueError, match="two scenes named 'spheremap_cone'"):
        accuracy.panels_for([cone, cone], quick)
    with pytest.raises(ValueError, match="two scenes named 'lab'"):
        accuracy.panels_for(["all", "lab"], quick)
