"""Hints by cause, from the call trace: every mutant of the suite (tests/labs/mutants.py:
the first rounds', issue 45's slips by pattern, the held-out batch, the GLSL slips the
value probe names, and the forms the handouts allow, which pass every task) is checked (one
warm checker a lab: tests/labs/warm_checks.py), the hint of its first failing task names
that mutant's cause, every task fails or passes as the mutant says, and no hint asks for a
call the file already made with the same arguments (the hints' property: parsed from the
hint, searched among the calls the file executed)."""

from __future__ import annotations

import re

import pytest

from mirrorlab.labs import lab_names
from tests.labs.mutants import (
    CUBE_EQUIVALENT,
    EVERY_MUTANT,
    GLSL_EQUIVALENT,
    HELD_OUT,
    TRACE_EQUIVALENT,
    TRACE_SLIPS,
    problems,
    write_mutants,
)
from tests.labs.warm_checks import check_folder_with_calls

ALL = (
    *EVERY_MUTANT,
    *TRACE_SLIPS,
    *HELD_OUT,
    *TRACE_EQUIVALENT,
    *GLSL_EQUIVALENT,
    *CUBE_EQUIVALENT,
)
CALL = re.compile(r"\b((?:glu?|lab\.)[A-Za-z_]\w*)\(([^()]*(?:\([^()]*\)[^()]*)*)\)")
QUOTE = re.compile(r"line \d+ \((?:[^()]|\((?:[^()]|\([^()]*\))*\))*\)|line \d+: .*? -> ")
"""The student's own lines as a hint quotes them (``line N (code)``, ``line N: code ->``):
what the file made, not what the hint asks for."""
FILE_NAME = re.compile(r"(?!GL_)[A-Z_][A-Z0-9_]*|.*[-+*/%].*")
"""An argument written with the file's own names (``WIDTH``, ``WIDTH // 2``): any value."""


def asked_calls(hint: str) -> list[tuple[str, list[str]]]:
    """The calls ``hint`` names outside the student's quoted lines: what it asks for (or
    shows as the solution's), each as (name, its arguments)."""
    text = QUOTE.sub(" ", hint)
    return [
        (m.group(1), [a.strip() for a in m.group(2).split(",") if a.strip()])
        for m in CALL.finditer(text)
        if not text[m.end() :].startswith(" at line")
    ]


def made_with_those_arguments(fn: str, arguments: list[str], made: list[str]) -> str:
    """The call the file executed that ``fn(arguments)`` is (same name, every argument the
    same, an argument in the file's own names standing for any), or ''."""
    for text in made:
        name, _, rest = text.partition("(")
        if name != fn:
            continue
        have = [a.strip() for a in rest[:-1].split(",") if a.strip()]
        if len(have) == len(arguments) and all(
            a == b or FILE_NAME.fullmatch(a) for a, b in zip(arguments, have, strict=True)
        ):
            return text
    return ""


def test_every_lab_has_a_dozen_slips_by_pattern():
    slips = {lab: sum(m.lab == lab for m in TRACE_SLIPS) for lab in lab_names()}
    assert min(slips.values()) >= 12, slips


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_hints_name_causes_and_never_ask_for_a_call_the_file_made(lab, tmp_path):
    mutants = [m for m in ALL if m.lab == lab]
    written = write_mutants(tmp_path / "class", mutants)
    assert len(written) == len(mutants), "two mutants share a name"
    graded = check_folder_with_calls(lab, tmp_path / "class")
    wrong = []
    for key, (tasks, made) in graded.items():
        mutant = written[key]
        verdicts = {task: (passed, hint) for task, passed, hint in tasks}
        wrong += [f"{key}: {p}" for p in problems(mutant.fails, verdicts)]
        failing = [(task, hint) for task, passed, hint in tasks if not passed]
        if mutant.fails:
            first, cause = mutant.expected_cause()
            if not failing or failing[0][0] != first or cause not in failing[0][1]:
                wrong.append(f"{key}: expected {first!r} first, naming {cause!r}: {failing[:1]}")
        for task, hint in failing:
            if "GLError(err" in hint:
                wrong.append(f"{key} {task}: a raw GL error reaches the student: {hint}")
            for fn, arguments in asked_calls(hint):
                if made_call := made_with_those_arguments(fn, arguments, made):
                    wrong.append(f"{key} {task}: asks for {made_call}, which the file made: {hint}")
    assert wrong == []
