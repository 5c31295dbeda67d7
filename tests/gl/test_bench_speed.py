"""``mirrorlab bench speed``: its quick mode runs whole, with pyrender's environment and
worker (``bench/speed.py``, which makes them) and without; ``--from-csv`` re-makes the
report; bad options stop it with one line and no output. It checks the benchmark works,
never its figures (timings are the benchmark's business, not a test's)."""

from __future__ import annotations

import csv
import subprocess
import sys

import pytest
from PIL import Image

from mirrorlab.cli import main
from tests import REPO_DIR

MIRRORLAB = {
    "mirrorlab two passes",
    "mirrorlab reflected two passes",
    "mirrorlab capture reused",
    "mirrorlab one pass",
}
PYRENDER = {"pyrender default", "pyrender flat"}
SCALE_SCENES = {
    "base",
    *(
        f"{count} {family}"
        for count in (3, 12)
        for family in (
            "mirrors unseen",
            "mirrors seen",
            "objects unseen",
            "objects seen",
            "tiny objects seen",
        )
    ),
}
MIRRORLESS = {s for s in SCALE_SCENES if "mirrors" not in s}


def read_csv(path) -> list[dict]:
    with open(path, newline="") as stream:
        return list(csv.DictReader(stream))


def check_report(folder, stdout: str, variants: set[str], pyrender: bool) -> None:
    """What every quick run writes: every configuration of every variant, the scale
    scenes in both modes (pyrender's flat frame of those without mirrors, when timed), the
    tables, and the plot."""
    rows = read_csv(folder / "speed.csv")
    configurations = {(int(r["triangles"]), int(r["size"])) for r in rows}
    assert configurations == {(400, 32), (400, 64), (1600, 32), (1600, 64)}
    for configuration in configurations:
        ran = {r["variant"] for r in rows if (int(r["triangles"]), int(r["size"])) == configuration}
        assert ran == variants, configuration
    for row in rows:
        assert int(row["frames"]) >= 3
        assert 0 < float(row["p10_ms"]) <= float(row["median_ms"]) <= float(row["p90_ms"])
        assert "llvmpipe" in row["gl"]
    scale = read_csv(folder / "scale.csv")
    ran = {(r["variant"].split(", ")[0], r["variant"].split(", ")[1]) for r in scale}
    assert ran == (
        {("mirrorlab still", s) for s in SCALE_SCENES}
        | {("mirrorlab moving", s) for s in SCALE_SCENES}
        | ({("pyrender flat", s) for s in MIRRORLESS} if pyrender else set())
    )
    for row in scale:
        assert int(row["frames"]) >= 3 and int(row["size"]) == 64
        assert 0 < float(row["p10_ms"]) <= float(row["median_ms"]) <= float(row["p90_ms"])
        assert (
            float(row["to_base"]) == 1.0
            if row["variant"].endswith(", base")
            else (float(row["to_base"]) > 0)
        )
    report = (folder / "speed.md").read_text()
    assert ("two passes / flat" in report) == pyrender
    assert ("pyrender was not timed" in report) == (not pyrender)
    assert "k in pixels, 400 triangles" in report
    assert "| 12 objects unseen |" in report and "k in count" in report
    assert report == stdout
    with Image.open(folder / "speed.png") as plot:
        assert plot.size[0] > 600 and plot.size[1] > 300
    assert len(list((folder / "meshes").rglob("*.obj"))) == 2 * 7  # two sets of 7 parts


def test_quick_speed_benchmark_with_pyrender_times_every_variant(tmp_path):
    done = subprocess.run(
        [
            sys.executable,
            str(REPO_DIR / "bench" / "speed.py"),
            "--quick",
            "--out-dir",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        cwd=REPO_DIR,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    check_report(tmp_path, done.stdout, MIRRORLAB | PYRENDER, pyrender=True)


def test_quick_speed_benchmark_without_pyrender_and_its_report_again(tmp_path, capsys):
    first = tmp_path / "first"
    assert main(["bench", "speed", "--quick", "--out-dir", str(first)]) == 0
    check_report(first, capsys.readouterr().out, MIRRORLAB, pyrender=False)
    again = tmp_path / "again"
    assert (
        main(["bench", "speed", "--from-csv", str(first / "speed.csv"), "--out-dir", str(again)])
        == 0
    )

    def tables(text: str) -> list[str]:
        return [line for line in text.splitlines() if line.startswith("|")]

    report = (again / "speed.md").read_text()
    assert capsys.readouterr().out == report
    assert tables(report) == tables((first / "speed.md").read_text())
    assert f"the figures of {first / 'speed.csv'}" in report
    assert (again / "speed.csv").read_text() == (first / "speed.csv").read_text()
    assert (again / "scale.csv").read_text() == (first / "scale.csv").read_text()


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--pyrender", "no/such/python"], "--pyrender: 'no/such/python' is not a file"),
        (["--pyrender", sys.executable], "cannot import pyrender"),
        (["--sizes", "8,64"], "--sizes"),
        (["--sizes", "64,,x"], "--sizes"),
        (["--subdivisions", "9"], "--subdivisions"),
        (["--parts", "sweep,race"], "--parts: expected one of sweep, scale, got 'race'"),
        (["--scale-modes", ","], "--scale-modes"),
        (["--scale-objects", "0"], "--scale-objects"),
        (["--frames", "none"], "--frames"),
        (["--scale-frames", "0"], "--scale-frames"),
        (["--from-csv", "no/such.csv"], "--from-csv: 'no/such.csv' is not a file"),
        (["--from-csv", "{garbage}"], "--from-csv"),
    ],
)
def test_bad_speed_options_stop_with_one_line_and_write_nothing(tmp_path, capsys, options, words):
    garbage = tmp_path / "garbage.csv"
    garbage.write_text("variant,size\nx,not a number\n")
    options = [str(garbage) if o == "{garbage}" else o for o in options]
    out = tmp_path / "out"
    assert main(["bench", "speed", *options, "--out-dir", str(out)]) == 2
    errors = capsys.readouterr().err.strip().splitlines()
    assert len(errors) == 1 and errors[0].startswith("mirrorlab bench: error: "), errors
    assert words in errors[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["garbage.csv"]


def test_a_pyrender_worker_that_ends_stops_the_benchmark_with_one_line(tmp_path, capsys):
    """An environment that imports pyrender but whose worker dies: exit 1, the worker and
    what it was asked named, no report written."""
    python = tmp_path / "python"
    python.write_text('#!/bin/sh\n[ "$1" = -c ] && exit 0\nexit 3\n')
    python.chmod(0o755)
    out = tmp_path / "out"
    assert (
        main(
            [
                "bench",
                "speed",
                "--quick",
                "--parts",
                "sweep",
                "--pyrender",
                str(python),
                "--out-dir",
                str(out),
            ]
        )
        == 1
    )
    errors = capsys.readouterr().err.strip().splitlines()
    assert errors == [
        "mirrorlab bench: error: pyrender's worker ended (exit 3) before it answered 'setup'"
    ], errors
    assert not (out / "speed.md").exists() and not (out / "speed.csv").exists()
