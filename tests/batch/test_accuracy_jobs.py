"""The accuracy sweep across the executor (``mirrorlab bench accuracy --jobs J``): truths
traced and frames scored by worker processes give the same figures as one process; only
the timing columns differ."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

from mirrorlab.accuracy import SweepSettings, lab_panel, sphere_panels, sweep_rows
from mirrorlab.cli import main
from mirrorlab.scene.model import CAPTURE_MODES
from mirrorlab.techniques import techniques
from tests import REPO_DIR

TIMES = ("wall_ms", "gpu_ms")


def figures(folder: Path) -> list[dict[str, str]]:
    with open(folder / "accuracy.csv") as stream:
        return [{k: v for k, v in row.items() if k not in TIMES} for row in csv.DictReader(stream)]


def test_the_quick_sweep_on_two_processes_gives_the_figures_of_one(tmp_path, capsys):
    one, two = tmp_path / "one", tmp_path / "two"
    assert main(["bench", "accuracy", "--quick", "--jobs", "1", "--out-dir", str(one)]) == 0
    assert "truths and scoring on serial (1 worker)" in capsys.readouterr().out
    # a process of its own: a pool forks, and this test process holds EGL contexts (it
    # imports the tests, so a run with twins of techniques registered has them there too)
    result = subprocess.run(
        [
            sys.executable,
            "-c",
            "import sys, tests; from mirrorlab.cli import main; sys.exit(main(sys.argv[1:]))",
            "bench",
            "accuracy",
            "--quick",
            "--jobs",
            "2",
            "--out-dir",
            str(two),
        ],
        capture_output=True,
        text=True,
        cwd=REPO_DIR,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "truths and scoring on pool (2 workers)" in result.stdout
    serial, parallel = figures(one), figures(two)
    # every configuration at every viewpoint, the ortho capture sized to its footprint
    # among them (each capture mode of each technique with a camera of its own, at each of
    # the lab's viewpoints)
    quick = SweepSettings.quick()
    lab = lab_panel(quick)
    assert len(serial) == sweep_rows([lab, *sphere_panels(quick)], quick)
    own = sum(t.own_camera for t in techniques("planar") if not t.draws_inline)
    footprints = len(lab.viewpoints) * len(CAPTURE_MODES) * own
    assert (
        footprints > 0 and sum(r["technique"].endswith(" footprint") for r in serial) == footprints
    )
    assert serial == parallel
    # the figures are real measurements: the ray tracer's rows score zero, others do not
    assert {r["mae"] for r in serial if r["technique"].startswith("raytrace")} == {"0.0"}
    assert any(float(r["mae"]) > 1.0 for r in serial if r["technique"] == "ortho-copy")
    with open(two / "accuracy.csv") as stream:
        assert all(float(r["wall_ms"]) > 0 for r in csv.DictReader(stream))


def test_bad_executor_options_of_the_sweep(capsys, tmp_path):
    for extra, words in (
        (["--jobs", "0"], "--jobs: expected a whole number from 1"),
        (["--engine", "threads"], "--engine"),
    ):
        code: int | str | None = None
        try:
            code = main(["bench", "accuracy", "--quick", "--out-dir", str(tmp_path / "x"), *extra])
        except SystemExit as stop:  # argparse refuses a choice itself, with its usage
            code = stop.code
        assert code == 2
        assert words in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
