"""``mirrorlab lab check``: every reference solution passes its checker, every untouched
starter fails each task with the hint the handout's step calls for, and bad command lines
get one line and exit 2. (Every mutant's verdicts and hints: test_hints.py.)"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mirrorlab.labs import find_lab, lab_names
from mirrorlab.scene.backgrounds import load_picture
from tests.labs.classroom import STARTER, starter_text
from tests.labs.conftest import LIMITS, SOLUTIONS, mirrorlab_command


def task_lines(output: str) -> dict[int, tuple[str, str]]:
    """task number -> (pass/FAIL, hint) from the checker's printout."""
    lines = output.splitlines()
    found = {}
    for i, line in enumerate(lines):
        if line.strip().startswith(("[pass] task", "[FAIL] task")):
            number = int(line.split("task ")[1].split(" ")[0])
            hint = (
                lines[i + 1].strip()
                if i + 1 < len(lines) and lines[i + 1].strip().startswith(("hint:", "note:"))
                else ""
            )
            found[number] = ("pass" if "[pass]" in line else "FAIL", hint)
    return found


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_reference_solution_passes(lab, tmp_path):
    spec = find_lab(lab)
    out = tmp_path / "check.png"
    done = mirrorlab_command(
        "lab",
        "check",
        lab,
        str(SOLUTIONS / f"{spec.folder}.py"),
        "--out",
        str(out),
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stdout + done.stderr
    count = len(spec.tasks)
    assert f"{count}/{count} tasks passed" in done.stdout
    assert all(state == "pass" for state, _ in task_lines(done.stdout).values())
    picture = load_picture(out)
    # student | reference | difference: the difference of the solution against itself is 0
    cell = (picture.shape[1] - 8) // 3
    rows = slice(16, 16 + cell)
    assert np.array_equal(picture[rows, :cell], picture[rows, cell + 4 : 2 * cell + 4])
    assert picture[rows, 2 * cell + 8 :].max() == 0


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_untouched_starter_fails_every_task_with_its_hint(lab, tmp_path):
    """The starter ``lab start`` writes, checked with no FILE from its folder (the folder's
    own file), judged against the packaged reference evidence: no solutions at hand, as
    for a student with the wheel. The report's first line names the file checked."""
    spec = find_lab(lab)
    started = mirrorlab_command("lab", "start", lab, str(tmp_path / "mine"))
    assert started.returncode == 0, started.stderr
    done = mirrorlab_command(
        "lab",
        "check",
        spec.folder,
        "--timeout",
        str(LIMITS.cpu_seconds),
        cwd=tmp_path / "mine",
        env={"MIRRORLAB_SOLUTIONS": None},
    )
    assert done.returncode == 1, done.stdout + done.stderr
    checked = tmp_path / "mine" / "starter.py"
    assert done.stdout.splitlines()[0] == f"{spec.title}: {checked}"
    assert (tmp_path / "mine" / "out" / f"{lab}_check.png").is_file()
    found = task_lines(done.stdout)
    assert sorted(found) == [t.number for t in spec.tasks]
    for task in spec.tasks:
        state, hint = found[task.number]
        assert state == "FAIL" and STARTER[lab][task.id] in hint, (task.id, hint)
    assert f"0/{len(spec.tasks)} tasks passed" in done.stdout


def test_check_without_a_file_checks_the_folders_own_or_refuses(tmp_path):
    """``lab check LAB`` with no FILE checks the folder's starter.py (here a finished one:
    every task passes, never the package's untouched starter) and overwrites the picture;
    in a folder without one, or with another lab's, it refuses in one line and leaves the
    picture it made before alone."""
    folder = tmp_path / "done"
    folder.mkdir()
    (folder / "starter.py").write_text((SOLUTIONS / "lab20_mirror.py").read_text())
    picture = folder / "out" / "lab20_check.png"
    done = mirrorlab_command(
        "lab", "check", "lab20", "--timeout", str(LIMITS.cpu_seconds), cwd=folder
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.splitlines()[0] == f"{find_lab('lab20').title}: {folder / 'starter.py'}"
    assert "8/8 tasks passed" in done.stdout and picture.is_file()
    made = picture.read_bytes()
    (folder / "starter.py").rename(folder / "mine.py")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "starter.py").write_text(starter_text("spheremap"))
    for where, message in (
        (folder, "holds no starter.py"),
        (tmp_path / "other", "a file of the spheremap lab"),
    ):
        refused = mirrorlab_command("lab", "check", "lab20", "--out", str(picture), cwd=where)
        assert refused.returncode == 2, refused.stdout + refused.stderr
        assert message in refused.stderr and refused.stdout == ""
        assert len(refused.stderr.strip().splitlines()) == 1, refused.stderr
    assert picture.read_bytes() == made


def test_every_hint_names_another_task_by_its_one_name():
    """Hints point to another task as ``task 8 (passes)`` (:func:`mirrorlab.labs.task_name`),
    the name the CSVs, reports and check lines use; none writes a bare ``task 8``."""
    import ast
    import re

    from mirrorlab.labs import labs, task_name
    from tests import REPO_DIR

    trusted = REPO_DIR / "mirrorlab/labs/trusted"
    paths = [spec.home / "judge.py" for spec in labs()] + [
        trusted / f"{module}.py" for module in ("judging", "checker", "grading", "report", "window")
    ]
    assert len(paths) == 8
    for path in paths:
        module = str(path.relative_to(REPO_DIR))
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                assert not re.search(r"\btask \d+(?! \()", node.value, re.I), (module, node.value)
    assert task_name("lab20", "passes") == "task 8 (passes)"
    assert [t.name for t in find_lab("cubemap").tasks][:1] == ["task 1 (face_selection)"]


def test_bad_command_lines_get_one_line_and_exit_2(tmp_path):
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "starter.py").write_text("# mine\n")
    (tmp_path / "full.key").write_text("a course key of more than 16 bytes\n")
    cases = [
        (("lab", "check", "lab99"), "LAB: unknown lab 'lab99'"),
        (("lab", "check", "lab20", str(tmp_path / "nothing.py")), "FILE:"),
        (("lab", "check", "lab20", "--out", str(tmp_path / "x.jpg")), "--out: expected"),
        (("lab", "check", "lab20", "--solutions", str(tmp_path / "none")), "--solutions:"),
        (("lab", "grade", "lab20", str(tmp_path / "missing")), "SUBMISSIONS_DIR:"),
        (("lab", "grade", "lab20", str(tmp_path), "--jobs", "0"), "--jobs"),
        (
            ("lab", "grade", "lab20", str(tmp_path), "--key", str(tmp_path / "no.key")),
            "--key: cannot read",
        ),
        (
            ("lab", "grade", "lab20", str(tmp_path), "--key", str(tmp_path / "full.key")),
            "give --students FILE",
        ),
        (
            ("lab", "grade", "lab20", str(tmp_path), "--copies", "half"),
            "--copies: 'half' is not a policy",
        ),
        (("lab", "check", "lab20", "--timeout=0"), "--timeout"),
        (("lab", "start", "lab20", str(tmp_path / "full")), "already holds starter.py"),
        (
            ("lab", "solution", "lab20", "--student", "ada", "--key", str(tmp_path / "no.key")),
            "--key: cannot read",
        ),
        (
            (
                "lab",
                "release",
                "lab20",
                str(tmp_path / "out"),
                "--students",
                str(tmp_path / "none.txt"),
                "--key",
                str(tmp_path / "k"),
            ),
            "--students: cannot read",
        ),
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
