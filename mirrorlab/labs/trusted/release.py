"""Giving labs out: ``mirrorlab lab start``, ``lab release`` and ``lab solution``.

- :func:`run_start` writes a lab's handout and starter, with the lab's own numbers, from
  the installed package into a folder of the student's.
- :func:`run_release` writes one folder per student of a class list: a handout and a
  starter carrying that student's variant (derived from the course key and the name),
  ``variant.json`` (which ``lab check`` reads beside the starter) and ``reference/``, the
  evidence the teacher's solution gives for that variant, made here by the trusted
  checker, so that the student's ``lab check`` at home judges against it.
- :func:`run_solution` prints one variant's reference solution, from the teacher's copy of
  the solutions (they are not in the package).
"""

from __future__ import annotations

import json
import os
import secrets
import sys
from pathlib import Path

from mirrorlab.files import Outputs
from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import (
    KEY_BYTES,
    Variant,
    VariantError,
    default_variant,
    derive_variant,
    read_key,
    student_key,
)


def _given(spec: LabSpec, variant: Variant) -> dict[str, bytes]:
    from mirrorlab.labs.content import handout, starter

    return {
        "README.md": handout(spec, variant).encode(),
        "starter.py": starter(spec, variant).encode(),
    }


def run_start(lab: str, folder: Path) -> int:
    """``mirrorlab lab start LAB DIR``: the handout (README.md) and starter.py in DIR, which
    may be new or empty of them."""
    spec = find_lab(lab)
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"DIR: {str(folder)!r} is a file, expected a folder")
    files = _given(spec, default_variant(spec.name))
    for name in files:
        if (folder / name).exists():
            raise ValueError(
                f"DIR: {str(folder)!r} already holds {name}; give a new or empty "
                f"folder (nothing was written)"
            )
    with Outputs() as outputs:
        for name, data in files.items():
            outputs.add(folder / name, data)
    print(
        f"wrote {folder / 'README.md'} (the handout) and {folder / 'starter.py'}; check "
        f"it with: mirrorlab lab check {spec.name} {folder / 'starter.py'}"
    )
    return 0


def course_key(path: Path) -> bytes:
    """The key in ``path``, made (random, mode 0600) when the file does not exist."""
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        key = secrets.token_hex(32).encode()
        descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(descriptor, "wb") as stream:
            stream.write(key + b"\n")
        print(
            f"made a new course key in {path}: keep it (grading needs it) and keep it "
            f"from the students",
            file=sys.stderr,
        )
    return read_key(path)


def _reference_job(lab: str, variant: dict, solution: str, limits: Limits) -> dict:
    """The trimmed reference evidence of one variant, as files (what a worker returns)."""
    import tempfile

    from mirrorlab.labs.trusted.grading import _reference_from_text, _variant

    spec = find_lab(lab)
    evidence = _reference_from_text(spec, _variant(variant), solution, limits)
    with tempfile.TemporaryDirectory(prefix="mirrorlab-release-") as folder:
        evidence.save(Path(folder))
        return {
            name: (Path(folder) / name).read_bytes() for name in ("evidence.json", "arrays.npz")
        }


def run_release(
    lab: str,
    out: Path,
    students_file: Path,
    key_file: Path,
    solutions: str | Path | None,
    jobs: int,
    limits: Limits,
) -> int:
    """``mirrorlab lab release LAB OUT --students FILE --key KEYFILE``: one folder per
    student under OUT (all written, or none)."""
    from mirrorlab.jobs import open_executor
    from mirrorlab.labs.trusted.checker import solution_source, solutions_dir
    from mirrorlab.labs.trusted.grading import safe_name
    from mirrorlab.labs.trusted.roster import read_roster

    spec = find_lab(lab)
    students = [student.name for student in read_roster(students_file)]
    folder = solutions_dir(solutions)
    if folder is None:
        raise ValueError(
            "--solutions: releasing needs the teacher's solutions, to make each "
            "student's reference for their lab check at home: give --solutions "
            "DIR (labs/solutions of the repository) or set MIRRORLAB_SOLUTIONS"
        )
    solution = solution_source(spec, folder)
    if out.exists() and not out.is_dir():
        raise ValueError(f"OUT: {str(out)!r} is a file, expected a folder")
    taken = [safe_name(s) for s in students if (out / safe_name(s)).exists()]
    if taken:
        raise ValueError(
            f"OUT: {str(out / taken[0])!r} exists already; release into a new "
            f"folder (nothing was written)"
        )
    key = course_key(key_file)
    variants = {s: derive_variant(spec.name, key, s) for s in students}
    work = {s: (spec.name, v.plain(), solution, limits) for s, v in variants.items()}
    references: dict[str, dict] = {}
    with open_executor(jobs) as executor:
        for outcome in executor.run(_reference_job, work):
            if outcome.error is not None:
                raise VariantError(
                    f"the reference of {outcome.key!r}'s variant could not be made: {outcome.error}"
                )
            references[outcome.key] = outcome.value
    with Outputs() as outputs:
        for student, variant in variants.items():
            base = out / safe_name(student)
            for name, data in _given(spec, variant).items():
                outputs.add(base / name, data)
            outputs.add(base / "variant.json", json.dumps(variant.plain(), indent=2).encode())
            for name, data in references[student].items():
                outputs.add(base / "reference" / name, data)
    print(
        f"released {spec.name} to {len(students)} students in {out}: each folder holds the "
        f"handout (README.md), starter.py, variant.json and reference/ of its variant"
    )
    return 0


def run_solution(lab: str, student: str, key_file: Path, solutions: str | Path | None) -> int:
    """``mirrorlab lab solution LAB --student NAME --key KEYFILE``: that student's variant
    of the reference solution, printed (teachers only)."""
    from mirrorlab.labs.content import solution_for
    from mirrorlab.labs.trusted.checker import solution_source, solutions_dir

    spec = find_lab(lab)
    if not student_key(student):
        raise ValueError(f"--student: {student!r} has no letters or digits")
    folder = solutions_dir(solutions)
    if folder is None:
        raise ValueError(
            "--solutions: the solutions are not in the mirrorlab package; give "
            "--solutions DIR (labs/solutions of the repository) or set "
            "MIRRORLAB_SOLUTIONS"
        )
    key = read_key(key_file)
    variant = derive_variant(spec.name, key, student)
    sys.stdout.write(solution_for(solution_source(spec, folder), variant))
    return 0


__all__ = ["KEY_BYTES", "run_release", "run_solution", "run_start"]
