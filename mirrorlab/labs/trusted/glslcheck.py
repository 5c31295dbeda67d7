"""Student GLSL compiled first, and probed, in a short-lived process of its own, with
bounded time and memory, before the trusted checker compiles it.

A driver's GLSL compiler runs inside the process that asks it: a preprocessor bomb (a few
dozen macros, each twice the one before) takes gigabytes and crashes the process, and a
loop that never ends holds it. So :func:`precompile` hands the text to ``python -m
mirrorlab.labs.trusted.glslcheck`` with a context of its own, which compiles and links it
exactly as the lab will (:func:`~.session.compile_program`), then runs the value probe
on it there (:func:`.probe.evaluate`: the inputs drawn here, from a secret seed, for the
lab's GLSL functions) and answers in JSON lines. That context holds nothing of any
student's calls: the probe sets up all it reads. When the process dies, is killed at its
memory limit or does not answer in time, the file gets the student's error ("could not
be compiled within the limits", or, once it compiled, its functions "did not finish on
the checker's inputs") and the checker's own process never compiled the text; when it
answers with a compile error, that is the error. What the process answers for a text is
kept for the process's life (a file draws with the same text every frame; a re-check of
an unchanged text reuses its inputs), up to :data:`KEPT` texts.
"""

from __future__ import annotations

import base64
import hashlib
import json
import subprocess
import sys
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

import numpy as np

SECONDS = 30.0
"""Wall-clock seconds the compiling process may take (it starts Python and a context)."""
CPU_SECONDS = 15
MEMORY_MB = 1024
"""Its address-space limit where the system has one (``resource``): a context takes a few
hundred MB of it, the honest labs' GLSL little more."""
KEPT = 64


@dataclass
class Answer:
    """What the compiling process said of one text: its error (line, message, whether it
    was refused rather than not compiled) or None,
    and the value probe's seed, inputs and values (by function)."""

    error: tuple[int, str, bool] | None
    seed: int = 0
    drawn: dict[str, Any] = field(default_factory=dict)
    values: dict[str, np.ndarray] = field(default_factory=dict)


_answers: OrderedDict[str, Answer] = OrderedDict()


def precompile(vertex: str, fragment: str, student: str, variable: str, lab: str = "") -> Answer:
    """Compile ``student`` (the GLSL of ``variable``) with the kit's ``vertex`` and
    ``fragment`` files in a process of its own, and probe the GLSL functions ``lab``
    declares there; StudentShaderError when it does not compile, link or finish, or not
    within the limits. RuntimeError when the process failed for a reason of its own."""
    from mirrorlab.labs.trusted import probe
    from mirrorlab.labs.trusted.session import StudentShaderError

    key = hashlib.sha256(json.dumps([vertex, fragment, student, lab]).encode()).hexdigest()
    if key not in _answers:
        functions = _probed_functions(lab, fragment)
        seed = probe.seed()
        drawn = probe.draw_all(functions, seed)
        _answers[key] = _compile_alone(vertex, fragment, student, variable, seed, drawn)
        while len(_answers) > KEPT:
            _answers.popitem(last=False)
    _answers.move_to_end(key)
    answer = _answers[key]
    if answer.error is not None:
        raise StudentShaderError(variable, *answer.error)
    return answer


def _probed_functions(lab: str, fragment: str) -> tuple[Any, ...]:
    """The GLSL functions of ``lab`` whose prototypes the kit's ``fragment`` declares."""
    if not lab:
        return ()
    from mirrorlab.gl.resources import expand_includes
    from mirrorlab.labs.trusted import probe, session

    _, prototypes = session.student_interface(expand_includes(fragment))
    offered = {name for _, name, _ in prototypes}
    return tuple(f for f in probe.lab_functions(lab) if f.name in offered)


def _encode(array: np.ndarray) -> dict[str, Any]:
    array = np.ascontiguousarray(array, dtype=np.float32)
    return {"shape": list(array.shape), "data": base64.b64encode(array.tobytes()).decode()}


def _decode(value: Any) -> np.ndarray | None:
    try:
        shape = tuple(int(s) for s in value["shape"])
        array = np.frombuffer(base64.b64decode(value["data"]), dtype=np.float32)
        return array.reshape(shape).copy()
    except (KeyError, TypeError, ValueError):
        return None


