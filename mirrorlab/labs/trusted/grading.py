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
(:data:`COPIES`). With a class list (``--students``, needed with ``--key``: :mod:`.roster`),
a submission named by no student of it is reported and not graded, and every output
keeps the list's names and ids. A submission the checker itself could not grade (no
OpenGL on a worker, a full disk, a checker that fails whatever the file: see
:mod:`.failures`) is "not graded": no score, its name printed, exit status 1; where the
machine cannot grade at all (no OpenGL, no sandbox), grading stops before it writes
anything (:class:`GradingStopped`). Each submission is sent to
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
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from mirrorlab.files import Outputs, png_bytes
from mirrorlab.jobs import open_executor
from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.roster import Student, find_student
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import (
    Variant,
    default_variant,
    derive_variant,
    read_key,
    student_key,
)

CSV_COLUMNS = ("student", "task", "passed", "hint", "seconds", "id")
NOT_GRADED = "not graded"
COPIES = {
    "flag": "the score as judged (the tasks that carry the other numbers fail), the copy "
    "named in copy_of",
    "zero": "a score of 0",
    "hold": "no score (score and percent left empty, so an import posts nothing) until the "
    "teacher decides",
}
"""The teacher's policies for a submission that carries another student's variant or the
lab's own (``--copies``), and what ``gradebook.csv`` gives it; ``flag`` is the default."""


class GradingStopped(RuntimeError):
    """This machine cannot grade (no OpenGL for the checker, no sandbox): nothing was
    written; one line saying why."""


@dataclass(frozen=True)
class Submission:
    """A student's submission: the student (the class list's name once matched to it),
    the file (None, with the ``problem``, when there is none to run) and the class list's
    record of the student (:class:`~.roster.Student`, None without a list)."""

    student: str
    path: Path | None
    problem: str = ""
    who: Student | None = None


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
    not_graded: str = ""
    """Why the checker could not grade it (its own or its machine's failure, never the
    file's): no score anywhere, the tasks not judged."""
    student_id: str = ""
    email: str = ""
    fields: dict[str, str] = field(default_factory=dict, repr=False)
    """The class list's own columns of the student (an LMS export's identifiers)."""

    @property
    def score(self) -> int:
        return sum(passed for _, passed, _ in self.tasks)

    @property
    def label(self) -> str:
        """The student as the class list names them, with their id: ``Ada (s1001)``."""
        return f"{self.student} ({self.student_id})" if self.student_id else self.student

    def booked(self, copies: str = "flag") -> int | None:
        """The score the gradebook gives under the policy ``copies`` (:data:`COPIES`):
        None for ``hold`` of a copy, and for a submission not graded."""
        if self.not_graded:
            return None
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
    submissions: list[Submission], roster: list[Student]
) -> tuple[list[Submission], list[Submission], list[Student]]:
    """Split ``submissions`` by the class list ``roster`` (:func:`~.roster.find_student`):
    those of a student on it (renamed to the list's name, with its record), those of
    nobody on it, and the students with no submission. ValueError when two submissions
    are one student's."""
    on: list[Submission] = []
    off: list[Submission] = []
    taken: dict[str, Submission] = {}
    for submission in submissions:
        who = find_student(roster, submission.student)
        if who is None:
            off.append(submission)
            continue
        if who.name in taken:
            first = taken[who.name]
            raise ValueError(
                f"SUBMISSIONS_DIR: {first.student!r} and {submission.student!r} are both "
                f"{who.label()!r} of the class list; keep one"
            )
        taken[who.name] = submission
        on.append(replace(submission, student=who.name, who=who))
    return on, off, [s for s in roster if s.name not in taken]


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
    """The grade of a submission with nothing to run (no file, an unreadable one): every
    task failed with ``problem``."""
    from mirrorlab.labs.trusted.judging import blank

    return Grade(
        submission.student,
        [(t.id, False, problem) for t in spec.tasks],
        "missing",
        0.0,
        png_bytes(blank((64, 192))),
        variant,
        **_identity(submission),
    )


def not_graded(
    spec: LabSpec, submission: Submission, reason: str, variant: str = "default"
) -> Grade:
    """The grade of a submission the checker could not grade (``reason``: its own or its
    machine's failure): no score, each task "not graded"."""
    from mirrorlab.labs.trusted.judging import blank

    return Grade(
        submission.student,
        [(t.id, False, f"{NOT_GRADED}: {reason}") for t in spec.tasks],
        NOT_GRADED,
        0.0,
        png_bytes(blank((64, 192))),
        variant,
        not_graded=reason,
        **_identity(submission),
    )


def _identity(submission: Submission) -> dict[str, Any]:
    who = submission.who
    if who is None:
        return {}
    return {"student_id": who.id, "email": who.email, "fields": dict(who.fields)}


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
                    NOT_GRADED if grade.not_graded else "yes" if passed else "no",
                    hint,
                    f"{grade.seconds:.2f}",
                    grade.student_id,
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
    roster: list[Student] | None = None,
) -> tuple[list[Grade], str]:
    """Grade every submission in ``folder`` (or those given, found in it by
    :func:`find_submissions` and matched to the class list by :func:`match_class`); with a
    ``key``, the variants of the class list ``roster`` (default: the submissions' names)
    are the others a copy is told by. A submission the checker could not grade is "not
    graded" (:func:`not_graded`); GradingStopped when this machine grades none (no OpenGL,
    no sandbox: on this machine's own workers, the first one to say so stops the rest).
    Returns the grades and the engine's name."""
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
                student.name: derive_variant(spec.name, key, student.name).plain()
                for student in roster
                if student_key(student.name) not in handed
            }
        )
    if key is not None:
        others["default"] = default_variant(spec.name).plain()
    grades: dict[str, Grade] = {}
    work: dict[str, tuple] = {}
    by_student = {s.student: s for s in submissions}
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
            submission = by_student[outcome.key]
            if outcome.error is not None:
                if scheduler is None and outcome.error.startswith(MACHINE_CANNOT_GRADE):
                    raise GradingStopped(outcome.error.split(": ", 1)[-1])
                grades[outcome.key] = not_graded(
                    spec, submission, outcome.error, variants[outcome.key].id
                )
            else:
                grades[outcome.key] = outcome.value
            bar.update(1)
        engine_name = f"{executor.engine} ({executor.workers} worker"
        engine_name += "s)" if executor.workers != 1 else ")"
    return [_identified(grades[s.student], s) for s in submissions], engine_name


