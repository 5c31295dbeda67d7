"""bench/speed.py's quick mode runs whole: pyrender's environment and worker, every
variant, the report. It checks the benchmark works, never its figures (timings are
the benchmark's business, not a test's)."""

from __future__ import annotations

import csv
import subprocess
import sys

from PIL import Image

from tests import REPO_DIR

VARIANTS = {"mirrorlab two passes", "mirrorlab reflected two passes",
            "mirrorlab capture reused", "mirrorlab one pass", "pyrender default",
            "pyrender flat"}
SCALE_SCENES = {"base", *(f"{count} {family}" for count in (3, 12) for family in (
    "mirrors unseen", "mirrors seen", "objects unseen", "objects seen", "tiny objects seen"))}


def test_quick_speed_benchmark_times_every_variant_and_writes_its_report(tmp_path):
    done = subprocess.run([sys.executable, str(REPO_DIR / "bench" / "speed.py"), "--quick",
                           "--out-dir", str(tmp_path)], capture_output=True, text=True,
                          cwd=REPO_DIR)
    assert done.returncode == 0, done.stderr[-3000:]
    with open(tmp_path / "speed.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    configurations = {(int(r["triangles"]), int(r["size"])) for r in rows}
    assert configurations == {(400, 32), (400, 64), (1600, 32), (1600, 64)}
    for configuration in configurations:
        ran = {r["variant"] for r in rows if (int(r["triangles"]), int(r["size"]))
               == configuration}
        assert ran == VARIANTS, configuration
    for row in rows:
        assert int(row["frames"]) >= 3
        assert 0 < float(row["p10_ms"]) <= float(row["median_ms"]) <= float(row["p90_ms"])
        assert "llvmpipe" in row["gl"]
    with open(tmp_path / "scale.csv", newline="") as stream:
        scale = list(csv.DictReader(stream))
    ran = {(r["variant"].split(", ")[0], r["variant"].split(", ")[1]) for r in scale}
    mirrorless = {s for s in SCALE_SCENES if "mirrors" not in s}
    assert ran == ({("mirrorlab still", s) for s in SCALE_SCENES}
                   | {("mirrorlab moving", s) for s in SCALE_SCENES}
                   | {("pyrender flat", s) for s in mirrorless})
    for row in scale:
        assert int(row["frames"]) >= 3 and int(row["size"]) == 64
        assert 0 < float(row["p10_ms"]) <= float(row["median_ms"]) <= float(row["p90_ms"])
    report = (tmp_path / "speed.md").read_text()
    assert "two passes / flat" in report and "k in pixels, 400 triangles" in report
    assert "| 12 objects unseen |" in report and "k in count" in report
    assert report == done.stdout
    with Image.open(tmp_path / "speed.png") as plot:
        assert plot.size[0] > 600 and plot.size[1] > 300
    assert len(list((tmp_path / "meshes").rglob("*.obj"))) == 2 * 7  # two sets of 7 parts
