"""Many files of one lab checked by one warm checker (:mod:`mirrorlab.labs.trusted.warm`),
one after another, as ``lab check --watch`` checks a student's saves: one GL process, and
for each file a new runner in a new box, a new context and a new session, the reference
copied. That shares between two files what a grading worker's kept process shares (the
process), and no more; it saves each file a process's start-up."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.checker import CheckResult, report_lines
from mirrorlab.labs.trusted.warm import WarmChecker
from tests.labs.conftest import LIMITS, SOLUTIONS


def check_files(
    lab: str, paths: Iterable[Path], limits=LIMITS, solutions: Path | None = SOLUTIONS
) -> dict[str, CheckResult]:
    """Each file checked, by its stem (references made from ``solutions``)."""
    spec = find_lab(lab)
    found: dict[str, CheckResult] = {}
    with WarmChecker(spec, limits, solutions) as checker:
        for path in paths:
            check = checker.check(path)
            assert check is not None, path
            found[path.stem] = check
    return found


def check_folder(lab: str, folder: Path, limits=LIMITS) -> dict[str, list[tuple[str, bool, str]]]:
    """Each ``.py`` file of ``folder`` checked, as ``lab grade``'s rows: by stem, (task id,
    passed, hint) per task."""
    checks = check_files(lab, sorted(folder.glob("*.py")), limits)
    return {
        stem: [(r.task.id, r.passed, r.hint) for r in check.results]
        for stem, check in checks.items()
    }


def report(lab: str, check: CheckResult) -> str:
    """The check as ``lab check`` prints it."""
    return "\n".join(report_lines(find_lab(lab), check))
