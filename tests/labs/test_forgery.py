"""The forgery suite: files that try to get marks without doing the lab (tests/labs/
forgeries.py) are each graded as not passing, named where the trusted side can name them,
one line a task and no traceback, by ``lab check`` and by ``lab grade``; the checker stays
small while a file tries to send it 1 GiB."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import default_variant
from tests.labs.conftest import LIMITS, mirrorlab_command, read_csv
from tests.labs.forgeries import forgeries
from tests.labs.glsl_forgeries import GLSL_FORGERIES, PHRASES
from tests.labs.warm_checks import check_files, report

TIMEOUT = "20"
"""CPU seconds a forgery may spend: enough that each meets the limit it is about (calls,
bytes, vertices) before the CPU limit, however loaded the machine."""
TASKS = len(find_lab("lab20").tasks)


@pytest.fixture(scope="module")
def forged(tmp_path_factory, lab_environment):
    import os

    folder = tmp_path_factory.mktemp("forgeries")
    found = forgeries(Path(os.environ["MIRRORLAB_CACHE"]))
    for name, (source, _) in found.items():
        (folder / f"{name}.py").write_text(source)
    return folder, {name: phrase for name, (_, phrase) in found.items()}


def test_every_forgery_fails_the_check_in_one_line(forged, capfd):
    """Through the warm checker (``lab check --watch``'s), one forgery after another: each
    fails, with a hint, one line a task, and no traceback or other word on stderr."""
    folder, phrases = forged
    assert len(phrases) >= 15
    limits = replace(LIMITS, cpu_seconds=int(TIMEOUT), seconds=3.0 * int(TIMEOUT) + 30)
    checks = check_files("lab20", [folder / f"{name}.py" for name in phrases], limits)
    for name, check in checks.items():
        printed = report("lab20", check)
        assert not check.passed and check.score < TASKS, (name, printed)
        assert "Traceback" not in printed, (name, printed)
        hints = [line for line in printed.splitlines() if line.strip().startswith("hint:")]
        assert hints, name
        phrase = phrases[name]
        assert phrase is None or any(phrase in hint for hint in hints), (name, phrase, hints)
    assert capfd.readouterr().err == ""


def test_every_forgery_fails_lab_grade(forged, tmp_path):
    folder, phrases = forged
    for picture in folder.glob("*.png"):
        picture.unlink()
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
    by_student: dict[str, list[dict[str, str]]] = {}
    for row in rows:
        by_student.setdefault(row["student"], []).append(row)
    assert sorted(by_student) == sorted(phrases)
    book = {row["student"]: row for row in read_csv(out / "gradebook.csv")}
    for name, tasks in by_student.items():
        assert int(book[name]["score"]) < TASKS, name
        assert not all(row["passed"] == "yes" for row in tasks), name
        for row in tasks:
            assert "\n" not in row["hint"] and "Traceback" not in row["hint"], (name, row)
        phrase = phrases[name]
        assert phrase is None or any(phrase in row["hint"] for row in tasks), (name, phrase)


def test_the_checker_stays_small_while_a_file_sends_1_gib(forged):
    """The upload is refused on its header; neither the checker's GL process nor this one
    grows by the gigabyte."""
    folder, _ = forged
    evidence = run_job(
        find_lab("lab20"),
        (folder / "forge_upload_1gib.py").read_bytes(),
        "forge.py",
        default_variant("lab20"),
        Limits(cpu_seconds=20, seconds=120),
        (256, 256),
    )
    assert evidence.status == "stopped" and "1024 MiB" in evidence.detail
    peak = evidence.state.get("checker_peak_kib", 0)
    assert 0 < peak < 400 * 1024, f"the checker's GL process peaked at {peak} KiB"


def test_the_command_stays_small_while_a_file_sends_1_gib(forged):
    folder, _ = forged
    # VmHWM: this process's own peak resident memory
    script = (
        "import sys\nfrom mirrorlab.cli import main\n"
        "code = main(sys.argv[1:])\n"
        "status = open('/proc/self/status').read()\n"
        "print('peak', status.split('VmHWM:')[1].split()[0])\n"
        "sys.exit(code)\n"
    )
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            script,
            "lab",
            "check",
            "lab20",
            str(folder / "forge_upload_1gib.py"),
            "--out",
            str(folder / "one.png"),
            "--timeout",
            TIMEOUT,
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 1, done.stderr
    assert "1024 MiB" in done.stdout
    peak_kib = int(done.stdout.split("peak ")[1].split()[0])
    assert peak_kib < 400 * 1024, f"the command peaked at {peak_kib} KiB"


@pytest.fixture(scope="module")
def glsl_forgeries_graded(tmp_path_factory, lab_environment):
    """Every GLSL forgery graded, a lab's at once (two at a time)."""
    from mirrorlab.labs.trusted.grading import grade_folder
    from tests.labs.conftest import LIMITS, SOLUTIONS

    found = {}
    for lab in ("spheremap", "cubemap"):
        folder = tmp_path_factory.mktemp(f"glsl-{lab}")
        for name, source in GLSL_FORGERIES.items():
            if name.split("_")[0] == lab:
                (folder / f"{name}.py").write_text(source)
        grades, _ = grade_folder(
            find_lab(lab), folder, 2, None, "pool", LIMITS, progress=False, solutions=SOLUTIONS
        )
        found.update({g.student: g for g in grades})
    return found


@pytest.mark.parametrize("name", sorted(GLSL_FORGERIES))
def test_glsl_forgeries_fail_the_glsl_tasks_in_one_line(glsl_forgeries_graded, name):
    """The student's GLSL is compiled alone (macros reach nothing), judged on inputs the
    checker draws (constants and 64 hard-coded fragments, the rest discarded, fail) and
    refused when it names the checker's own ``ml_`` uniforms."""
    grade = glsl_forgeries_graded[name]
    assert grade.status == "ok", grade
    verdicts = {task: (passed, hint) for task, passed, hint in grade.tasks}
    first, second = list(verdicts)[:2]
    for task in (first, second):
        passed, hint = verdicts[task]
        assert not passed and "\n" not in hint and "Traceback" not in hint, (task, hint)
    assert PHRASES[name] in verdicts[first][1], verdicts[first]
