"""``mirrorlab lab check``: one student's file judged against the reference evidence of
the student's own variant, each task with a hint.

The file runs in the sandbox with no GL of its own; the trusted checker process
(:mod:`.gl_process`) executes its calls and makes every observation. The reference evidence
is made the same way from the teacher's solution where the solutions are given
(``--solutions DIR`` or ``$MIRRORLAB_SOLUTIONS``), cached in ``$MIRRORLAB_CACHE`` or
``~/.cache/mirrorlab`` by the files that make it; without them, the evidence shipped in
the package (the lab's own numbers) or beside a released starter (its student's) is used.
The sandbox can reach none of these.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab.labs import LabSpec, find_lab, lab_names
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.failures import Runner, run_attributed
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.judging import Context, TaskResult
from mirrorlab.labs.trusted.sandbox import Limits, sandboxed, unsandboxed_note
from mirrorlab.labs.trusted.variants import (
    Variant,
    VariantError,
    default_variant,
    variant_from_file,
    variant_from_header,
)

CHECK_SIZE = (256, 256)
DEFAULT_LIMITS = Limits()
VARIANT_FILE = "variant.json"
LAB_FILE = "starter.py"
"""The file a lab's folder holds for the student to edit (``lab start``, ``lab release``)."""
REFERENCE_FOLDER = "reference"


@dataclass
class CheckResult:
    """One submission's check: its tasks' results, how its run ended, its picture (student
    | reference | difference, ``(h, w, 3)`` uint8), the seconds it took and its variant."""

    student: str
    results: list[TaskResult]
    status: str
    detail: str
    seconds: float
    picture: np.ndarray = field(repr=False)
    variant: str = "default"

    @property
    def passed(self) -> bool:
        return bool(self.results) and all(r.passed for r in self.results)

    @property
    def score(self) -> int:
        return sum(r.passed for r in self.results)


class CheckError(RuntimeError):
    """No usable reference: the solutions are missing or failed, or the lab is broken."""


def solutions_dir(given: str | Path | None) -> Path | None:
    """The teacher's solutions folder: ``given``, else ``$MIRRORLAB_SOLUTIONS``, else None;
    ValueError when the one named is not a folder."""
    value = given if given is not None else os.environ.get("MIRRORLAB_SOLUTIONS") or None
    if value is None:
        return None
    folder = Path(value)
    if not folder.is_dir():
        option = "--solutions" if given is not None else "MIRRORLAB_SOLUTIONS"
        raise ValueError(
            f"{option}: {str(folder)!r} is not a folder (the repository's labs/solutions/)"
        )
    return folder


def solution_source(spec: LabSpec, folder: Path) -> str:
    """The teacher's solution of ``spec``: ``<folder>.py`` in the solutions ``folder``, else
    the file the lab's registry entry names (:attr:`~mirrorlab.labs.LabSpec.solution`);
    ValueError when neither is there."""
    for path in (folder / f"{spec.folder}.py", spec.solution):
        if path.is_file():
            return path.read_text()
    raise ValueError(f"--solutions: {str(folder)!r} holds no {spec.folder}.py")


def cache_dir() -> Path:
    return Path(os.environ.get("MIRRORLAB_CACHE", Path.home() / ".cache" / "mirrorlab"))


