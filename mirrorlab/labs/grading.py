"""``mirrorlab lab grade``: every submission of a class folder checked in parallel (through
:mod:`mirrorlab.jobs`), with a progress bar; ``grades.csv``, one picture per student and
``report.html`` in the output folder.

A submission is a ``.py`` file (the student is its name) or a folder (the student is the
folder's name; its ``starter.py``, else its only ``.py`` file). Each is sent to a worker as
its bytes, so workers on other machines need no shared folder; each worker finds the
reference solution's run in its own cache (made once per machine). Results are collected
by student: a job run twice (its worker died) still counts once, and the files written are
the same whichever engine ran the jobs (only the seconds differ).
"""

from __future__ import annotations

import csv
import io
import re
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from mirrorlab.files import Outputs, png_bytes
from mirrorlab.jobs import open_executor
from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.sandbox import Limits

CSV_COLUMNS = ("student", "task", "passed", "hint", "seconds")


@dataclass(frozen=True)
class Submission:
    student: str
    path: Path | None
    problem: str = ""


@dataclass
class Grade:
    """One student's grade: ``tasks`` as (task id, passed, hint), how the run ended, the
    seconds it took and the picture as PNG bytes."""

    student: str
    tasks: list[tuple[str, bool, str]]
    status: str
    seconds: float
    picture_png: bytes

    @property
    def score(self) -> int:
        return sum(passed for _, passed, _ in self.tasks)


def safe_name(student: str) -> str:
    """``student`` as a file name: letters, digits, ``-_.`` only, never hidden."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", student).lstrip(".") or "student"
    return name[:80]


def find_submissions(folder: Path) -> list[Submission]:
    """The submissions in ``folder``, by student name."""
    if not folder.is_dir():
        raise ValueError(f"SUBMISSIONS_DIR: {str(folder)!r} is not a folder")
    found = []
    for entry in sorted(folder.iterdir()):
        if entry.name.startswith("."):
            continue
        if entry.is_file() and entry.suffix == ".py":
            found.append(Submission(entry.stem, entry))
        elif entry.is_dir():
            files = sorted(p for p in entry.glob("*.py") if p.is_file())
            starter = entry / "starter.py"
            if starter.is_file():
                found.append(Submission(entry.name, starter))
            elif len(files) == 1:
                found.append(Submission(entry.name, files[0]))
            elif not files:
                found.append(Submission(entry.name, None, "the folder holds no .py file"))
            else:
                names = ", ".join(p.name for p in files[:4])
                found.append(Submission(entry.name, None, f"the folder holds several .py files "
                                        f"({names}) and no starter.py"))
    students = [s.student for s in found]
    duplicates = {s for s in students if students.count(s) > 1}
    if duplicates:
        raise ValueError(f"SUBMISSIONS_DIR: two submissions for {sorted(duplicates)[0]!r} "
                         f"(a file and a folder?)")
    if not found:
        raise ValueError(f"SUBMISSIONS_DIR: {str(folder)!r} holds no .py file or folder")
    return found


def grade_one(lab: str, student: str, source: bytes, limits: Limits) -> Grade:
    """Check one submission (``source``, the file's bytes) on this machine: what a worker
    runs. Never raises for anything the submission does."""
    from mirrorlab.labs.checker import check_submission, reference_evidence

    spec = find_lab(lab)
    reference = reference_evidence(spec, limits)
    with tempfile.TemporaryDirectory(prefix="mirrorlab-submission-") as folder:
        path = Path(folder) / "submission.py"
        path.write_bytes(source)
        check = check_submission(spec, path, reference, student, limits)
    return Grade(student, [(r.task.id, r.passed, r.hint) for r in check.results],
                 check.status, round(check.seconds, 2), png_bytes(check.picture))


def unrunnable(spec: LabSpec, submission: Submission, problem: str) -> Grade:
    from mirrorlab.labs.judging import blank

    return Grade(submission.student, [(t.id, False, problem) for t in spec.tasks], "missing",
                 0.0, png_bytes(blank((64, 192))))


def grades_csv(spec: LabSpec, grades: list[Grade]) -> str:
    """The CSV: one row per student and task, students in name order, tasks in the lab's."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for grade in sorted(grades, key=lambda g: g.student):
        for task_id, passed, hint in grade.tasks:
            writer.writerow((grade.student, task_id, "yes" if passed else "no", hint,
                             f"{grade.seconds:.2f}"))
    return buffer.getvalue()


def grade_folder(spec: LabSpec, folder: Path, jobs: int, scheduler: str | None, engine: str,
                 limits: Limits, progress: bool = True) -> tuple[list[Grade], str]:
    """Grade every submission in ``folder``; returns the grades and the engine's name."""
    from tqdm import tqdm

    from mirrorlab.labs.checker import reference_evidence

    submissions = find_submissions(folder)
    reference_evidence(spec, limits)  # once here, so that local workers find it cached
    grades: dict[str, Grade] = {}
    work: dict[str, tuple] = {}
    for submission in submissions:
        if submission.path is None:
            grades[submission.student] = unrunnable(spec, submission, submission.problem)
            continue
        try:
            source = submission.path.read_bytes()
        except OSError as exc:
            grades[submission.student] = unrunnable(spec, submission,
                                                    f"cannot read it: {exc.strerror}")
            continue
        work[submission.student] = (spec.name, submission.student, source, limits)
    with open_executor(jobs, scheduler, engine) as executor, \
            tqdm(total=len(submissions), initial=len(grades), unit="submission",
                 desc=f"grading {spec.name}", disable=not progress, file=sys.stderr) as bar:
        for outcome in executor.run(grade_one, work):
            if outcome.key in grades:  # never counted twice
                continue
            if outcome.error is not None:
                submission = next(s for s in submissions if s.student == outcome.key)
                grades[outcome.key] = unrunnable(spec, submission,
                                                 f"grading failed: {outcome.error}")
            else:
                grades[outcome.key] = outcome.value
            bar.update(1)
        engine_name = f"{executor.engine} ({executor.workers} worker"
        engine_name += "s)" if executor.workers != 1 else ")"
    return [grades[s.student] for s in submissions], engine_name


def run_grade(lab: str, folder: Path, jobs: int, scheduler: str | None, engine: str,
              out_dir: Path | None, limits: Limits) -> int:
    """The ``grade`` command: grade, then write grades.csv, the pictures and report.html
    together (all or none)."""
    from mirrorlab.labs.report import report_html

    spec = find_lab(lab)
    folder = folder.resolve()
    out_dir = out_dir or folder.parent / f"{folder.name}-grades"
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"--out-dir: {str(out_dir)!r} is a file, expected a folder")
    started = time.perf_counter()
    grades, engine_name = grade_folder(spec, folder, jobs, scheduler, engine, limits)
    seconds = time.perf_counter() - started
    with Outputs() as outputs:
        outputs.add(out_dir / "grades.csv", grades_csv(spec, grades).encode())
        for grade in grades:
            outputs.add(out_dir / "pictures" / f"{safe_name(grade.student)}.png",
                        grade.picture_png)
        outputs.add(out_dir / "report.html", report_html(spec, grades, engine_name,
                                                        seconds).encode())
    full = sum(g.score == len(spec.tasks) for g in grades)
    print(f"graded {len(grades)} submissions of {spec.name} in {seconds:.1f} s on "
          f"{engine_name}: {full} passed every task; {out_dir / 'grades.csv'}, "
          f"{out_dir / 'report.html'}")
    return 0
