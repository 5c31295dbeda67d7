"""``gradebook.csv`` in the layout an LMS imports (``lab grade --format``).

- ``plain`` (the default): ``student,score,max_score,percent,variant,copy_of,feedback,id,
  email,not_graded``, one row per student in name order.
- ``canvas``: Canvas's gradebook import (Grades, Import): ``Student, ID, SIS User ID, SIS
  Login ID, Section``, then one column for the lab; a ``Points Possible`` row gives the
  most points. Canvas finds each student by ``ID`` (its own user id), else ``SIS User ID``,
  else ``SIS Login ID``, else the name (its importer, ``app/models/gradebook_importer.rb``).
  A class list exported from Canvas keeps its own ``ID``, ``SIS User ID``, ``SIS Login ID``
  and ``Section``; any other list puts its id in ``SIS User ID`` and its email in ``SIS Login
  ID`` and leaves ``ID`` empty (an id of the school's taken for a Canvas user id could name
  another student). A cell left empty changes nothing in Canvas: a submission not graded
  (or a copy held) posts nothing.
- ``moodle``: Moodle's CSV grade import (Grades, Import, CSV file): ``Full name, ID number,
  Email address`` and one column for the lab; at import, "Identify user by" maps the
  file's ``ID number`` (or ``Email address``) to the user field of that name, and the lab's
  column to its grade item. Moodle reads an empty cell as "no grade" (clearing one it
  has) and stops the whole import at a user it cannot find, so a submission not graded
  (or a copy held) has no row at all, and every student needs an id or an email.

The lab's column is named ``--assignment`` (default: the lab's title); in Canvas, a name of
the form ``Title (123)``, as its own export writes it, names assignment 123.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from typing import Any

from mirrorlab.labs import LabSpec

PLAIN_COLUMNS = (
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
)
CANVAS_COLUMNS = ("Student", "ID", "SIS User ID", "SIS Login ID", "Section")
MOODLE_COLUMNS = ("Full name", "ID number", "Email address")


def _writer() -> tuple[io.StringIO, Any]:
    buffer = io.StringIO()
    return buffer, csv.writer(buffer, lineterminator="\n")


def plain(spec: LabSpec, grades: list, copies: str, assignment: str) -> str:
    """mirrorlab's own layout (see the module's text); ``feedback`` is each student's page
    in the output folder."""
    from mirrorlab.labs.trusted.grading import safe_name

    buffer, writer = _writer()
    writer.writerow(PLAIN_COLUMNS)
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
                grade.student_id,
                grade.email,
                grade.not_graded,
            )
        )
    return buffer.getvalue()


def canvas(spec: LabSpec, grades: list, copies: str, assignment: str) -> str:
    """Canvas's gradebook import (see the module's text)."""
    buffer, writer = _writer()
    writer.writerow((*CANVAS_COLUMNS, assignment))
    writer.writerow(("Points Possible", "", "", "", "", len(spec.tasks)))
    for grade in sorted(grades, key=lambda g: g.student):
        fields = grade.fields or {}
        score = grade.booked(copies)
        writer.writerow(
            (
                fields.get("Student", grade.student),
                fields.get("ID", ""),
                fields.get("SIS User ID", grade.student_id),
                fields.get("SIS Login ID", grade.email),
                fields.get("Section", ""),
                "" if score is None else score,
            )
        )
    return buffer.getvalue()


def moodle(spec: LabSpec, grades: list, copies: str, assignment: str) -> str:
    """Moodle's CSV grade import (see the module's text)."""
    buffer, writer = _writer()
    writer.writerow((*MOODLE_COLUMNS, assignment))
    for grade in sorted(grades, key=lambda g: g.student):
        score = grade.booked(copies)
        if score is None:
            continue
        writer.writerow((grade.student, grade.student_id, grade.email, score))
    return buffer.getvalue()


FORMATS: dict[str, Callable[[LabSpec, list, str, str], str]] = {
    "plain": plain,
    "canvas": canvas,
    "moodle": moodle,
}
"""``--format`` -> the function that writes ``gradebook.csv`` in that layout."""


def check_format(name: str, roster: list | None) -> None:
    """ValueError (one line) for a ``--format`` that is no layout, or that the class list
    cannot fill: Moodle finds a student by an id or an email only."""
    if name not in FORMATS:
        raise ValueError(
            f"--format: {name!r} is not a layout; expected one of {', '.join(FORMATS)}"
        )
    if name != "moodle":
        return
    if roster is None:
        raise ValueError(
            "--format moodle: Moodle finds a student by an id or an email: give --students "
            "CLASS.csv with an id or email column"
        )
    nameless = [s for s in roster if not (s.id or s.email)]
    if nameless:
        raise ValueError(
            f"--format moodle: {nameless[0].name!r} of the class list has neither an id nor "
            f"an email, which Moodle needs to find the student"
        )