MACHINE_CANNOT_GRADE = ("GLContextError:", "GLVersionError:", "SandboxError:")
"""A job's error (``Type: message``) that says this machine grades nothing: no OpenGL for
the checker, no sandbox."""


def _identified(grade: Grade, submission: Submission) -> Grade:
    """``grade`` with the class list's id, email and columns of its student."""
    who = submission.who
    if who is None:
        return grade
    return replace(grade, student_id=who.id, email=who.email, fields=dict(who.fields))


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
    layout: str = "plain",
    assignment: str | None = None,
) -> int:
    """The ``grade`` command: grade, then write grades.csv, gradebook.csv (in the LMS
    ``layout``: :mod:`.gradebooks`, its column named ``assignment``), the feedback pages,
    the pictures and report.html together (all or none). With a class list
    (``students_file``: :mod:`.roster`), submissions of nobody on it are reported, one line
    each, and not graded; it is needed with a key (a variant is made from a name on the
    list). Returns 0, or 1 when the checker could not grade some submissions (each named;
    their gradebook cells empty). GradingStopped (nothing written) when this machine
    cannot grade at all."""
    from mirrorlab.errors import GLContextError
    from mirrorlab.labs.trusted.checker import solutions_dir
    from mirrorlab.labs.trusted.gradebooks import FORMATS, check_format
    from mirrorlab.labs.trusted.report import feedback_html, report_html
    from mirrorlab.labs.trusted.roster import read_roster

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
    students = read_roster(students_file) if students_file is not None else None
    check_format(layout, students)
    column = assignment if assignment is not None else spec.title
    if not column.strip():
        raise ValueError("--assignment: the gradebook's column needs a name")
    found = solutions_dir(solutions)
    out_dir = out_dir or folder.parent / f"{folder.name}-grades"
    if out_dir.exists() and not out_dir.is_dir():
        raise ValueError(f"--out-dir: {str(out_dir)!r} is a file, expected a folder")
    submissions = find_submissions(folder)
    unlisted: list[Submission] = []
    missing: list[Student] = []
    if students is not None:
        submissions, unlisted, missing = match_class(submissions, students)
        if not submissions:
            raise ValueError(
                f"SUBMISSIONS_DIR: none of its {len(unlisted)} submissions is "
                f"by a student of the class list {students_file}"
            )
    # after the command line's own errors, before anything is run or said of the class
    unsandboxed = _sandbox_or_risk(limits)
    if scheduler is None:  # this machine's own workers: OpenGL for their checkers
        from mirrorlab.gl.context import choose

        try:
            choose("offscreen", new_process=True)
        except GLContextError as exc:
            raise GradingStopped(str(exc)) from None
    for submission in unlisted:
        where = submission.path or folder / submission.student
        print(
            f"not graded: {submission.student!r} ({where.name}) is not on the class "
            f"list {students_file}"
        )
    started = time.perf_counter()
    try:
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
    except GLContextError as exc:  # the reference, made here first
        raise GradingStopped(str(exc)) from None
    engine_name += unsandboxed
    seconds = time.perf_counter() - started
    with Outputs() as outputs:
        outputs.add(out_dir / "grades.csv", grades_csv(spec, grades).encode())
        outputs.add(
            out_dir / "gradebook.csv", FORMATS[layout](spec, grades, copies, column).encode()
        )
        for grade in grades:
            name = safe_name(grade.student)
            outputs.add(out_dir / "pictures" / f"{name}.png", grade.picture_png)
            outputs.add(out_dir / "feedback" / f"{name}.html", feedback_html(spec, grade).encode())
        outputs.add(
            out_dir / "report.html",
            report_html(
                spec,
                grades,
                engine_name,
                seconds,
                copies,
                [s.student for s in unlisted],
                [s.label() for s in missing],
            ).encode(),
        )
    labels = {s.name: s.label() for s in students or []}
    for student in missing:
        print(f"no submission: {student.label()!r} of the class list")
    for grade in grades:
        if grade.copied_from:
            whose = labels.get(grade.copied_from, grade.copy_of())
            print(
                f"copy: {grade.label!r} carries the numbers of {whose}; "
                f"--copies={copies}: {COPIES[copies]}"
            )
    skipped = [g for g in grades if g.not_graded]
    for grade in skipped:
        print(f"{NOT_GRADED}: {grade.label!r}: {grade.not_graded}")
    full = sum(g.score == len(spec.tasks) for g in grades)
    graded = len(grades) - len(skipped)
    print(
        f"graded {graded} submissions of {spec.name} in {seconds:.1f} s on "
        f"{engine_name}: {full} passed every task"
        + (
            f"; {len(skipped)} not graded (the checker's own failure: no score, named "
            f"above; grade them again)"
            if skipped
            else ""
        )
        + f"; {out_dir / 'grades.csv'}, {out_dir / 'gradebook.csv'} ({layout}), "
        f"{out_dir / 'report.html'}"
    )
    return 1 if skipped else 0
