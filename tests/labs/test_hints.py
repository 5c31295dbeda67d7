"""Hints by cause: every mutant of the suite (tests/labs/mutants.py), round two's among them
(GLSL slips that give another slip's numbers on the cone, GL errors, a frame stopped
early), is checked (one warm checker a lab: tests/labs/warm_checks.py), and the hint of
its first failing task names that mutant's cause; the issue's slips fail exactly the
tasks they should."""

from __future__ import annotations

import pytest

from mirrorlab.labs import lab_names
from tests.labs.mutants import EVERY_MUTANT, PROBED_SLIPS, ROUND_TWO, problems, write_mutants
from tests.labs.warm_checks import check_folder


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_the_first_failing_hint_names_the_cause(lab, tmp_path):
    mutants = [m for m in EVERY_MUTANT if m.lab == lab]
    written = write_mutants(tmp_path / "class", mutants)
    by_student = check_folder(lab, tmp_path / "class")
    wrong = []
    for stem, mutant in written.items():
        first, cause = mutant.expected_cause()
        failing = [(task, hint) for task, passed, hint in by_student[stem] if not passed]
        if not failing or failing[0][0] != first or cause not in failing[0][1]:
            wrong.append(f"{stem}: expected {first!r} first, naming {cause!r}; got {failing[:1]}")
        if mutant in ROUND_TWO or mutant in PROBED_SLIPS:
            verdicts = {task: (passed, hint) for task, passed, hint in by_student[stem]}
            wrong += [f"{stem}: {p}" for p in problems(mutant.fails, verdicts)]
        for _, _, hint in by_student[stem]:
            if "GLError(err" in hint:
                wrong.append(f"{stem}: a raw GL error reaches the student: {hint}")
    assert wrong == []
