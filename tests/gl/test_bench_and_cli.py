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
    assert "technique" in out.out and "reflected-fbo" in out.out
    assert "20/20" in out.err  # the progress bar reached the end
    with open(tmp_path / "accuracy.csv") as stream:
        table = list(csv.DictReader(stream))
    # 2 viewpoints x (ray tracer + 2 methods x 2 captures x 2 sizes + stencil)
    assert len(table) == 20
    by_key = {(r["technique"], r["map_size"], r["viewpoint"]): r for r in table}
    assert float(by_key[("raytrace", "0", "60 deg")]["mae"]) == 0.0
    ortho = float(by_key[("ortho-copy", "128", "60 deg")]["mae"])
    reflected = float(by_key[("reflected-copy", "128", "60 deg")]["mae"])
    stencil = float(by_key[("stencil", "0", "60 deg")]["mae"])
    assert reflected < 0.2 * ortho and stencil < 0.2 * ortho
    assert all(float(r["wall_ms"]) > 0 for r in table)
    assert "| technique |" in (tmp_path / "accuracy.md").read_text()
    with Image.open(tmp_path / "accuracy.png") as plot:
        assert plot.size[0] > 400 and np.asarray(plot.convert("L")).std() > 10


def test_bench_refuses_a_file_as_its_folder_and_unknown_benchmarks(tmp_path, capsys):
    blocker = tmp_path / "taken"
    blocker.write_text("keep me")
    assert main(["bench", "accuracy", "--quick", "--out-dir", str(blocker)]) == 2
    assert main(["bench", "speed"]) == 2
    assert main(["bench", "accuracy", "--sizes", "64,zero"]) == 2
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 3 and "--out-dir" in errors[0] and "accuracy" in errors[1]
    assert "--sizes" in errors[2]
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


def test_plan_command_explains_what_runs(capsys):
    assert main(["plan", "--method", "reflected"]) == 0
    assert main(["plan", "--camera", "-12,2,-2", "--target", "0,0,0"]) == 0
    text = capsys.readouterr().out
    assert "run  reflected-capture" in text and "skip reflected-capture" in text
    assert "behind" in text