def _compile_alone(
    vertex: str, fragment: str, student: str, variable: str, seed: int, drawn: dict[str, Any]
) -> Answer:
    """The answer of a process of its own for the texts, its probe given ``drawn``."""
    job = json.dumps(
        {
            "vertex": vertex,
            "fragment": fragment,
            "student": student,
            "variable": variable,
            "probe": {
                name: [_encode(inputs.values[p]) for p in inputs.values]
                for name, inputs in drawn.items()
            },
        }
    )
    from mirrorlab.labs.trusted.gl_process import child_options, gl_process_environment

    # the checker's own GL backend; compiling needs no rasteriser threads
    environment = {**gl_process_environment(), "LP_NUM_THREADS": "1"}
    limits = f"({SECONDS:g} s, {MEMORY_MB} MB)"
    not_compiled = Answer(
        (0, f"your shader could not be compiled within the limits {limits}", False)
    )
    try:
        done = subprocess.run(
            [sys.executable, "-m", "mirrorlab.labs.trusted.glslcheck"],
            input=job,
            capture_output=True,
            text=True,
            timeout=SECONDS,
            env=environment,
            **child_options(MEMORY_MB, CPU_SECONDS, cores=False),
        )
    except subprocess.TimeoutExpired as exc:
        stdout = exc.stdout.decode(errors="replace") if isinstance(exc.stdout, bytes) else ""
        return _unfinished(stdout or "", not_compiled, limits)
    answers = _answers_in(done.stdout)
    final = answers[-1] if answers else None
    if final is None or "ok" not in final:
        return _unfinished(done.stdout, not_compiled, limits)
    if final.get("internal"):
        raise RuntimeError(f"the checker's GLSL probe failed: {str(final['internal'])[:300]}")
    if not final.get("ok"):
        line = final.get("line")
        message = str(final.get("message", ""))[:300]
        return Answer(((line if type(line) is int else 0), message, final.get("refused") is True))
    values = {}
    for name in drawn:
        array = _decode((final.get("probe") or {}).get(name))
        if array is None or array.shape != (drawn[name].count, 4):
            raise RuntimeError(f"the checker's GLSL probe gave no values for {name}")
        values[name] = array
    return Answer(None, seed, drawn, values)


def _unfinished(stdout: str, not_compiled: Answer, limits: str) -> Answer:
    """A process that never answered: the GLSL did not compile within the limits, or,
    once it had compiled, its functions did not finish on the probe's inputs."""
    if any(a.get("compiled") for a in _answers_in(stdout)):
        return Answer(
            (
                0,
                f"your functions did not finish on the checker's inputs within the limits "
                f"{limits}: a loop that never ends?",
                False,
            )
        )
    return not_compiled


def _answers_in(stdout: str) -> list[dict[str, Any]]:
    found = []
    for line in stdout.splitlines():
        if line.startswith("{"):
            try:
                value = json.loads(line)
            except ValueError:
                continue
            if isinstance(value, dict):
                found.append(value)
    return found


def main() -> int:
    """The compiling process: a job on stdin, JSON lines on stdout ("compiled", then the
    answer)."""
    job = json.loads(sys.stdin.read())
    from mirrorlab.gl.context import offscreen_context

    context = offscreen_context()
    try:
        from mirrorlab.labs.trusted.session import StudentShaderError, compile_program

        try:
            program = compile_program(
                job["vertex"], job["fragment"], job["student"], job["variable"]
            )
            from mirrorlab.gl.opengl import GL

            GL.glDeleteProgram(program)
            print(json.dumps({"compiled": True}), flush=True)
            answer: dict[str, Any] = {"ok": True, "probe": _probe(job, context.resources)}
        except StudentShaderError as exc:
            answer = {"ok": False, "line": exc.line, "message": exc.detail, "refused": exc.refused}
        except Exception as exc:  # the checker's own failure, never the student's
            answer = {"ok": False, "internal": f"{type(exc).__name__}: {exc}"}
    finally:
        context.release()
    print(json.dumps(answer), flush=True)
    return 0


def _probe(job: dict[str, Any], registry: Any) -> dict[str, Any]:
    from mirrorlab.labs.trusted.probe import evaluate

    calls = {}
    for name, arguments in (job.get("probe") or {}).items():
        decoded = [_decode(a) for a in arguments]
        if any(a is None for a in decoded):
            raise ValueError(f"the probe's inputs for {name} are malformed")
        calls[name] = [a for a in decoded if a is not None]
    if not calls:
        return {}
    found = evaluate(job["fragment"], job["student"], job["variable"], calls, registry)
    return {name: _encode(values) for name, values in found.items()}


if __name__ == "__main__":
    sys.exit(main())
