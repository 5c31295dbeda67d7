"""Evidence nobody can launder (issue 39, round two): the forgeries of tests/labs/
launderings.py each fail at least one task, with the hint that names what they did (since
round three, the refusal of the channel they used: tests/gl/test_lab_channels.py tries
every channel, tests/unit/test_overlays.py the whole frame's rule)."""

from __future__ import annotations

import pytest

from mirrorlab.labs import find_lab, lab_names
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted.grading import grade_folder
from tests.labs.conftest import LIMITS, SOLUTIONS
from tests.labs.launderings import launderings


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_laundered_evidence_fails_with_its_hint(lab, tmp_path):
    found = launderings()[lab]
    folder = tmp_path / "class"
    folder.mkdir()
    for name, (source, _) in found.items():
        (folder / f"{name}.py").write_text(source)
    grades, _ = grade_folder(
        find_lab(lab), folder, 2, None, "pool", LIMITS, progress=False, solutions=SOLUTIONS
    )
    by_student = {g.student: g.tasks for g in grades}
    assert sorted(by_student) == sorted(found)
    for name, (_, phrase) in found.items():
        tasks = by_student[name]
        failed = [hint for _, passed, hint in tasks if not passed]
        assert failed, f"{name} passed every task"
        assert any(phrase in hint for hint in failed), (name, phrase, failed)
        assert all("\n" not in hint and "Traceback" not in hint for _, _, hint in tasks)


def test_no_lab_offers_a_way_to_read_what_was_drawn():
    for lab in lab_names():
        offered = C.lab_specs(lab)
        for name in C.REFUSED:
            assert name not in offered, (lab, name)
            assert C.refused_text(lab, name).startswith(
                f"{name} is not one of the OpenGL calls this lab offers: "
            )
    assert "glCopyTexImage2D" not in C.lab_specs("spheremap")
    assert "glCopyTexImage2D" in C.lab_specs("lab20")
    assert "glUniform1i" in C.lab_specs("lab20") and "glUniform1i" not in C.lab_specs("cubemap")


def test_one_file_for_every_variant_gets_a_refusal_for_each_student(tmp_path):
    """The issue's file, shared by students of different variants: before, each got 8/8;
    now each is refused at the first call that draws in set-up."""
    source, phrase = launderings()["lab20"]["measure_variant_at_setup"]
    folder = tmp_path / "class"
    folder.mkdir()
    for student in ("Ada_Lovelace", "Ben_Ng"):
        (folder / f"{student}.py").write_text(source)
    grades, _ = grade_folder(
        find_lab("lab20"),
        folder,
        2,
        None,
        "pool",
        LIMITS,
        progress=False,
        key=b"a course key of the test, 32 bytes",
        solutions=SOLUTIONS,
    )
    assert len({g.variant for g in grades}) == 2
    for grade in grades:
        hints = [hint for _, passed, hint in grade.tasks if not passed]
        assert hints and any(phrase in hint for hint in hints), (grade.student, hints)
