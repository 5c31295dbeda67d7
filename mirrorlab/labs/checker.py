"""``mirrorlab lab check`` and ``mirrorlab lab run``: one student's file, judged by what its
GL state and pictures show against the reference solution's, each task with a hint.

The student's file runs in the sandbox (:mod:`mirrorlab.labs.sandbox`) through the
harness; this process only reads what the harness wrote. The reference solution's run is
kept in a cache folder (``$MIRRORLAB_CACHE`` or ``~/.cache/mirrorlab``), keyed by the
files that make it.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.judging import Evidence, TaskResult, picture
from mirrorlab.labs.sandbox import Limits, new_box, read_outputs, run_harness
from mirrorlab.paths import PACKAGE_DIR

CHECK_SIZE = (256, 256)


def judges():
    from mirrorlab.labs import cubemap, lab20, spheremap

    return {"lab20": lab20, "spheremap": spheremap, "cubemap": cubemap}


@dataclass
class CheckResult:
    """One submission's check: its tasks' results, how its run ended, its picture (student
    | reference | difference, ``(h, w, 3)`` uint8) and the seconds it took."""

    student: str
    results: list[TaskResult]
    status: str
    detail: str
    seconds: float
    picture: np.ndarray = field(repr=False)

    @property
    def passed(self) -> bool:
        return bool(self.results) and all(r.passed for r in self.results)

    @property
    def score(self) -> int:
        return sum(r.passed for r in self.results)


class CheckError(RuntimeError):
    """The reference solution itself failed: the lab or the machine is broken."""


def _cache_key(spec: LabSpec, size: tuple[int, int]) -> str:
    digest = hashlib.sha256(f"{spec.name} {size}".encode())
    files = [spec.solution, *sorted((PACKAGE_DIR / "labs").glob("*.py")),
             *sorted((PACKAGE_DIR / "shaders").glob("kit_*"))]
    for path in files:
        digest.update(path.read_bytes())
    return digest.hexdigest()[:24]


def cache_dir() -> Path:
    return Path(os.environ.get("MIRRORLAB_CACHE", Path.home() / ".cache" / "mirrorlab"))


DEFAULT_LIMITS = Limits()


def reference_evidence(spec: LabSpec, limits: Limits = DEFAULT_LIMITS,
                       size: tuple[int, int] = CHECK_SIZE) -> Evidence:
    """What the reference solution's run shows (cached); CheckError if it fails."""
    folder = cache_dir() / "lab-references" / f"{spec.name}-{_cache_key(spec, size)}"
    try:
        run, arrays = read_outputs(folder)
        return Evidence(run, arrays)
    except (ValueError, OSError):
        pass
    box = new_box()
    try:
        result = run_harness(spec.name, spec.solution, box, limits, size)
        if result.status != "ok":
            raise CheckError(f"the reference solution of {spec.name} did not run: "
                             f"{result.detail}")
        run, arrays = read_outputs(result.out_dir)
        if run.get("errors"):
            raise CheckError(f"the reference solution of {spec.name} raised: "
                             f"{run['errors'][0]['message']}")
        folder.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(str(folder) + f".{os.getpid()}.tmp")
        shutil.rmtree(staging, ignore_errors=True)
        shutil.copytree(result.out_dir, staging)
        try:
            os.replace(staging, folder)
        except OSError:  # another process cached it first
            shutil.rmtree(staging, ignore_errors=True)
        return Evidence(run, arrays)
    finally:
        shutil.rmtree(box, ignore_errors=True)


def check_submission(spec: LabSpec, file: Path, reference: Evidence, student: str = "",
                     limits: Limits = DEFAULT_LIMITS, size: tuple[int, int] = CHECK_SIZE,
                     box_root: Path | None = None) -> CheckResult:
    """Run ``file`` in the sandbox and judge it against ``reference``."""
    module = judges()[spec.name]
    started = time.perf_counter()
    box = new_box(box_root)
    try:
        result = run_harness(spec.name, Path(file), box, limits, size)
        if result.status == "ok":
            try:
                run, arrays = read_outputs(result.out_dir)
            except ValueError as exc:
                result.status, result.detail = "crashed", f"its results are unreadable ({exc})"
    finally:
        shutil.rmtree(box, ignore_errors=True)
    name = student or Path(file).stem
    if result.status != "ok":
        results = [TaskResult(task, False, result.detail)
                   for task in spec.tasks]
        evidence = Evidence({}, {})
    else:
        evidence = Evidence(run, arrays)
        try:
            results = module.judge(spec, evidence, reference)
        except Exception as exc:
            results = [TaskResult(task, False, f"its results could not be judged "
                                  f"({type(exc).__name__}: {exc})") for task in spec.tasks]
    return CheckResult(name, results, result.status, result.detail,
                       time.perf_counter() - started, module.check_picture(evidence, reference))


def report_lines(spec: LabSpec, check: CheckResult) -> list[str]:
    """The check as a student reads it, one line per task (and its hint)."""
    lines = [f"{spec.title}: {check.student}"]
    for result in check.results:
        mark = "pass" if result.passed else "FAIL"
        lines.append(f"  [{mark}] task {result.task.number} ({result.task.function}): "
                     f"{result.task.title}")
        if result.hint:
            lines.append(f"         {'note' if result.passed else 'hint'}: {result.hint}")
    lines.append(f"{check.score}/{len(check.results)} tasks passed")
    return lines


def run_check(lab: str, file: str | None, out: Path | None, limits: Limits) -> int:
    """``mirrorlab lab check``: print the verdicts, write the picture; 0 only when every
    task passed."""
    from mirrorlab.files import write_png_atomic

    spec = find_lab(lab)
    path = Path(file) if file else spec.starter
    if not path.is_file():
        raise FileNotFoundError(f"FILE: {str(path)!r} is not a file")
    out = out or Path("out") / f"{spec.name}_check.png"
    reference = reference_evidence(spec, limits)
    check = check_submission(spec, path, reference, path.name, limits)
    print("\n".join(report_lines(spec, check)))
    write_png_atomic(out, check.picture)
    print(f"picture (student | reference | difference): {out}")
    return 0 if check.passed else 1


def run_window(lab: str, file: str | None, size: tuple[int, int], max_frames: int,
               screenshot: Path | None) -> int:
    """``mirrorlab lab run``: the student's file in a window, in a process of its own (so
    that this one never runs student code), with the same limits on memory and processes;
    no time limit unless ``max_frames`` is given."""
    import subprocess

    spec = find_lab(lab)
    path = Path(file) if file else spec.starter
    if not path.is_file():
        raise FileNotFoundError(f"FILE: {str(path)!r} is not a file")
    code = ("import sys; from pathlib import Path; from mirrorlab.labs.harness import "
            "run_window; sys.exit(run_window(sys.argv[1], Path(sys.argv[2]), "
            "(int(sys.argv[3]), int(sys.argv[4])), int(sys.argv[5]), "
            "Path(sys.argv[6]) if sys.argv[6] else None))")
    argv = [sys.executable, "-c", code, spec.name, str(path.resolve()), str(size[0]),
            str(size[1]), str(max_frames), str(screenshot.resolve()) if screenshot else ""]
    env = {**os.environ, "PYOPENGL_PLATFORM": "glx"}
    return subprocess.run(argv, env=env).returncode


__all__ = ["CheckResult", "check_submission", "picture", "reference_evidence", "run_check"]
