"""A fourth lab added by a test alone: tests/labs/fourth_lab/ holds its spec, student and
trusted sides, judge, handout, starter and solution, and registers itself when imported.
Nothing of mirrorlab names it, yet ``lab start``, ``check``, ``release`` and ``grade``
take it (in this process: the registry is this process's; the checker's GL process and
the sandbox find the lab from its registry entry)."""

from __future__ import annotations

import importlib
import json
import os

import pytest

from mirrorlab.cli import main
from mirrorlab.labs import LabSpec, find_lab, lab_names, unregister
from mirrorlab.labs.content import solution_for
from mirrorlab.labs.trusted.variants import variant_from_file
from tests.labs.conftest import read_csv

NO_SANDBOX = ["--unsandboxed"] if os.environ.get("MIRRORLAB_SANDBOX") == "none" else []


@pytest.fixture
def quad_lab():
    """The fourth lab, registered for one test and removed after it."""
    spec = importlib.import_module("tests.labs.fourth_lab").SPEC
    yield spec
    unregister(spec.name)


def test_the_fourth_lab_is_registered_from_its_own_folder_alone(quad_lab: LabSpec):
    assert "quad" in lab_names() and find_lab("lab_quad") is quad_lab
    assert quad_lab.home.parent.name == "labs" and quad_lab.solution.is_file()
    assert not (quad_lab.home / "reference").exists()  # its reference comes from its solution


def test_lab_start_check_release_and_grade_take_the_fourth_lab(quad_lab, tmp_path, capsys):
    # lab start: the handout and the starter, with the lab's own colour
    assert main(["lab", "start", "quad", str(tmp_path / "mine")]) == 0
    handout = (tmp_path / "mine" / "README.md").read_text()
    assert handout.startswith("# The quad lab") and "(0.3, 0.2, 0.4)" in handout
    starter = tmp_path / "mine" / "starter.py"
    assert "{{" not in starter.read_text()

    # lab check: the starter fails each task with a hint, the solution passes
    capsys.readouterr()
    out = ["--out", str(tmp_path / "check.png")]
    assert main(["lab", "check", "quad", str(starter), *out]) == 1
    report = capsys.readouterr().out
    assert "[FAIL] task 1 (clear)" in report and "[FAIL] task 2 (quad)" in report
    assert "hint: clear_background() makes no glClearColor(0.3, 0.2, 0.4, 1)" in report
    assert "hint: draw_quad() makes no " in report
    assert main(["lab", "check", "quad", str(quad_lab.solution), *out]) == 0
    assert "2/2 tasks passed" in capsys.readouterr().out

    # lab release: each student's folder with their own colour and reference
    (tmp_path / "class.txt").write_text("Ada Lovelace\nAlan Turing\n")
    key = tmp_path / "course.key"
    released = tmp_path / "released"
    release = ["--students", str(tmp_path / "class.txt"), "--key", str(key), "--jobs", "1"]
    assert main(["lab", "release", "quad", str(released), *release]) == 0
    ada = released / "Ada_Lovelace"
    variant = json.loads((ada / "variant.json").read_text())
    assert variant["lab"] == "quad" and (ada / "reference" / "evidence.json").is_file()
    colour = f"({variant['values']['red']:g}, 0.2, 0.4)"
    assert colour in (ada / "README.md").read_text()
    # Ada's solution, made for her numbers, passes against her released reference
    mine = ada / "mine.py"
    mine.write_text(
        solution_for(quad_lab.solution.read_text(), variant_from_file(ada / "variant.json", "quad"))
    )
    capsys.readouterr()
    assert main(["lab", "check", "quad", str(mine), *out]) == 0

    # lab grade: a solution and a starter
    submissions = tmp_path / "submissions"
    submissions.mkdir()
    (submissions / "good.py").write_text(quad_lab.solution.read_text())
    (submissions / "empty.py").write_text(starter.read_text())
    grades = tmp_path / "grades"
    assert (
        main(["lab", "grade", "quad", str(submissions), "--out-dir", str(grades), *NO_SANDBOX]) == 0
    )
    rows = {(r["student"], r["task"]): r["passed"] for r in read_csv(grades / "grades.csv")}
    assert rows == {
        ("empty", "task 1 (clear)"): "no",
        ("empty", "task 2 (quad)"): "no",
        ("good", "task 1 (clear)"): "yes",
        ("good", "task 2 (quad)"): "yes",
    }


def test_the_fourth_lab_leaves_the_registry_with_its_test(quad_lab):
    unregister(quad_lab.name)
    with pytest.raises(ValueError, match="unknown lab 'quad'"):
        find_lab("quad")
    importlib.import_module("tests.labs.fourth_lab")  # for the fixture to remove again
