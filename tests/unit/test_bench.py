"""The sweep's scoring and reporting, on made-up numbers (no GL)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from mirrorlab import bench


def test_image_error_scores_only_the_masked_pixels():
    truth = np.zeros((4, 4, 3), dtype=np.uint8)
    image = truth.copy()
    image[0, 0] = (20, 0, 0)  # off by 20 in one channel
    image[3, 3] = (255, 255, 255)  # outside the mask: ignored
    mask = np.zeros((4, 4), dtype=bool)
    mask[:2, :2] = True
    error = bench.image_error(image, truth, mask)
    assert error.mae == pytest.approx(20 / 12)  # 4 pixels x 3 channels
    assert error.share_off == pytest.approx(0.25)
    assert error.psnr == pytest.approx(10 * math.log10(255 ** 2 / (400 / 12)))
    assert error.p95 == pytest.approx(np.percentile([20, 0, 0, 0], 95))


def test_identical_images_and_empty_masks_score_zero():
    image = np.full((3, 3, 3), 7, dtype=np.uint8)
    assert bench.image_error(image, image, np.ones((3, 3), bool)).psnr == math.inf
    empty = bench.image_error(image, image * 0, np.zeros((3, 3), bool))
    assert (empty.mae, empty.share_off) == (0.0, 0.0)


def rows():
    make = bench.SweepRow
    return [
        make("lab", "ortho-copy", 64, "a", 4.0, 30.0, 20.0, 0.2, 5.0, 4.0),
        make("lab", "ortho-copy", 64, "b", 2.0, 10.0, 25.0, 0.1, 7.0, 6.0),
        make("lab", "stencil", 0, "a", 0.0, 0.0, math.inf, 0.0, 3.0, math.nan),
        make("lab", "stencil", 0, "b", 0.1, 1.0, 50.0, 0.0, 4.0, math.nan),
        make("sphere-sky", "stencil", 0, "a", 9.0, 9.0, 9.0, 0.9, 9.0, 9.0),
    ]


def test_summary_averages_errors_and_takes_median_times_per_technique_and_size():
    summary = bench.summarise(rows())
    assert [(s.scene, s.technique, s.map_size) for s in summary] == [
        ("lab", "ortho-copy", 64), ("lab", "stencil", 0), ("sphere-sky", "stencil", 0)]
    ortho, stencil, _ = summary
    assert ortho.mae == 3.0 and ortho.wall_ms == 6.0 and ortho.worst_viewpoint == "a"
    assert math.isnan(stencil.gpu_ms) and stencil.worst_viewpoint == "b"
    table = bench.summary_table(summary[:2])
    assert table[2][1] == "-" and table[2][6] == "-"
    text = bench.format_text(table)
    assert text.splitlines()[0].startswith("technique") and "ortho-copy" in text
    markdown = bench.format_markdown(table)
    assert markdown.count("\n") == 3 and markdown.splitlines()[1].startswith("|---")


def test_csv_has_a_header_and_one_line_per_row():
    text = bench.rows_to_csv(rows())
    lines = text.strip().splitlines()
    assert lines[0].startswith("scene,technique,map_size,viewpoint,mae")
    assert len(lines) == 6 and ",inf," in lines[3]


def test_without_matplotlib_no_plot_is_written(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    assert not bench.plot_summary(bench.summarise(rows()), tmp_path / "p.png", "t")
    assert not (tmp_path / "p.png").exists()


def test_the_viewpoints_look_at_the_mirror_from_its_front():
    for name, camera in bench.lab_viewpoints().items():
        assert camera.eye[0] > -7.0, name
        assert camera.target == (-7.0, 1.0, -2.0)


def test_csv_round_trip_keeps_every_field():
    again = bench.rows_from_csv(bench.rows_to_csv(rows()))
    assert len(again) == len(rows())
    for before, after in zip(rows(), again, strict=True):
        assert (before.scene, before.technique, before.map_size, before.viewpoint) == (
            after.scene, after.technique, after.map_size, after.viewpoint)
        for name in ("mae", "p95", "psnr", "share_off", "wall_ms", "gpu_ms"):
            a, b = getattr(before, name), getattr(after, name)
            assert (math.isnan(a) and math.isnan(b)) or a == b  # exact: shortest repr


def test_a_csv_with_other_columns_is_refused():
    with pytest.raises(ValueError, match="expected the columns"):
        bench.rows_from_csv("technique,mae\nx,1\n")
    with pytest.raises(ValueError, match="line 2"):
        bench.rows_from_csv(bench.rows_to_csv(rows()).replace(",64,", ",sixty-four,", 1))
