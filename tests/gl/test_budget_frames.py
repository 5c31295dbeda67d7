"""Frames under a budget, on llvmpipe: the renderer draws what the budget chose, the plan
stays lossless with a budget (planned frames equal ``--no-plan`` frames), a frame without
a budget is what it was, ``render --stats`` and ``plan`` report the choice, and ``bench
budget --quick`` runs end to end (its figures are the benchmark's, not checked here)."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest

from mirrorlab.budget.scenes import motion
from mirrorlab.cli import main
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import Budget

SIZE = (64, 64)


def _frames(renderer: SceneRenderer, target: Framebuffer, scenes, use_plan=True):
    images, stats = [], []
    for scene in scenes:
        stats.append(renderer.render(scene, target, use_plan=use_plan))
        images.append(target.read())
    return images, stats


@pytest.mark.parametrize("budget", [Budget(max_error=0.03), Budget(max_ms=6.0)])
def test_a_budget_draws_its_choice_and_the_plan_stays_lossless(registry, budget):
    scene = load_scene("mirror_and_sphere")
    scenes = [replace(motion(scene, f, 3), budget=budget) for f in range(3)]
    target = Framebuffer(registry, *SIZE)
    planned = SceneRenderer(registry)
    unplanned = SceneRenderer(registry)
    plain = SceneRenderer(registry)
    try:
        images, stats = _frames(planned, target, scenes)
        every, _ = _frames(unplanned, target, scenes, use_plan=False)
        for frame, (image, other) in enumerate(zip(images, every, strict=True)):
            assert np.array_equal(image, other), f"frame {frame} differs from --no-plan"
        # the frame is the chosen configuration's, drawn without a budget
        for scene, image, found in zip(scenes, images, stats, strict=True):
            assert found.budget is not None and found.budget.budget == budget
            chosen = list(scene.reflectors)
            for i, choice in enumerate(found.budget.choices):
                if choice.chosen is not None:
                    chosen[i] = choice.chosen.candidate.apply(chosen[i])
            plain.state.clear()
            plain.memo.clear()
            expected = replace(scene, reflectors=tuple(chosen), budget=None)
            assert plain.render(expected, target).budget is None
            assert np.array_equal(target.read(), image)
    finally:
        for renderer in (planned, unplanned, plain):
            renderer.release()
        target.release()


def test_render_stats_and_plan_report_the_choice(tmp_path, capsys):
    out = tmp_path / "x.png"
    assert (
        main(
            [
                "render",
                "chrome_sphere",
                "--max-error",
                "0.05",
                "--frames",
                "2",
                "--size",
                "64x64",
                "--stats",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    said = capsys.readouterr().out
    assert "budget FLIP <= 0.05: predicted" in said
    assert "sphere: " in said and "bound" in said
    assert "planned and --no-plan frames are the same" in said
    assert main(["plan", "lab20", "--max-ms", "8", "--frames", "1", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    budget = document["frames"][0]["budget"]
    assert budget["kind"] == "max_ms" and budget["reflectors"][0]["candidates"]
    chosen = budget["reflectors"][0]["chosen"]
    drawn = document["frames"][0]["draws"][0]["technique"]
    assert chosen.split(" ")[0].split("-")[0] == drawn


def test_bench_budget_quick_writes_its_csv_summary_and_plot(tmp_path, capsys):
    out = tmp_path / "bench"
    code = main(
        [
            "bench",
            "budget",
            "lab20",
            "--quick",
            "--frames",
            "2",
            "--max-error",
            "0.05,mae=4",
            "--max-ms",
            "10",
            "--out-dir",
            str(out),
        ]
    )
    assert code == 0
    said = capsys.readouterr()
    assert "held" in said.out and "cost/oracle" in said.out
    summary = json.loads((out / "summary.json").read_text())
    for key in (
        "held_share",
        "worst_overrun",
        "cost_vs_oracle",
        "cost_vs_best_fixed",
        "error_vs_oracle",
    ):
        assert key in summary, key
    assert 0.0 <= summary["held_share"] <= 1.0
    with open(out / "budget.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 3 * 2  # three budgets, two frames, one reflector
    assert {"frame", "reflector", "chosen", "predicted_error", "true_error", "cost_ms"} <= set(
        rows[0]
    )
    assert all(float(r["true_error"]) >= 0 for r in rows)
    assert (out / "budget.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    "arguments, message",
    [
        ([], "--max-error: give --max-error"),
        (["--max-error", "2"], "--max-error: expected a mean FLIP"),
        (["--max-ms", "0"], "--max-ms: expected milliseconds above 0"),
    ],
)
def test_bench_budget_bad_input_is_one_line_and_writes_nothing(
    tmp_path, capsys, arguments, message
):
    out = tmp_path / "bench"
    assert main(["bench", "budget", "lab20", "--quick", *arguments, "--out-dir", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
