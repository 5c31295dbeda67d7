"""Hints by cause, from the call trace: every mutant of the suite (tests/labs/mutants.py:
the first rounds', issue 45's slips by pattern, the held-out batch, and the forms the
handouts allow, which pass every task) is checked, the hint of its first failing task names
that mutant's cause, every task fails or passes as the mutant says, and no hint asks for a
call the file already made with the same arguments (the hints' property: parsed from the
hint, searched among the calls the file executed)."""

from __future__ import annotations

import re

from mirrorlab.jobs import PoolExecutor
from tests.labs.conftest import LIMITS, SOLUTIONS
from tests.labs.jobfunctions import judged_with_calls
from tests.labs.mutants import (
    EVERY_MUTANT,
    HELD_OUT,
    TRACE_EQUIVALENT,
    TRACE_SLIPS,
    Mutant,
    problems,
)

ALL = (*EVERY_MUTANT, *TRACE_SLIPS, *HELD_OUT, *TRACE_EQUIVALENT)
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


def test_hints_name_causes_and_never_ask_for_a_call_the_file_made():
    sources = {f"{m.lab}_{m.name}": (m.lab, m.source()) for m in ALL}
    mutants: dict[str, Mutant] = {f"{m.lab}_{m.name}": m for m in ALL}
    assert len(sources) == len(ALL), "two mutants share a name"
    graded = {}
    with PoolExecutor(2) as executor:
        jobs = {key: (lab, text, str(SOLUTIONS), LIMITS) for key, (lab, text) in sources.items()}
        for outcome in executor.run(judged_with_calls, jobs):
            assert outcome.error is None, f"{outcome.key}: {outcome.error}"
            graded[outcome.key] = outcome.value
    wrong = []
    for key, (tasks, made) in graded.items():
        mutant = mutants[key]
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
    slips = {
        lab: sum(m.lab == lab for m in TRACE_SLIPS) for lab in ("lab20", "spheremap", "cubemap")
    }
    assert min(slips.values()) >= 12, slips
