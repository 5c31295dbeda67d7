"""The crash files (tests/labs/crashes.py): legal files that used to break the checker are
judged (by the warm checker, one file after another, and by ``lab grade``), every task
with its line and no traceback; the honest ones pass like the
teacher's solution, the others say what was wrong in the words given."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from mirrorlab.labs import find_lab
from tests.labs.conftest import LIMITS, mirrorlab_command
from tests.labs.crashes import CRASHES
from tests.labs.warm_checks import check_files, report

TIMEOUT = "20"


@pytest.fixture(scope="module")
def checked(tmp_path_factory, lab_environment):
    """Each crash file's check, through one warm checker a lab (``lab check --watch``'s):
    its report as ``lab check`` prints it, and whether it passed."""
    folder = tmp_path_factory.mktemp("crashes")
    limits = replace(LIMITS, cpu_seconds=int(TIMEOUT), seconds=3.0 * int(TIMEOUT) + 30)
    found: dict[str, tuple[str, bool]] = {}
    for lab in sorted({crash.lab for crash in CRASHES}):
        paths = []
        for crash in (c for c in CRASHES if c.lab == lab):
            paths.append(folder / f"{crash.name}.py")
            paths[-1].write_text(crash.source())
        for name, check in check_files(lab, paths, limits).items():
            found[name] = (report(lab, check), check.passed)
    return found


@pytest.mark.parametrize("crash", CRASHES, ids=[c.name for c in CRASHES])
def test_each_crash_file_is_judged(checked, crash):
    printed, passed = checked[crash.name]
    tasks = len(find_lab(crash.lab).tasks)
    assert "Traceback" not in printed, printed
    score = re.search(rf"(\d+)/{tasks} tasks passed", printed)
    assert score, printed
    assert "could not be judged" not in printed, printed
    if crash.phrase is None:
        assert int(score.group(1)) == tasks and passed, printed
    else:
        assert crash.phrase in printed, (crash.phrase, printed)


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
