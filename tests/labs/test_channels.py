"""Round three's files against the channels from a file's numbers to the frame (tests/labs/
channel_forgeries.py, issue 44): forged passes 1, 2, 3 and 7 each fail a task (the hatched
word by the whole frame's rule at every scale), the crash files are judged (the modelview
stack left full passes, the depth-format copy fails naming the format), and the leftover
state fuzz corpus is judged task by task in one line each, never "grading failed"."""

from __future__ import annotations

import pytest

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.grading import grade_folder
from tests.labs.channel_forgeries import channel_forgeries
from tests.labs.conftest import LIMITS, SOLUTIONS

FILES = channel_forgeries()


@pytest.mark.parametrize("lab", ["lab20", "spheremap", "cubemap"])
def test_channel_forgeries_fail_and_crashes_are_judged(lab, tmp_path):
    found = {f.name: f for f in FILES if f.lab == lab}
    folder = tmp_path / "class"
    folder.mkdir()
    for name, forged in found.items():
        (folder / f"{name}.py").write_text(forged.source)
    grades, _ = grade_folder(  # one process: a pool's start costs more than it saves here
        find_lab(lab), folder, 1, None, "pool", LIMITS, progress=False, solutions=SOLUTIONS
    )
    by_student = {g.student: g for g in grades}
    assert sorted(by_student) == sorted(found)
    for name, forged in found.items():
        grade = by_student[name]
        assert grade.status in ("ok", "stopped"), (name, grade.status)
        tasks = grade.tasks
        assert len(tasks) == len(find_lab(lab).tasks)
        for _, _, hint in tasks:
            assert "\n" not in hint and "Traceback" not in hint, (name, hint)
            assert "grading failed" not in hint and "could not be judged" not in hint, hint
            assert "checker's OpenGL process failed" not in hint, (name, hint)
        failed = [hint for _, passed, hint in tasks if not passed]
        if forged.expect == "pass":
            assert not failed, (name, failed)
        elif forged.expect == "fail":
            assert failed, f"{name} passed every task"
            assert any(forged.phrase in hint for hint in failed), (name, forged.phrase, failed)
