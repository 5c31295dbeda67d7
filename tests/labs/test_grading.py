"""``mirrorlab lab grade`` on the generated class of 42 (solutions, the handout's allowed
forms, the starter, every lab 20 mutant, students whose files raise or do not parse, and
the attacks on the machine): the expected grades.csv with ``--jobs 2`` (a process pool),
and for a third of the class (one of each kind) with ``--jobs 1`` and on a local Dask
cluster through ``--scheduler``; the same files whichever ran it; the gradebook and each
student's own feedback page; every attack reported as that student's failure with nothing
outside harmed; report.html in a real headless Chromium."""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.sandbox import UID_BASE
from mirrorlab.scene.backgrounds import load_picture
from tests.labs.classroom import compare, starter_text
from tests.labs.conftest import LIMITS, mirrorlab_command, read_csv
from tests.labs.mutants import solution

ENGINES = ("serial", "pool", "dask")


@pytest.fixture(scope="session")
def dask_scheduler():
    """A local Dask cluster of two worker processes on loopback, for --scheduler."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        yield cluster.scheduler_address


def part_of_the_class(expected: dict) -> list[str]:
    """The students the serial and Dask engines grade: every third, and every attack."""
    names = sorted(expected)
    return sorted({*names[::3], *(n for n in names if n.startswith("attack_"))})


@pytest.fixture(scope="session")
def graded(classroom, tmp_path_factory, request):
    """engine -> (output folder, the command's result), each graded once on demand: the
    pool grades the whole class, the others :func:`part_of_the_class`."""
    whole, expected = classroom
    part = tmp_path_factory.mktemp("class-part") / "submissions"
    part.mkdir()
    for name in part_of_the_class(expected):
        source = whole / name if (whole / name).is_dir() else whole / f"{name}.py"
        (shutil.copytree if source.is_dir() else shutil.copy)(source, part / source.name)
    done: dict[str, tuple[Path, subprocess.CompletedProcess]] = {}

    def grade(engine: str) -> tuple[Path, subprocess.CompletedProcess]:
        folder = whole if engine == "pool" else part
        if engine not in done:
            out = tmp_path_factory.mktemp(f"grades-{engine}")
            options = {
                "serial": ["--jobs", "1"],
                "pool": ["--jobs", "2"],
                "dask": ["--scheduler", request.getfixturevalue("dask_scheduler")],
            }
            result = mirrorlab_command(
                "lab",
                "grade",
                "lab20",
                str(folder),
                "--out-dir",
                str(out),
                "--timeout",
                str(LIMITS.cpu_seconds),
                *options[engine],
            )
            assert result.returncode == 0, result.stdout + result.stderr[-3000:]
            done[engine] = (out, result)
        return done[engine]

    return grade


@pytest.mark.parametrize("engine", ENGINES)
def test_grades_csv_is_the_expected_one(engine, classroom, graded):
    _, expected = classroom
    assert len(expected) >= 40
    if engine != "pool":
        expected = {name: expected[name] for name in part_of_the_class(expected)}
    out, result = graded(engine)
    rows = read_csv(out / "grades.csv")
    assert list(rows[0]) == ["student", "task", "passed", "hint", "seconds", "id"]
    assert compare(rows, expected) == []
    assert [r["student"] for r in rows] == sorted(r["student"] for r in rows)
    engine_words = {
        "serial": "serial (1 worker)",
        "pool": "pool (2 workers)",
        "dask": "dask (2 workers)",
    }
    assert engine_words[engine] in result.stdout
    # the progress bar counted every submission
    assert re.search(rf"grading lab20: 100%.*{len(expected)}/{len(expected)}", result.stderr)


def test_every_engine_writes_the_same_files(graded, classroom):
    outputs = {engine: graded(engine)[0] for engine in ENGINES}
    part = set(part_of_the_class(classroom[1]))
    tables = {
        engine: [
            {k: v for k, v in row.items() if k != "seconds"}
            for row in read_csv(out / "grades.csv")
            if row["student"] in part
        ]
        for engine, out in outputs.items()
    }
    assert tables["serial"] == tables["pool"] == tables["dask"]
    names = sorted(p.name for p in (outputs["serial"] / "pictures").iterdir())
    assert len(names) == len(tables["serial"]) // len(find_lab("lab20").tasks)
    for engine in ("pool", "dask"):
        assert set(names) <= {p.name for p in (outputs[engine] / "pictures").iterdir()}
        for name in names:
            assert np.array_equal(
                load_picture(outputs["serial"] / "pictures" / name),
                load_picture(outputs[engine] / "pictures" / name),
            ), name


def test_gradebook_and_feedback_pages(graded, classroom):
    out, _ = graded("pool")
    _, expected = classroom
    rows = read_csv(out / "gradebook.csv")
    assert list(rows[0]) == [
        "student",
        "score",
        "max_score",
        "percent",
        "variant",
        "copy_of",
        "feedback",
        "id",
        "email",
        "not_graded",
    ]
    assert [r["student"] for r in rows] == sorted(expected)
    # without a key everyone has the lab's own numbers: no file is another's copy
    assert {(r["variant"], r["copy_of"]) for r in rows} == {("default", "")}
    tasks = len(find_lab("lab20").tasks)
    for row in rows:
        passing = sum(passed for passed, _ in expected[row["student"]].values())
        assert (int(row["score"]), int(row["max_score"])) == (passing, tasks), row
        assert float(row["percent"]) == pytest.approx(100 * passing / tasks, abs=0.05)
        page = (out / row["feedback"]).read_text()
        assert "data:image/png;base64," in page
        page = html.unescape(re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", page))
        # the student's own name, score and picture, and nobody else's
        assert f"{row['student']}" in page and f"{passing} of {tasks} tasks passed" in page
        others = [
            s
            for s in expected
            if s != row["student"] and s not in row["student"] and row["student"] not in s
        ]
        assert not [s for s in others if s in page], row["student"]


def test_attacks_harm_nothing_outside(graded, canaries):
    graded("pool")
    assert (canaries / "delete_me.txt").read_text() == "canary\n"
    assert (canaries / "overwrite_me.txt").read_text() == "canary\n"
    assert sorted(p.name for p in canaries.iterdir()) == ["delete_me.txt", "overwrite_me.txt"]
    # No sandboxed process outlives its run (the fork bomb's included). A sandboxed process
    # runs as UID_BASE + the id of the process that asked for the run, which waits for the
    # run to end: one whose asker is gone has outlived its run. (A run that other tests
    # make at the same time, beside this one, still has its asker.)
    leftovers = [
        entry.name
        for entry in Path("/proc").iterdir()
        if entry.name.isdigit()
        and _uid(entry) >= UID_BASE
        and not Path(f"/proc/{_uid(entry) - UID_BASE}").exists()
    ]
    assert leftovers == []


def _uid(entry: Path) -> int:
    try:
        return entry.stat().st_uid
    except OSError:
        return -1


def chromium(*args: str) -> subprocess.CompletedProcess:
    """Headless Chromium with a fresh profile (flags that work here as root)."""
    binary = shutil.which("chromium") or shutil.which("chromium-browser")
    assert binary, "chromium is not installed: ./dev test installs the Debian package"
    with tempfile.TemporaryDirectory(prefix="mirrorlab-chromium-") as profile:
        return subprocess.run(
            [
                binary,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={profile}",
                *args,
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )


def test_report_opens_in_chromium_with_every_row_and_picture(graded, classroom, tmp_path):
    out, _ = graded("pool")
    _, expected = classroom
    url = (out / "report.html").resolve().as_uri() + "#sort=-score"
    dom = chromium("--dump-dom", url)
    assert dom.returncode == 0, dom.stderr[-2000:]
    html = dom.stdout
    students = re.findall(r'<tr data-student="([^"]+)"', html)
    assert sorted(students) == sorted(expected)
    found = re.search(r"<body[^>]*>", html)
    assert found is not None
    body = found.group(0)
    assert f'data-images-loaded="{len(expected)}"' in body
    assert 'data-images-broken="0"' in body
    # sorted by score, highest first, as the address asked
    assert 'data-sorted-by="score descending"' in html
    scores = [int(s) for s in re.findall(r'<td class="score" data-sort="(\d+)"', html)]
    assert scores == sorted(scores, reverse=True) and scores[0] == 8
    shot = tmp_path / "report.png"
    # in name order the first rows hold both passes (ada) and failures (the attacks)
    done = chromium(
        "--window-size=2560,1600", f"--screenshot={shot}", (out / "report.html").resolve().as_uri()
    )
    assert done.returncode == 0 and shot.is_file(), done.stderr[-2000:]
    if os.environ.get("MIRRORLAB_KEEP_SCREENSHOT"):
        shutil.copy(shot, os.environ["MIRRORLAB_KEEP_SCREENSHOT"])
    image = load_picture(shot)
    assert image.shape[:2] == (1600, 2560)
    # the table's pass and fail colours and the thumbnails' dark frames are on screen
    pixels = image.reshape(-1, 3).astype(int)
    assert np.any(np.all(np.abs(pixels - (0xE3, 0xF6, 0xE3)) <= 2, axis=1))
    assert np.any(np.all(np.abs(pixels - (0xFB, 0xE4, 0xE4)) <= 2, axis=1))
    # the thumbnails: the lab's dark background (0.16, 0.18, 0.22) in their frames
    background = np.all(np.abs(pixels - (41, 46, 56)) <= 6, axis=1)
    assert np.mean(background) > 0.01, "no thumbnails on screen"


def test_a_worker_killed_mid_submission_has_it_graded_elsewhere_once(tmp_path, dask_scheduler):
    """Kill the Dask worker that is running a (looping) submission while ``lab grade
    --scheduler`` grades the class from its own process: the scheduler runs it again on
    another worker, and every student is graded exactly once."""
    import signal
    import sys
    import time

    from distributed import Client

    from mirrorlab.labs.trusted.sandbox import uid_processes

    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "ada.py").write_text(solution("lab20"))
    (folder / "cy.py").write_text(starter_text("lab20"))
    (folder / "slow.py").write_text("while True:\n    pass\n")
    out = tmp_path / "grades"
    grading = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "mirrorlab.cli",
            "lab",
            "grade",
            "lab20",
            str(folder),
            "--out-dir",
            str(out),
            "--scheduler",
            dask_scheduler,
            "--timeout",
            "3",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ),
    )
    killed = None
    with Client(dask_scheduler) as client:
        # wait until a worker runs the slow submission alone and its sandbox is up
        while grading.poll() is None and killed is None:
            for address, keys in client.processing().items():
                if [str(k).split("-")[0] for k in keys] != ["slow"]:
                    continue
                pid = client.run(os.getpid, workers=[address])[address]
                if uid_processes(UID_BASE + pid):
                    os.kill(pid, signal.SIGKILL)
                    killed = pid
                    break
            time.sleep(0.05)
    _, stderr = grading.communicate(timeout=600)
    assert grading.returncode == 0, stderr[-3000:]
    assert killed is not None, "the slow submission was never seen running"
    rows = read_csv(out / "grades.csv")
    tasks = len(find_lab("lab20").tasks)
    assert sorted({r["student"] for r in rows}) == ["ada", "cy", "slow"]
    assert len(rows) == 3 * tasks
    assert all(r["passed"] == "yes" for r in rows if r["student"] == "ada")
    assert all("CPU-time limit" in r["hint"] for r in rows if r["student"] == "slow")
    # the dead worker's sandbox died with it (bubblewrap's --die-with-parent); its
    # processes may take a moment to be reaped
    for _ in range(600):
        if not uid_processes(UID_BASE + killed):
            break
        time.sleep(0.05)
    else:
        raise AssertionError("the killed worker's sandboxed processes are still running")
    # what the killed worker's processes left in the temporary folder, the next run of
    # any worker on this machine removes (their process ids are gone)
    from mirrorlab.labs.trusted.sandbox import new_box, sweep_stale

    scratch = Path(tempfile.gettempdir())
    sweep_stale(scratch)
    left = [
        p.name
        for p in scratch.iterdir()
        if p.name.startswith(("mirrorlab-box-", "mirrorlab-check-"))
        and int(p.name.split("-")[2]) != os.getpid()
    ]
    assert left == [], left
    new_box(scratch).rmdir()
