"""Functions the executor tests send to worker processes (importable there)."""

from __future__ import annotations

import os
from pathlib import Path


def square(value: int) -> int:
    return value * value


def fail(value: int) -> int:
    raise ValueError(f"no good: {value}")


def die_once(marker: str, value: int) -> int:
    """Kill the worker process the first time (``marker`` does not exist yet); return
    ``value`` the next time."""
    path = Path(marker)
    if not path.exists():
        path.write_text(str(os.getpid()))
        os._exit(3)
    return value


def count_calls(folder: str, key: str) -> str:
    """Leave one file per call in ``folder``; returns ``key``."""
    Path(folder, f"{key}-{os.getpid()}-{len(list(Path(folder).iterdir()))}").touch()
    return key


def process_id(_: int) -> int:
    return os.getpid()


def judged_with_calls(
    lab: str, source: str, solutions: str, limits: object
) -> tuple[list[tuple[str, bool, str]], list[str]]:
    """``source`` checked as ``lab`` (its own numbers) by this worker's kept checker process,
    against the reference made from ``solutions`` (cached): each task as (id, passed,
    hint), and the text of every call the file executed (as the call trace names it), for
    the hints' property test."""
    from mirrorlab.labs import find_lab
    from mirrorlab.labs.trusted.checker import CHECK_SIZE, reference_evidence
    from mirrorlab.labs.trusted.gl_process import run_job
    from mirrorlab.labs.trusted.judging import Context
    from mirrorlab.labs.trusted.trace_hints import Roles, Trace
    from mirrorlab.labs.trusted.variants import default_variant

    spec = find_lab(lab)
    variant = default_variant(lab)
    reference = reference_evidence(spec, variant, Path(solutions), limits)  # type: ignore[arg-type]
    evidence = run_job(spec, source.encode(), "submission.py", variant, limits, CHECK_SIZE, True)  # type: ignore[arg-type]
    judge = spec.module("judge")
    results = judge.judge(spec, evidence, reference, Context(variant))
    declared = judge.JUDGE
    trace = Trace(evidence, Roles(evidence, declared.roles, declared.programs, declared.uniforms))
    made = [c.text for c in trace.calls if c.kind != "function" and not c.error]
    return [(r.task.id, r.passed, r.hint) for r in results], made
