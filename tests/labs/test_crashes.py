"""The crash files (tests/labs/crashes.py): legal files that used to break the checker are
judged, every task with its line and no traceback; the honest ones pass like the
teacher's solution, the others say what was wrong in the words given."""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor

import pytest

from mirrorlab.labs import find_lab
from tests.labs.conftest import mirrorlab_command
from tests.labs.crashes import CRASHES

TIMEOUT = "20"


@pytest.fixture(scope="module")
def checked(tmp_path_factory, lab_environment):
    folder = tmp_path_factory.mktemp("crashes")

    def check(crash):
        path = folder / f"{crash.name}.py"
        path.write_text(crash.source())
        return mirrorlab_command(
            "lab",
            "check",
            crash.lab,
            str(path),
            "--out",
            str(folder / f"{crash.name}.png"),
            "--timeout",
            TIMEOUT,
        )

    with ThreadPoolExecutor(2) as pool:
        return dict(zip((c.name for c in CRASHES), pool.map(check, CRASHES), strict=True))


@pytest.mark.parametrize("crash", CRASHES, ids=[c.name for c in CRASHES])
def test_each_crash_file_is_judged(checked, crash):
    done = checked[crash.name]
    tasks = len(find_lab(crash.lab).tasks)
    assert done.stderr == "" and "Traceback" not in done.stdout, done.stdout + done.stderr
    score = re.search(rf"(\d+)/{tasks} tasks passed", done.stdout)
    assert score, done.stdout
    assert "could not be judged" not in done.stdout, done.stdout
    if crash.phrase is None:
        assert int(score.group(1)) == tasks and done.returncode == 0, done.stdout
    else:
        assert crash.phrase in done.stdout, (crash.phrase, done.stdout)


def test_lab_grade_judges_every_crash_file(tmp_path, lab_environment):
    """In ``lab grade`` too: no crash file's grade is "grading failed"; the honest ones get
    every task."""
    from tests.labs.conftest import read_csv

    folder = tmp_path / "submissions"
    folder.mkdir()
    crashes = {c.name: c for c in CRASHES if c.lab == "lab20"}
    for name, crash in crashes.items():
        (folder / f"{name}.py").write_text(crash.source())
    out = tmp_path / "grades"
    done = mirrorlab_command(
        "lab",
        "grade",
        "lab20",
        str(folder),
        "--out-dir",
        str(out),
        "--jobs",
        "2",
        "--timeout",
        TIMEOUT,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    rows = read_csv(out / "grades.csv")
    assert {row["student"] for row in rows} == set(crashes)
    for row in rows:
        assert "grading failed" not in row["hint"] and "Traceback" not in row["hint"], row
    book = {row["student"]: row for row in read_csv(out / "gradebook.csv")}
    tasks = len(find_lab("lab20").tasks)
    for name, crash in crashes.items():
        if crash.phrase is None:
            assert int(book[name]["score"]) == tasks, (name, book[name])
