"""Student GLSL compiled first in a short-lived process of its own, with bounded time and
memory, before the trusted checker compiles it.

A driver's GLSL compiler runs inside the process that asks it: a preprocessor bomb (a few
dozen macros, each twice the one before) takes gigabytes and crashes the process. So
:func:`precompile` hands the text to ``python -m mirrorlab.labs.trusted.glslcheck`` in a
context of its own, which compiles and links it exactly as the lab will
(:func:`~.session.compile_program`) and answers in one JSON line. When that process dies, is
killed at its memory limit or does not answer in time, the file gets the student's error
"could not be compiled within the limits" and the checker's own process never compiled
it; when it answers with a compile error, that is the error, and the checker does not
compile the text either. A text that compiled is remembered for the process's life.

A checker process kept for many runs (:func:`keep_ready`) starts the next compiling
process as soon as one has answered, so that the next text finds Python, OpenGL and a
context loaded (about half a second of a core on llvmpipe): each text still gets a
process of its own, which has compiled nothing before it.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from typing import Any

SECONDS = 30.0
"""Wall-clock seconds the compiling process may take (it starts Python and a context)."""
CPU_SECONDS = 15
MEMORY_MB = 1024
"""Its address-space limit where the system has one (``resource``): a context takes a few
hundred MB of it, the honest labs' GLSL little more."""

_answers: dict[str, tuple[int, str] | None] = {}
"""By digest of the texts: None for a text that compiled, else the error's line and
message (a file draws with the same text every frame)."""
_ready: list[subprocess.Popen] = []
"""The compiling process started ahead (at most one), waiting for its text."""
_keep_ready = [False]


def precompile(vertex: str, fragment: str, student: str, variable: str) -> None:
    """Compile ``student`` (the GLSL of ``variable``) with the kit's ``vertex`` and
    ``fragment`` files in a process of its own; StudentShaderError when it does not compile
    or not within the limits."""
    from mirrorlab.labs.trusted.session import StudentShaderError

    key = hashlib.sha256(json.dumps([vertex, fragment, student]).encode()).hexdigest()
    if key not in _answers:
        _answers[key] = _compile_alone(vertex, fragment, student, variable)
    failed = _answers[key]
    if failed is not None:
        raise StudentShaderError(variable, *failed)


def keep_ready(keep: bool = True) -> None:
    """Whether this process keeps a compiling process started ahead for its next text
    (a kept checker process does; without it, every text starts its own); ``False``
    also ends the one waiting."""
    _keep_ready[0] = keep
    if not keep:
        while _ready:
            process = _ready.pop()
            process.kill()
            process.communicate()


def _start() -> subprocess.Popen:
    """A compiling process, its context made, waiting for its job on stdin."""
    from mirrorlab.labs.trusted.gl_process import child_options, gl_process_environment

    # the checker's own GL backend; compiling needs no rasteriser threads
    environment = {**gl_process_environment(), "LP_NUM_THREADS": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "mirrorlab.labs.trusted.glslcheck"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=environment,
        **child_options(MEMORY_MB, CPU_SECONDS, cores=False, die_with_parent=True),
    )


def _compile_alone(
    vertex: str, fragment: str, student: str, variable: str
) -> tuple[int, str] | None:
    """None when the texts compile and link in a process of their own, within the
    limits; else the error's line (0: none) and message."""
    job = json.dumps(
        {"vertex": vertex, "fragment": fragment, "student": student, "variable": variable}
    )
    limits = f"your shader could not be compiled within the limits ({SECONDS:g} s, {MEMORY_MB} MB)"
    process = _ready.pop() if _ready else _start()
    try:
        stdout, _ = process.communicate(job, timeout=SECONDS)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        return 0, limits
    finally:
        if _keep_ready[0]:
            _ready.append(_start())
    answer = _answer(stdout)
    if answer is None:
        return 0, limits
    if not answer.get("ok"):
        line = answer.get("line")
        return (line if type(line) is int else 0), str(answer.get("message", ""))[:300]
    return None


def _answer(stdout: str) -> dict[str, Any] | None:
    lines = [line for line in stdout.splitlines() if line.startswith("{")]
    try:
        answer = json.loads(lines[-1]) if lines else None
    except ValueError:
        return None
    return answer if isinstance(answer, dict) else None


def main() -> int:
    """The compiling process: its context made, then a job on stdin, one JSON line on
    stdout."""
    from mirrorlab.gl.context import offscreen_context

    context = offscreen_context()
    try:
        from mirrorlab.labs.trusted.session import StudentShaderError, compile_program

        job = json.loads(sys.stdin.read())
        try:
            compile_program(job["vertex"], job["fragment"], job["student"], job["variable"])
            answer: dict[str, Any] = {"ok": True}
        except StudentShaderError as exc:
            answer = {"ok": False, "line": exc.line, "message": exc.detail}
    finally:
        context.release()
    print(json.dumps(answer), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
