"""``mirrorlab lab grade``: every submission of a class folder checked in parallel (through
:mod:`mirrorlab.jobs`), with a progress bar; ``grades.csv``, ``gradebook.csv`` (one row
per student, in the shape LMS imports take), ``feedback/STUDENT.html``, one picture per
student and ``report.html`` in the output folder.

A submission is a ``.py`` file (the student is its name) or a folder (the student is the
folder's name; its ``starter.py``, else its only ``.py`` file). With ``--key`` each
student is judged against their own variant (derived from the key and their name), and
the numbers of every other variant of the class (and the lab's own) are known to the
judges, so a file copied from another student fails saying so, and ``gradebook.csv`` names
whose numbers it carries (``copy_of``) and scores it by the teacher's policy for copies
(:data:`COPIES`). With a class list (``--students``, needed with ``--key``), a submission
whose name is not on it is reported and not graded. Each submission is sent to
a worker as its bytes, with the teacher's solution's text when references are to be made
from it, so workers on other machines need no shared folder; each worker makes (and
caches) the references it needs. Results are collected by student: a job run twice (its
worker died) still counts once, and the files written are the same whichever engine ran
the jobs (only the seconds differ).
"""

from __future__ import annotations

import csv
import io
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mirrorlab.files import Outputs, png_bytes
from mirrorlab.jobs import open_executor
from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import (
    Variant,
    default_variant,
    derive_variant,
    read_key,
    student_key,
)

CSV_COLUMNS = ("student", "task", "passed", "hint", "seconds")
GRADEBOOK_COLUMNS = ("student", "score", "max_score", "percent", "variant", "copy_of", "feedback")
COPIES = {
    "flag": "the score as judged (the tasks that carry the other numbers fail), the copy "
    "named in copy_of",
    "zero": "a score of 0",
    "hold": "no score (score and percent left empty, so an import posts nothing) until the "
    "teacher decides",
}
"""The teacher's policies for a submission that carries another student's variant or the
lab's own (``--copies``), and what ``gradebook.csv`` gives it; ``flag`` is the default."""


@dataclass(frozen=True)
class Submission:
    student: str
    path: Path | None
    problem: str = ""


@dataclass
class Grade:
    """One student's grade: ``tasks`` as (task id, passed, hint), how the run ended, the
    seconds it took, the picture as PNG bytes, the student's variant, and the student
    (or ``default``) whose variant's numbers the file carries when they are not the
    student's own (for the teacher's gradebook and report, never the feedback page)."""

    student: str
    tasks: list[tuple[str, bool, str]]
    status: str
    seconds: float
    picture_png: bytes
    variant: str = "default"
    copied_from: str = ""

    @property
    def score(self) -> int:
        return sum(passed for _, passed, _ in self.tasks)

    def booked(self, copies: str = "flag") -> int | None:
        """The score the gradebook gives under the policy ``copies`` (:data:`COPIES`):
        None for ``hold`` of a copy."""
        if not self.copied_from or copies == "flag":
            return self.score
        return 0 if copies == "zero" else None

    def copy_of(self) -> str:
        """Whose numbers the file carries, as the gradebook says it: '' (its own),
        ``default variant`` (the lab's own numbers) or another student's name."""
        return "default variant" if self.copied_from == "default" else self.copied_from


