"""The class list (a text file or a CSV with ids and emails, an LMS's own export among them)
and the gradebook's layouts (mirrorlab's own, Canvas's and Moodle's imports), without
grading anything: the rows a list gives, the submissions it names, the refusals, and each
layout read back as its LMS reads it."""

from __future__ import annotations

import csv
import io

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.gradebooks import FORMATS, check_format
from mirrorlab.labs.trusted.grading import Grade, Submission, match_class
from mirrorlab.labs.trusted.roster import Student, find_student, read_roster
from mirrorlab.labs.trusted.variants import (
    VariantError,
    default_variant,
    derive_variant,
    header_line,
    variant_from_header,
)

SPEC = find_lab("lab20")
TASKS = [t.id for t in SPEC.tasks]


def write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_a_text_list_and_a_csv_list_give_names_ids_and_emails(tmp_path):
    plain = read_roster(write(tmp_path, "class.txt", "Ada Lovelace\n\n# late\nBen Ng # ok\n"))
    assert [(s.name, s.id, s.email) for s in plain] == [
        ("Ada Lovelace", "", ""),
        ("Ben Ng", "", ""),
    ]
    listed = read_roster(
        write(
            tmp_path,
            "class.csv",
            "\ufeffID,Name,E-mail\ns1001,Ada Lovelace,ada@uni.edu\n,,\ns1002,Ben Ng,\n",
        )
    )
    assert [(s.name, s.id, s.email) for s in listed] == [
        ("Ada Lovelace", "s1001", "ada@uni.edu"),
        ("Ben Ng", "s1002", ""),
    ]
    semicolons = read_roster(
        write(tmp_path, "eu.csv", "student number;first name;last name\n7;Émilie;du Châtelet\n")
    )
    assert [(s.name, s.id) for s in semicolons] == [("Émilie du Châtelet", "7")]


def test_lms_exports_are_class_lists_as_they_are(tmp_path):
    canvas = read_roster(
        write(
            tmp_path,
            "canvas.csv",
            "Student,ID,SIS User ID,SIS Login ID,Section,Lab 20 (4411)\n"
            "    Points Possible,,,,,8\n"
            '"Lovelace, Ada",5011,s1001,ada@uni.edu,CS370-01,\n',
        )
    )
    assert len(canvas) == 1
    ada = canvas[0]
    assert (ada.name, ada.id) == ("Lovelace, Ada", "5011")
    assert ada.fields["SIS User ID"] == "s1001" and ada.fields["Section"] == "CS370-01"
    moodle = read_roster(
        write(
            tmp_path,
            "moodle.csv",
            "First name,Last name,ID number,Institution,Department,Email address\n"
            "Ben,Ng,s1002,Uni,CS,ben@uni.edu\n",
        )
    )
    assert [(s.name, s.id, s.email) for s in moodle] == [("Ben Ng", "s1002", "ben@uni.edu")]


def test_a_submission_is_the_student_it_is_named_by():
    ada = Student("Lovelace, Ada", "s1001", "ada.l@uni.edu")
    ben = Student("Ben Ng", "s1002", "")
    roster = [ada, ben]
    for name in ("Ada_Lovelace", "lovelace-ada", "S1001", "ada.l@uni.edu", "ada_l"):
        assert find_student(roster, name) is ada, name
    assert find_student(roster, "ben_ng") is ben
    assert find_student(roster, "Cy") is None
    on, off, missing = match_class([Submission("s1001", None), Submission("zed", None)], roster)
    assert [(s.student, s.who) for s in on] == [("Lovelace, Ada", ada)]
    assert [s.student for s in off] == ["zed"] and missing == [ben]
    with pytest.raises(ValueError, match="are both 'Lovelace, Ada \\(s1001\\)'"):
        match_class([Submission("s1001", None), Submission("ada_lovelace", None)], roster)


@pytest.mark.parametrize(
    ("name", "text", "said"),
    [
        ("no_name.csv", "id,email\n1,a@b\n", "has no name column"),
        ("same_id.csv", "id,name\n1,Ada\n1,Ben\n", "are the same student"),
        ("same_name.txt", "Ada Lovelace\nada_lovelace\n", "are the same student"),
        ("email_is_a_name.csv", "name,email\nAda,x@u\nBen,ada@u\n", "are the same student"),
        ("blank.csv", "name,id\n!!,3\n", "line 2 of blank.csv has no name"),
        ("empty.csv", "name,id\n", "holds no students"),
    ],
)
def test_a_list_that_cannot_be_used_is_one_line(tmp_path, name, text, said):
    with pytest.raises(ValueError, match=said) as refused:
        read_roster(write(tmp_path, name, text))
    assert "\n" not in str(refused.value) and str(refused.value).startswith("--students:")


# ------------------------------------------------------------------------------ gradebooks
def grade(student: str, score: int | None, **extra) -> Grade:
    passed = [i < (score or 0) for i in range(len(TASKS))]
    return Grade(
        student,
        [(t, p, "") for t, p in zip(TASKS, passed, strict=True)],
        "ok",
        1.0,
        b"",
        **extra,
    )


CLASS = [
    grade("Ada Lovelace", 8, student_id="s1001", email="ada@uni.edu"),
    grade("Ben Ng", 5, student_id="s1002", email="ben@uni.edu"),
    grade("Cy Twombly", 3, student_id="s1003", email="", copied_from="Ada Lovelace"),
    grade("Dee Dee", None, student_id="s1004", email="dee@uni.edu", not_graded="disk full"),
]