@lru_cache(maxsize=8)
def code_digest(home: Path) -> str:
    """A digest of everything that makes a reference run of the lab whose package is in
    ``home``: the labs' shared code, the lab's own, kit shaders, meshes and pictures."""
    import mirrorlab.labs as labs_package
    from mirrorlab.data import data_path
    from mirrorlab.shaders import shader_source

    root = Path(labs_package.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(
        [
            *root.glob("*.py"),
            *root.glob("student/*.py"),
            *root.glob("trusted/*.py"),
            *home.glob("*.py"),
        ]
    ):
        digest.update(path.read_bytes())
    for name in (
        "kit_scene.vert",
        "kit_scene.frag",
        "kit_texture.vert",
        "kit_texture.frag",
        "kit_sphere.vert",
        "kit_sphere.frag",
        "kit_cube.vert",
        "kit_cube.frag",
    ):
        digest.update(shader_source(name).encode())
    for folder in ("models", "textures"):
        for path in sorted(data_path(folder).glob("*")):
            if path.is_file():
                digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def trim_reference(evidence: Evidence) -> Evidence:
    """What the judges read of a reference run: its pictures, the set-up's and the last
    frame's events (the call trace the hints align a student's with among them)."""
    keep = {"frame", "capture", "cube_faces", "values_mask"}
    events = list(evidence.last_frame)
    for event in events:
        if event.get("picture"):
            keep.add(event["picture"])
    return Evidence(
        evidence.lab,
        evidence.status,
        evidence.detail,
        setup=list(evidence.setup),
        frames=[{"events": events}],
        # the value probe's seed and inputs judge the student's GLSL only
        state={k: v for k, v in evidence.state.items() if not k.startswith("probe_")},
        textures=dict(evidence.textures),
        arrays={k: v for k, v in evidence.arrays.items() if k in keep},
        variant=evidence.variant,
    )


def make_reference(
    spec: LabSpec,
    variant: Variant,
    solution: str,
    limits: Limits,
    size: tuple[int, int],
    keep: bool = False,
) -> Evidence:
    """The evidence of ``solution`` (the teacher's, with ``variant``'s numbers) run like any
    submission; CheckError when it does not run cleanly."""
    from mirrorlab.labs.content import solution_for

    text = solution_for(solution, variant)
    evidence = run_attributed(spec, text.encode(), "solution.py", variant, limits, size, keep)
    if evidence.status != "ok":
        raise CheckError(f"the reference solution of {spec.name} did not run: {evidence.detail}")
    problems = evidence.errors or evidence.call_errors
    if problems:
        problem = problems[0]
        raise CheckError(
            f"the reference solution of {spec.name} raised at line "
            f"{problem.get('line', 0)}: {problem.get('message', '')}"
        )
    return trim_reference(evidence)


def reference_evidence(
    spec: LabSpec,
    variant: Variant,
    solutions: Path | None,
    limits: Limits = DEFAULT_LIMITS,
    size: tuple[int, int] = CHECK_SIZE,
    released: Path | None = None,
    keep: bool = False,
) -> Evidence:
    """The reference evidence for ``variant``: made from the teacher's ``solutions`` when
    given (cached), else shipped in the package (the default variant) or in a released
    folder (``released``); CheckError when there is none. A lab that ships no reference
    evidence (one registered from outside the package) is referenced by its own solution
    (:attr:`~mirrorlab.labs.LabSpec.solution`)."""
    from mirrorlab.labs.content import reference_folder

    shipped = reference_folder(spec)
    if solutions is None and not (shipped / "evidence.json").is_file() and spec.solution.is_file():
        solutions = spec.solution.parent
    if solutions is not None:
        solution = solution_source(spec, solutions)
        digest = hashlib.sha256(
            repr(
                (spec.name, size, sorted(variant.values.items()), solution, code_digest(spec.home))
            ).encode()
        ).hexdigest()[:24]
        folder = cache_dir() / "lab-references" / f"{spec.name}-{variant.id}-{digest}"
        try:
            return Evidence.load(folder)
        except ValueError:
            pass
        evidence = make_reference(spec, variant, solution, limits, size, keep)
        folder.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(f"{folder}.{os.getpid()}.tmp")
        shutil.rmtree(staging, ignore_errors=True)
        evidence.save(staging)
        try:
            os.replace(staging, folder)
        except OSError:  # another process cached it first
            shutil.rmtree(staging, ignore_errors=True)
        return evidence
    if released is not None and (released / "evidence.json").is_file():
        try:
            return Evidence.load(released)
        except ValueError as exc:
            raise CheckError(f"{released}: {exc}") from None
    if variant.is_default:
        if size != CHECK_SIZE:
            raise CheckError(
                f"the shipped reference is {CHECK_SIZE[0]}x{CHECK_SIZE[1]}; give "
                f"--solutions to check at another size"
            )
        return Evidence.load(shipped)
    raise CheckError(
        f"no reference for variant {variant.id} of {spec.name}: its released "
        f"folder's {REFERENCE_FOLDER}/ is missing; give --solutions DIR (the "
        f"teacher's labs/solutions)"
    )


def check_submission(
    spec: LabSpec,
    source: bytes,
    reference: Evidence,
    context: Context,
    student: str = "",
    file_name: str = "submission.py",
    limits: Limits = DEFAULT_LIMITS,
    size: tuple[int, int] = CHECK_SIZE,
    keep: bool = False,
    run: Runner = run_job,
) -> CheckResult:
    """Run ``source`` in the sandbox through the trusted checker (with ``keep``, a kept
    checker process: this process's, or the one ``run`` keeps) and judge it against
    ``reference`` for ``context.variant``; the checker's own failures are told from the
    file's (:func:`~.failures.run_attributed`, with ``run`` for
    :func:`~.gl_process.run_job`). A check in a process of its own imports the judge while
    the file runs (an interrupt ends that process too: it is in the terminal's process
    group, where a kept process is left to its owner)."""
    started = time.perf_counter()
    if keep:
        module = spec.module("judge")
        evidence = run_attributed(spec, source, file_name, context.variant, limits, size, keep, run)
    else:
        with ThreadPoolExecutor(1) as pool:
            running = pool.submit(
                run_attributed, spec, source, file_name, context.variant, limits, size, False, run
            )
            module = spec.module("judge")
            evidence = running.result()
    try:
        results = module.judge(spec, evidence, reference, context)
    except Exception as exc:  # a judge's own fault: every task fails, saying so
        results = [
            TaskResult(task, False, f"its run could not be judged ({type(exc).__name__}: {exc})")
            for task in spec.tasks
        ]
    return CheckResult(
        student or Path(file_name).stem,
        results,
        evidence.status,
        evidence.detail,
        time.perf_counter() - started,
        module.check_picture(evidence, reference),
        context.variant.id,
    )


def report_lines(spec: LabSpec, check: CheckResult) -> list[str]:
    """The check as a student reads it, one line per task (and its hint)."""
    variant = "" if check.variant == "default" else f" (variant {check.variant})"
    lines = [f"{spec.title}: {check.student}{variant}"]
    for result in check.results:
        mark = "pass" if result.passed else "FAIL"
        lines.append(
            f"  [{mark}] {result.task.name}: {result.task.title}, in {result.task.function}()"
        )
        if result.hint:
            lines.append(f"         {'note' if result.passed else 'hint'}: {result.hint}")
    lines.append(f"{check.score}/{len(check.results)} tasks passed")
    return lines


def file_variant(spec: LabSpec, path: Path) -> Variant:
    """The variant of a student's file: its released folder's ``variant.json`` beside it,
    else the variant its header names (:data:`~.variants.HEADER`: the first line of every
    starter), else the lab's own numbers. (``lab grade`` never asks: a variant follows
    from the course key and the student's name there.)"""
    found = path.parent / VARIANT_FILE
    try:
        if found.is_file():
            return variant_from_file(found, spec.name)
        named = variant_from_header(_text(path), spec.name, str(path))
    except VariantError as exc:
        raise ValueError(str(exc)) from None
    return named if named is not None else default_variant(spec.name)


def default_note(spec: LabSpec, path: Path) -> str:
    """The line ``lab check`` says under the file's name when ``path`` names no variant (no
    ``variant.json`` beside it, no header) and is judged against the lab's own numbers
    ('' otherwise)."""
    if (path.parent / VARIANT_FILE).is_file():
        return ""
    try:
        if variant_from_header(_text(path), spec.name, str(path)) is not None:
            return ""
    except VariantError:
        return ""
    return (
        f"note: {path.name} names no variant (no {VARIANT_FILE} beside it, no variant line "
        f"at its top): judged against the lab's own numbers; a released starter is checked "
        f"in its own folder"
    )


def _text(path: Path) -> str:
    try:
        with open(path, "rb") as stream:
            return stream.read(1 << 16).decode("utf-8", errors="replace")
    except OSError:
        return ""


def folder_file(spec: LabSpec, folder: Path) -> Path:
    """The lab file of ``folder``: the ``starter.py`` that ``lab start`` and ``lab release``
    put there; FileNotFoundError (one line) when it has none or it is another lab's."""
    path = folder / LAB_FILE
    if not path.is_file():
        raise FileNotFoundError(
            f"FILE: {str(folder)!r} holds no {LAB_FILE} (the file lab start puts in a lab's "
            f"folder): give the file to check, mirrorlab lab check {spec.name} FILE, or run "
            f"it in your lab's folder"
        )
    try:
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise FileNotFoundError(f"FILE: cannot read {str(path)!r}: {exc.strerror}") from None
    labs = set(re.findall(r"\bkit\.(\w+)\(", text)) & set(lab_names())
    if labs and spec.name not in labs:
        raise FileNotFoundError(
            f"FILE: {str(path)!r} is a file of the {sorted(labs)[0]} lab "
            f"(kit.{sorted(labs)[0]}()), not of {spec.name}"
        )
    return path


def file_reference(
    spec: LabSpec,
    variant: Variant,
    solutions: Path | None,
    limits: Limits,
    path: Path,
    size: tuple[int, int] = CHECK_SIZE,
) -> Evidence:
    """The reference evidence the student's file ``path`` (of ``variant``) is judged
    against (:func:`reference_evidence`, its released folder beside it); CheckError when
    the ``reference/`` beside it is another variant's."""
    released = path.parent / REFERENCE_FOLDER
    reference = reference_evidence(spec, variant, solutions, limits, size, released=released)
    made_for = reference.variant.get("id") if isinstance(reference.variant, dict) else None
    if made_for not in (None, variant.id):
        raise CheckError(
            f"{path.name} is variant {variant.id}, but the {REFERENCE_FOLDER}/ beside it is "
            f"variant {made_for}'s: check the file in its own released folder"
        )
    return reference


def file_report(spec: LabSpec, path: Path, check: CheckResult) -> list[str]:
    """The check of the file ``path`` as ``lab check`` prints it: :func:`report_lines`,
    with the note of :func:`default_note` right under the file's name (what it was judged
    against)."""
    lines = report_lines(spec, check)
    note = default_note(spec, path)
    if note:
        lines.insert(1, f"  {note}")
    return lines


def run_check(
    lab: str,
    file: str | None,
    out: Path | None,
    limits: Limits,
    solutions: str | Path | None = None,
    watch: bool = False,
) -> int:
    """``mirrorlab lab check``: print the verdicts, write the picture; 0 only when every
    task passed. Without ``file``, the lab file of the current folder (:func:`folder_file`)
    is checked. The report's first line names the file checked. With ``watch``, the file
    is checked again on every save until Ctrl-C (:func:`~.watch.watch_check`)."""
    from mirrorlab.files import write_png_atomic
    from mirrorlab.gl.context import choose

    spec = find_lab(lab)
    folder = solutions_dir(solutions)
    path = Path(file) if file else folder_file(spec, Path.cwd())
    if not path.is_file():
        raise FileNotFoundError(f"FILE: {str(path)!r} is not a file")
    out = out or Path("out") / f"{spec.name}_check.png"
    choose("offscreen", new_process=True)  # no OpenGL: render's one line, before any of it
    if not sandboxed():
        print(f"mirrorlab lab check: {unsandboxed_note()}", file=sys.stderr)
    if watch:
        from mirrorlab.labs.trusted.watch import watch_check

        return watch_check(spec, path, out, limits, folder)
    source = path.read_bytes()
    variant = file_variant(spec, path)
    reference = file_reference(spec, variant, folder, limits, path)
    check = check_submission(
        spec, source, reference, Context(variant), str(path), path.name, limits
    )
    print("\n".join(file_report(spec, path, check)))
    write_png_atomic(out, check.picture)
    print(f"picture (student | reference | difference): {out}")
    return 0 if check.passed else 1