def safe_name(student: str) -> str:
    """``student`` as a file name: letters, digits, ``-_.`` only, never hidden."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", student).lstrip(".") or "student"
    return name[:80]


def match_class(
    submissions: list[Submission], students: list[str]
) -> tuple[list[Submission], list[Submission], list[str]]:
    """Split ``submissions`` by the class list ``students`` (names compared as
    :func:`~.variants.student_key` compares them): those on it, those not on it, and the
    names on it with no submission."""
    listed = {student_key(name): name for name in students}
    on: list[Submission] = []
    off: list[Submission] = []
    for submission in submissions:
        (on if student_key(submission.student) in listed else off).append(submission)
    handed = {student_key(s.student) for s in on}
    return on, off, [name for key, name in listed.items() if key not in handed]


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
                found.append(
                    Submission(
                        entry.name,
                        None,
                        f"the folder holds several .py files ({names}) and no starter.py",
                    )
                )
    students = [s.student for s in found]
    duplicates = {s for s in students if students.count(s) > 1}
    if duplicates:
        raise ValueError(
            f"SUBMISSIONS_DIR: two submissions for {sorted(duplicates)[0]!r} (a file and a folder?)"
        )
    if not found:
        raise ValueError(f"SUBMISSIONS_DIR: {str(folder)!r} holds no .py file or folder")
    return found


def _variant(plain: dict[str, Any]) -> Variant:
    return Variant(plain["lab"], dict(plain["values"]), plain["id"], plain.get("student", ""))


def grade_one(
    lab: str,
    student: str,
    source: bytes,
    limits: Limits,
    variant: dict[str, Any] | None = None,
    others: dict[str, dict[str, Any]] | None = None,
    solution: str | None = None,
) -> Grade:
    """Check one submission (``source``, the file's bytes) on this machine against its
    ``variant`` (plain; default: the lab's own numbers), knowing the class's ``others``:
    what a worker runs. References come from ``solution`` (the teacher's text) when
    given, else from the package. Never raises for anything the submission does."""
    from mirrorlab.labs.trusted.checker import check_submission, reference_evidence
    from mirrorlab.labs.trusted.judging import Context

    spec = find_lab(lab)
    mine = _variant(variant) if variant else default_variant(lab)
    context = Context(mine, {name: _variant(v) for name, v in (others or {}).items()})
    reference = (
        reference_evidence(spec, mine, None, limits)
        if solution is None
        else _reference_from_text(spec, mine, solution, limits)
    )
    check = check_submission(
        spec, source, reference, context, student, "submission.py", limits, keep=True
    )
    return Grade(
        student,
        [(r.task.id, r.passed, r.hint) for r in check.results],
        check.status,
        round(check.seconds, 2),
        png_bytes(check.picture),
        mine.id,
        context.matched,
    )


def _reference_from_text(spec: LabSpec, variant: Variant, solution: str, limits: Limits):
    """The reference of ``variant`` from the solution's text (cached as the checker
    caches a solutions folder's)."""
    import tempfile

    from mirrorlab.labs.trusted.checker import reference_evidence

    with tempfile.TemporaryDirectory(prefix="mirrorlab-solution-") as folder:
        (Path(folder) / f"{spec.folder}.py").write_text(solution)
        return reference_evidence(spec, variant, Path(folder), limits, keep=True)


def unrunnable(
    spec: LabSpec, submission: Submission, problem: str, variant: str = "default"
) -> Grade:
    from mirrorlab.labs.trusted.judging import blank

    return Grade(
        submission.student,
        [(t.id, False, problem) for t in spec.tasks],
        "missing",
        0.0,
        png_bytes(blank((64, 192))),
        variant,
    )


def grades_csv(spec: LabSpec, grades: list[Grade]) -> str:
    """The CSV: one row per student and task, students in name order, tasks in the lab's,
    each task by its name (:attr:`~mirrorlab.labs.Task.name`, as the hints name it)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for grade in sorted(grades, key=lambda g: g.student):
        for task_id, passed, hint in grade.tasks:
            writer.writerow(
                (
                    grade.student,
                    spec.task_name(task_id),
                    "yes" if passed else "no",
                    hint,
                    f"{grade.seconds:.2f}",
                )
            )
    return buffer.getvalue()


def gradebook_csv(spec: LabSpec, grades: list[Grade], copies: str = "flag") -> str:
    """One row per student (name order) with the score, as an LMS gradebook import takes
    it: ``student,score,max_score,percent,variant,copy_of,feedback``; a copy (``copy_of``
    names whose numbers it carries) scored by the policy ``copies`` (:data:`COPIES`)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(GRADEBOOK_COLUMNS)
    total = len(spec.tasks)
    for grade in sorted(grades, key=lambda g: g.student):
        score = grade.booked(copies)
        writer.writerow(
            (
                grade.student,
                "" if score is None else score,
                total,
                "" if score is None else f"{100 * score / total:.1f}",
                grade.variant,
                grade.copy_of(),
                f"feedback/{safe_name(grade.student)}.html",
            )
        )
    return buffer.getvalue()


def class_variants(spec: LabSpec, students: list[str], key: bytes | None) -> dict[str, Variant]:
    """Each student's variant (all the default one without a key)."""
    if key is None:
        return {s: default_variant(spec.name) for s in students}
    return {s: derive_variant(spec.name, key, s) for s in students}


def grade_folder(
    spec: LabSpec,
    folder: Path,
    jobs: int,
    scheduler: str | None,
    engine: str,
    limits: Limits,
    progress: bool = True,
    key: bytes | None = None,
    solutions: Path | None = None,
    submissions: list[Submission] | None = None,
    roster: list[str] | None = None,
) -> tuple[list[Grade], str]:
    """Grade every submission in ``folder`` (or those given, found in it by
    :func:`find_submissions`); with a ``key``, the variants of the class list ``roster``
    (default: the submissions' names) are the others a copy is told by. Returns the grades
    and the engine's name."""
    from tqdm import tqdm

    from mirrorlab.labs.trusted.checker import reference_evidence, solution_source

    if submissions is None:
        submissions = find_submissions(folder)
    variants = class_variants(spec, [s.student for s in submissions], key)
    solution = solution_source(spec, solutions) if solutions is not None else None
    if key is not None and solution is None:
        raise ValueError(
            "--key: grading variants needs the teacher's solutions to make each "
            "student's reference: give --solutions DIR (labs/solutions of the "
            "repository) or set MIRRORLAB_SOLUTIONS"
        )
    if key is None:
        # once here, so that local workers find it cached (or fail here in one line)
        reference_evidence(spec, default_variant(spec.name), solutions, limits)
    others = {name: v.plain() for name, v in variants.items()}
    if key is not None and roster is not None:
        handed = {student_key(s.student) for s in submissions}
        others.update(
            {
                name: derive_variant(spec.name, key, name).plain()
                for name in roster
                if student_key(name) not in handed
            }
        )
    if key is not None:
        others["default"] = default_variant(spec.name).plain()
    grades: dict[str, Grade] = {}
    work: dict[str, tuple] = {}
    for submission in submissions:
        variant = variants[submission.student]
        if submission.path is None:
            grades[submission.student] = unrunnable(
                spec, submission, submission.problem, variant.id
            )
            continue
        try:
            source = submission.path.read_bytes()
        except OSError as exc:
            grades[submission.student] = unrunnable(
                spec, submission, f"cannot read it: {exc.strerror}", variant.id
            )
            continue
        theirs = {n: v for n, v in others.items() if n != submission.student}
        work[submission.student] = (
            spec.name,
            submission.student,
            source,
            limits,
            variant.plain(),
            theirs if key is not None else {},
            solution,
        )
    with (
        open_executor(jobs, scheduler, engine) as executor,
        tqdm(
            total=len(submissions),
            initial=len(grades),
            unit="submission",
            desc=f"grading {spec.name}",
            disable=not progress,
            file=sys.stderr,
        ) as bar,
    ):
        for outcome in executor.run(grade_one, work):
            if outcome.key in grades:  # never counted twice
                continue
            if outcome.error is not None:
                submission = next(s for s in submissions if s.student == outcome.key)
                grades[outcome.key] = unrunnable(
                    spec, submission, f"grading failed: {outcome.error}", variants[outcome.key].id
                )
            else:
                grades[outcome.key] = outcome.value
            bar.update(1)
        engine_name = f"{executor.engine} ({executor.workers} worker"
        engine_name += "s)" if executor.workers != 1 else ")"
    return [grades[s.student] for s in submissions], engine_name


def _sandbox_or_risk(limits: Limits) -> str:
    """Nothing when grading here is sandboxed; SandboxError (one line: how to get
    bubblewrap, or the flag) when it is not and ``limits`` do not take the risk; else
    what the report says of it (and a warning line on stderr)."""
    from mirrorlab.labs.trusted import sandbox

    if sandbox.sandboxed():
        return ""
    if not limits.unsandboxed:
        raise sandbox.SandboxError(sandbox.missing_sandbox())
    how = sandbox.unsandboxed_how()
    print(
        f"mirrorlab lab grade: warning: not sandboxed ({sandbox.UNSANDBOXED_FLAG}): every "
        f"submission runs {how}",
        file=sys.stderr,
    )
    return f", NOT sandboxed ({sandbox.UNSANDBOXED_FLAG}: each submission ran {how})"


def run_grade(
    lab: str,
    folder: Path,
    jobs: int,
    scheduler: str | None,
    engine: str,
    out_dir: Path | None,
    limits: Limits,
    key_file: Path | None = None,
    solutions: str | Path | None = None,
    students_file: Path | None = None,
    copies: str = "flag",
) -> int:
    """The ``grade`` command: grade, then write grades.csv, gradebook.csv, the feedback
    pages, the pictures and report.html together (all or none). With a class list
    (``students_file``), submissions not on it are reported, one line each, and not
    graded; it is needed with a key (a variant is made from a name on the list)."""
    from mirrorlab.labs.trusted.checker import solutions_dir
    from mirrorlab.labs.trusted.release import read_students
    from mirrorlab.labs.trusted.report import feedback_html, report_html

    spec = find_lab(lab)
    if copies not in COPIES:
        raise ValueError(
            f"--copies: {copies!r} is not a policy; expected one of {', '.join(COPIES)}"
        )
    folder = folder.resolve()
    key = read_key(key_file) if key_file is not None else None
    if key is not None and students_file is None:
        raise ValueError(
            "--key: grading variants needs the class list the lab was released "
            "to (a variant is made from a name on it): give --students FILE"
        )
    students = read_students(students_file) if students_file is not None else None
    found = solutions_dir(solutions)
    out_dir = out_dir or folder.parent / f"{folder.name}-grades"
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"--out-dir: {str(out_dir)!r} is a file, expected a folder")
    submissions = find_submissions(folder)
    unlisted: list[Submission] = []
    missing: list[str] = []
    if students is not None:
        submissions, unlisted, missing = match_class(submissions, students)
        if not submissions:
            raise ValueError(
                f"SUBMISSIONS_DIR: none of its {len(unlisted)} submissions is "
                f"by a student of the class list {students_file}"
            )
    # after the command line's own errors, before anything is run or said of the class
    unsandboxed = _sandbox_or_risk(limits)
    for submission in unlisted:
        where = submission.path or folder / submission.student
        print(
            f"not graded: {submission.student!r} ({where.name}) is not on the class "
            f"list {students_file}"
        )
    started = time.perf_counter()
    grades, engine_name = grade_folder(
        spec,
        folder,
        jobs,
        scheduler,
        engine,
        limits,
        key=key,
        solutions=found,
        submissions=submissions,
        roster=students,
    )
    engine_name += unsandboxed
    seconds = time.perf_counter() - started
    with Outputs() as outputs:
        outputs.add(out_dir / "grades.csv", grades_csv(spec, grades).encode())
        outputs.add(out_dir / "gradebook.csv", gradebook_csv(spec, grades, copies).encode())
        for grade in grades:
            name = safe_name(grade.student)
            outputs.add(out_dir / "pictures" / f"{name}.png", grade.picture_png)
            outputs.add(out_dir / "feedback" / f"{name}.html", feedback_html(spec, grade).encode())
        outputs.add(
            out_dir / "report.html",
            report_html(
                spec, grades, engine_name, seconds, copies, [s.student for s in unlisted], missing
            ).encode(),
        )
    for name in missing:
        print(f"no submission: {name!r} of the class list")
    for grade in grades:
        if grade.copied_from:
            print(
                f"copy: {grade.student!r} carries the numbers of {grade.copy_of()}; "
                f"--copies={copies}: {COPIES[copies]}"
            )
    full = sum(g.score == len(spec.tasks) for g in grades)
    print(
        f"graded {len(grades)} submissions of {spec.name} in {seconds:.1f} s on "
        f"{engine_name}: {full} passed every task; {out_dir / 'grades.csv'}, "
        f"{out_dir / 'gradebook.csv'}, {out_dir / 'report.html'}"
    )
    return 0