def rows(text: str) -> list[list[str]]:
    return list(csv.reader(io.StringIO(text)))


def canvas_reads(table: list[list[str]]) -> dict[str, list]:
    """The header, points and student rows as Canvas's importer takes them
    (instructure/canvas-lms, app/models/gradebook_importer.rb: row_has_student_headers?,
    update_column_count, check_for_non_student_row)."""
    header = table[0]
    assert len(header) > 3 and "Student" in header[0] and "ID" in header[1]
    assert header[2] == "SIS User ID" and header[3] == "SIS Login ID"
    student_columns = 5  # name, ID, SIS User ID, SIS Login ID, Section
    assert "Section" in header[student_columns - 1]
    assignments = header[student_columns:]
    points = [row for row in table[1:] if "Points Possible" in row[0]]
    students = [row for row in table[1:] if "Points Possible" not in row[0]]
    return {"assignments": assignments, "points": points, "students": students}


def test_the_canvas_gradebook_is_what_canvas_imports():
    table = rows(FORMATS["canvas"](SPEC, CLASS, "hold", "Lab 20 (4411)"))
    read = canvas_reads(table)
    assert read["assignments"] == ["Lab 20 (4411)"]
    assert read["points"] == [["Points Possible", "", "", "", "", "8"]]
    # ids in SIS User ID (never Canvas's own ID, which another id could name wrongly);
    # a held copy and a submission not graded post nothing (an empty cell changes nothing)
    assert read["students"] == [
        ["Ada Lovelace", "", "s1001", "ada@uni.edu", "", "8"],
        ["Ben Ng", "", "s1002", "ben@uni.edu", "", "5"],
        ["Cy Twombly", "", "s1003", "", "", ""],
        ["Dee Dee", "", "s1004", "dee@uni.edu", "", ""],
    ]
    # a list exported from Canvas keeps Canvas's own identifiers
    fields = {"Student": "Lovelace, Ada", "ID": "5011", "SIS User ID": "s1001"}
    fields |= {"SIS Login ID": "alove", "Section": "CS370-01"}
    exported = grade("Lovelace, Ada", 7, student_id="5011", fields=fields)
    (row,) = canvas_reads(rows(FORMATS["canvas"](SPEC, [exported], "flag", "Lab")))["students"]
    assert row == ["Lovelace, Ada", "5011", "s1001", "alove", "CS370-01", "7"]


def test_the_moodle_gradebook_has_a_row_for_every_grade_and_no_other():
    table = rows(FORMATS["moodle"](SPEC, CLASS, "zero", "Lab 20"))
    assert table[0] == ["Full name", "ID number", "Email address", "Lab 20"]
    # Moodle reads an empty cell as "no grade" (clearing one): no row for Dee, not graded
    assert table[1:] == [
        ["Ada Lovelace", "s1001", "ada@uni.edu", "8"],
        ["Ben Ng", "s1002", "ben@uni.edu", "5"],
        ["Cy Twombly", "s1003", "", "0"],
    ]
    with pytest.raises(ValueError, match="needs to find the student"):
        check_format("moodle", [Student("Ada"), Student("Ben", "s2")])
    with pytest.raises(ValueError, match="give --students"):
        check_format("moodle", None)
    with pytest.raises(ValueError, match="is not a layout"):
        check_format("blackboard", None)


def test_the_plain_gradebook_leaves_a_submission_not_graded_empty():
    table = rows(FORMATS["plain"](SPEC, CLASS, "flag", "Lab 20"))
    by_name = {row[0]: dict(zip(table[0], row, strict=True)) for row in table[1:]}
    assert by_name["Dee Dee"]["score"] == by_name["Dee Dee"]["percent"] == ""
    assert by_name["Dee Dee"]["not_graded"] == "disk full"
    assert by_name["Cy Twombly"]["copy_of"] == "Ada Lovelace"
    assert (by_name["Ada Lovelace"]["id"], by_name["Ada Lovelace"]["score"]) == ("s1001", "8")


# ------------------------------------------------------------------ a starter's variant line
@settings(max_examples=40, deadline=None)
@given(st.sampled_from(["lab20", "spheremap", "cubemap"]), st.text(min_size=1, max_size=30))
def test_a_starters_header_names_its_variant_and_nothing_else(lab, name):
    key = b"a course key for the tests: 0123456789abcdef"
    variant = derive_variant(lab, key, name)
    text = header_line(variant) + "print('my file')\n"
    found = variant_from_header(text, lab, "starter.py")
    assert found is not None and (found.id, found.values) == (variant.id, variant.values)
    assert variant_from_header("print('no header')\n", lab, "starter.py") is None


def test_a_header_with_numbers_outside_the_lab_is_refused():
    variant = default_variant("lab20")
    line = header_line(variant)
    for forged, said in (
        (line.replace('"width": 8.0', '"width": 1000'), "width = 1000 is not one of"),
        (line.replace('"mirror_x": -7.0', '"mirror_x": -7.5'), "default variant with numbers"),
        (line.replace('"lab20"', '"cubemap"'), "not of lab20"),
        (line[:40] + "\n", "its variant line, is not one"),
    ):
        with pytest.raises(VariantError, match=said):
            variant_from_header(forged, "lab20", "mine.py")
