"""``mirrorlab lab check``: every reference solution passes its checker, every untouched
starter fails each task with the hint the handout's step calls for, the sphere-map and
cube-map mutants are each caught with the right hint (each of the issue's hint problems
among them) and their allowed equivalents pass (lab 20's are in the class graded by
test_grading.py), and bad command lines get one line and exit 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mirrorlab.labs import LABS
from mirrorlab.labs.trusted.grading import grade_folder
from mirrorlab.scene.backgrounds import load_picture
from tests.labs.classroom import STARTER
from tests.labs.conftest import LIMITS, SOLUTIONS, mirrorlab_command
from tests.labs.mutants import (
    CUBE_EQUIVALENT,
    CUBEMAP,
    LAB20_MORE,
    SPHEREMAP,
    problems,
    write_mutants,
)


def task_lines(output: str) -> dict[int, tuple[str, str]]:
    """task number -> (pass/FAIL, hint) from the checker's printout."""
    lines = output.splitlines()
    found = {}
    for i, line in enumerate(lines):
        if line.strip().startswith(("[pass] task", "[FAIL] task")):
            number = int(line.split("task ")[1].split(" ")[0])
            hint = lines[i + 1].strip() if i + 1 < len(lines) and \
                lines[i + 1].strip().startswith(("hint:", "note:")) else ""
            found[number] = ("pass" if "[pass]" in line else "FAIL", hint)
    return found


@pytest.mark.parametrize("lab", sorted(LABS))
def test_reference_solution_passes(lab, tmp_path):
    spec = LABS[lab]
    out = tmp_path / "check.png"
    done = mirrorlab_command("lab", "check", lab, str(SOLUTIONS / f"{spec.folder}.py"),
                             "--out", str(out), "--timeout", str(LIMITS.cpu_seconds))
    assert done.returncode == 0, done.stdout + done.stderr
    count = len(spec.tasks)
    assert f"{count}/{count} tasks passed" in done.stdout
    assert all(state == "pass" for state, _ in task_lines(done.stdout).values())
    picture = load_picture(out)
    # student | reference | difference: the difference of the solution against itself is 0
    cell = (picture.shape[1] - 8) // 3
    rows = slice(16, 16 + cell)
    assert np.array_equal(picture[rows, :cell], picture[rows, cell + 4:2 * cell + 4])
    assert picture[rows, 2 * cell + 8:].max() == 0


@pytest.mark.parametrize("lab", sorted(LABS))
def test_untouched_starter_fails_every_task_with_its_hint(lab, tmp_path):
    """The packaged starter (no FILE), judged against the packaged reference evidence:
    no solutions at hand, as for a student with the wheel."""
    spec = LABS[lab]
    done = mirrorlab_command("lab", "check", spec.folder, "--out", str(tmp_path / "c.png"),
                             "--timeout", str(LIMITS.cpu_seconds),
                             env={"MIRRORLAB_SOLUTIONS": None})
    assert done.returncode == 1, done.stdout + done.stderr
    found = task_lines(done.stdout)
    assert sorted(found) == [t.number for t in spec.tasks]
    for task in spec.tasks:
        state, hint = found[task.number]
        assert state == "FAIL" and STARTER[lab][task.id] in hint, (task.id, hint)
    assert f"0/{len(spec.tasks)} tasks passed" in done.stdout


@pytest.mark.parametrize("lab, mutants", [("spheremap", SPHEREMAP),
                                          ("cubemap", (*CUBEMAP, *CUBE_EQUIVALENT)),
                                          ("lab20", LAB20_MORE)])
def test_each_mutant_is_caught_with_the_right_hint(lab, mutants, tmp_path):
    assert len(mutants) >= 6
    written = write_mutants(tmp_path / "class", mutants)
    if lab == "spheremap":  # a GLSL slip: the error names the Python string and its line
        source = (SOLUTIONS / "lab_spheremap.py").read_text().replace(
            "return u - 2.0 * dot(n, u) * n;", "return u - 2.0 * dot(n, u) * n")
        (tmp_path / "class" / "glsl_typo.py").write_text(source)
    grades, _ = grade_folder(LABS[lab], tmp_path / "class", 2, None, "pool", LIMITS,
                             progress=False, solutions=SOLUTIONS)
    by_student = {g.student: {task: (passed, hint) for task, passed, hint in g.tasks}
                  for g in grades}
    for stem, mutant in written.items():
        assert problems(mutant.fails, by_student[stem]) == [], stem
    if lab == "spheremap":
        typo = by_student["glsl_typo"]
        for task in ("reflection", "sphere_coordinates"):
            assert not typo[task][0] and "GLSL in SPHERE_MAP_GLSL line" in typo[task][1]


def test_bad_command_lines_get_one_line_and_exit_2(tmp_path):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "starter.py").write_text("# mine\n")
    cases = [
        (("lab", "check", "lab99"), "LAB: unknown lab 'lab99'"),
        (("lab", "check", "lab20", str(tmp_path / "nothing.py")), "FILE:"),
        (("lab", "check", "lab20", "--out", str(tmp_path / "x.jpg")), "--out: expected"),
        (("lab", "check", "lab20", "--solutions", str(tmp_path / "none")), "--solutions:"),
        (("lab", "grade", "lab20", str(tmp_path / "missing")), "SUBMISSIONS_DIR:"),
        (("lab", "grade", "lab20", str(tmp_path), "--jobs", "0"), "--jobs"),
        (("lab", "grade", "lab20", str(tmp_path), "--key", str(tmp_path / "no.key")),
         "--key: cannot read"),
        (("lab", "check", "lab20", "--timeout=0"), "--timeout"),
        (("lab", "start", "lab20", str(tmp_path / "full")), "already holds starter.py"),
        (("lab", "solution", "lab20", "--student", "ada", "--key", str(tmp_path / "no.key")),
         "--key: cannot read"),
        (("lab", "release", "lab20", str(tmp_path / "out"), "--students",
          str(tmp_path / "none.txt"), "--key", str(tmp_path / "k")), "--students: cannot read"),
    ]
    for args, message in cases:
        done = mirrorlab_command(*args)
        assert done.returncode == 2, (args, done.stderr)
        assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "x.jpg").exists()
    assert (tmp_path / "full" / "starter.py").read_text() == "# mine\n"
    assert not (tmp_path / "k").exists() and not (tmp_path / "out").exists()


def test_an_empty_class_folder_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("no submissions here")
    done = mirrorlab_command("lab", "grade", "lab20", str(tmp_path))
    assert done.returncode == 2 and "holds no .py file" in done.stderr
    assert not Path(str(tmp_path) + "-grades").exists()
