"""The class list (``--students``): who a lab is released to and who is graded.

Two forms:

- a text file, one name a line (blank lines and ``#`` comments skipped);
- a CSV file (its name ends in ``.csv``): a header row, then one student a row. The name is
  the column ``name`` (or ``student``, ``full name``), or ``first name`` and ``last name``
  together; an id is the column ``id`` (or ``student id``, ``id number``, ``sis user id``,
  ...), an email ``email`` (or ``email address``, ...); headers are matched whatever their
  case and spaces, and other columns are kept as they are (an LMS's own export, Canvas's
  or Moodle's, is a class list as it is: :mod:`.gradebooks` writes its identifiers back).

Every output of grading keeps the list's names and ids. A submission is the list's student
whose name, id or email (or the email's part before ``@``) it is named by, compared as
:func:`~.variants.student_key` compares names; ``Lovelace, Ada`` is also ``Ada Lovelace``
(in the list and in a submission's name).
Two students that one of these would name alike are refused: they would be one to
mirrorlab. The variant of a student follows from their name as the list writes it.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from mirrorlab.labs.trusted.variants import student_key

NAME_HEADERS = ("name", "student", "full name", "student name", "fullname")
FIRST_HEADERS = ("first name", "firstname", "given name", "first")
LAST_HEADERS = ("last name", "lastname", "surname", "family name", "last")
ID_HEADERS = (
    "id",
    "student id",
    "student number",
    "id number",
    "idnumber",
    "sis user id",
    "sis id",
    "user id",
    "number",
    "matriculation number",
)
EMAIL_HEADERS = ("email", "e-mail", "email address", "e-mail address", "mail")
SKIPPED_NAMES = ("points possible",)
"""Rows an LMS export holds that are no student (Canvas's "Points Possible")."""


@dataclass(frozen=True)
class Student:
    """One student of the class list: ``name`` (as the list writes it), ``id`` and
    ``email`` ('' when the list has none), and the list's own columns of the row
    (``fields``, header -> value: an LMS export's identifiers)."""

    name: str
    id: str = ""
    email: str = ""
    fields: dict[str, str] = field(default_factory=dict, compare=False, repr=False)

    def keys(self) -> set[str]:
        """The names a submission of this student may have, compared as
        :func:`~.variants.student_key` compares them."""
        found = {student_key(self.name)}
        if self.name.count(",") == 1:  # "Lovelace, Ada" is Ada Lovelace
            last, first = self.name.split(",")
            found.add(student_key(f"{first} {last}"))
        for value in (self.id, self.email, self.email.split("@")[0] if self.email else ""):
            if value:
                found.add(student_key(value))
        return found - {""}

    def label(self) -> str:
        """The name, with the id where the list gives one: ``Ada Lovelace (s1001)``."""
        return f"{self.name} ({self.id})" if self.id else self.name


def _header(text: str) -> str:
    return " ".join(re.sub(r"[_\-.]+", " ", text.strip().casefold()).split())


def _column(headers: list[str], wanted: Iterable[str]) -> int | None:
    plain = [_header(h) for h in headers]
    for name in wanted:
        if _header(name) in plain:
            return plain.index(_header(name))
    return None


def _csv_rows(path: Path, text: str) -> tuple[list[str], list[tuple[int, list[str]]]]:
    sample = text[:4096]
    try:
        dialect: type[csv.Dialect] | csv.Dialect = csv.Sniffer().sniff(sample, ",;\t")
    except csv.Error:
        dialect = csv.excel
    reader = csv.reader(io.StringIO(text), dialect)
    rows = [(number, row) for number, row in enumerate(reader, 1) if any(c.strip() for c in row)]
    if not rows:
        raise ValueError(f"--students: {str(path)!r} holds no header row")
    return rows[0][1], rows[1:]


def _from_csv(path: Path, text: str) -> list[Student]:
    headers, rows = _csv_rows(path, text)
    name = _column(headers, NAME_HEADERS)
    first, last = _column(headers, FIRST_HEADERS), _column(headers, LAST_HEADERS)
    if name is None and (first is None or last is None):
        raise ValueError(
            f"--students: {path.name} has no name column (its header is "
            f"{', '.join(headers)[:120]}); expected name (or student, full name), or "
            f"first name and last name"
        )
    ident, email = _column(headers, ID_HEADERS), _column(headers, EMAIL_HEADERS)
    students = []
    for number, row in rows:
        cells = row + [""] * (len(headers) - len(row))

        def cell(index: int | None, cells: list[str] = cells) -> str:
            return cells[index].strip() if index is not None else ""

        full = cell(name) if name is not None else f"{cell(first)} {cell(last)}".strip()
        if _header(full) in SKIPPED_NAMES:
            continue
        if not student_key(full):
            raise ValueError(
                f"--students: line {number} of {path.name} has no name (letters or digits) "
                f"in its {headers[name] if name is not None else 'name'} column"
            )
        students.append(
            Student(
                full,
                cell(ident),
                cell(email),
                {h: cells[i].strip() for i, h in enumerate(headers) if h.strip()},
            )
        )
    return students


def _from_text(path: Path, text: str) -> list[Student]:
    students = []
    for number, line in enumerate(text.splitlines(), 1):
        name = line.split("#", 1)[0].strip()
        if not name:
            continue
        if not student_key(name):
            raise ValueError(
                f"--students: line {number} of {path.name}, {name!r}, has no letters or digits"
            )
        students.append(Student(name))
    return students


def read_roster(path: Path) -> list[Student]:
    """The class list in ``path`` (see the module's text); ValueError, one line naming the
    file and line, for one that cannot be used."""
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"--students: cannot read {str(path)!r}: {exc}") from None
    is_csv = path.suffix.casefold() in (".csv", ".tsv")
    students = _from_csv(path, text) if is_csv else _from_text(path, text)
    if not students:
        what = "students (a header, then one a row)" if is_csv else "names (one a line)"
        raise ValueError(f"--students: {str(path)!r} holds no {what}")
    seen: dict[str, Student] = {}
    for student in students:
        for key in student.keys():
            other = seen.get(key)
            if other is not None and other is not student:
                raise ValueError(
                    f"--students: {student.label()!r} and {other.label()!r} are the same "
                    f"student to mirrorlab (both are named {key!r} one way or another); give "
                    f"each a distinct name, id and email"
                )
            seen[key] = student
    return students


def find_student(roster: list[Student], name: str) -> Student | None:
    """The student of ``roster`` a submission named ``name`` is (see the module's text)."""
    named = Student(name).keys()
    return next((s for s in roster if named & s.keys()), None)
