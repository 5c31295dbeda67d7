"""Driving one student's file through a lab, in the sandbox, from the trusted side.

:class:`LabRun` starts the student side (:mod:`mirrorlab.labs.student.runner`) in the
sandbox with a pipe to this process, sends it the session (the names and values of
OpenGL, the lab object's numbers), then commands: load the file, run the lab's set-up
functions, then ``display()`` frame after frame. Every call that comes back is executed
here (:mod:`.call_executor`); when the frames are drawn this process makes its own
observations (the frame, the textures, the student's GLSL judged by the values it
writes) and the run becomes :class:`~.evidence.Evidence`. The sandbox produces only the
call stream; nothing it writes to its box is ever read.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.gl.opengl import GL
from mirrorlab.labs import LabSpec, lab_names
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.call_executor import Executor, RunLimits, Stop
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.pipe import (
    PipeBudget,
    PipeClosed,
    PipeError,
    PipeTimeout,
    TrustedChannel,
)
from mirrorlab.labs.trusted.runner import Runner, start_runner
from mirrorlab.labs.trusted.sandbox import (
    Limits,
    Sandboxed,
    SandboxError,
    remove_box,
    sandbox_mode,
)
from mirrorlab.labs.trusted.session import LabBase, LabSetupError

FRAMES = 2
"""Frames drawn by a check: the second shows what a capture left for the next frame."""


@lru_cache(maxsize=4)
def gl_names(lab: str) -> dict[str, Any]:
    """PyOpenGL's GL and GLU names: constants with their values, and functions; which of
    them ``lab`` offers, and the line a student reads for the ones it refuses."""
    from OpenGL import GLU

    names: dict[str, Any] = {}
    for key, module, prefix in (("gl", GL, "GL_"), ("glu", GLU, "GLU_")):
        constants, functions = {}, []
        for name in dir(module):
            value = getattr(module, name, None)
            if name.startswith(prefix) and isinstance(value, int):
                constants[name] = int(value)
            elif name.startswith(prefix.lower()[:-1]) and callable(value):
                functions.append(name)
        names[f"{key}_constants"], names[f"{key}_functions"] = constants, functions
    offered = C.lab_specs(lab)
    names["gl_offered"] = C.offered(offered)
    names["gl_refused"] = {
        name: C.refused_text(lab, name)
        for name in names["gl_functions"]
        if name not in offered and C.refusal(lab, name)
    }
    names["glu_offered"] = C.offered(C.GLU_SPECS)
    names["pixel_types"] = {str(k): code for k, (_, code) in C.PIXEL_TYPES.items()}
    return names


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


class LabRun:
    """One run of the student's ``source`` (named ``file_name``) through ``spec``'s lab in
    ``session``; use as a context manager, then :meth:`check` (or drive it yourself with
    :meth:`load`, :meth:`call` and :meth:`finish`)."""

    def __init__(
        self,
        spec: LabSpec,
        session: LabBase,
        source: bytes,
        file_name: str,
        limits: Limits,
        run_limits: RunLimits | None = None,
        budget: PipeBudget | None = None,
        registry: Any = None,
        owner: int | None = None,
        runner: Runner | None = None,
    ) -> None:
        self.spec, self.session, self.limits = spec, session, limits
        self.owner = owner
        self.runner = runner
        self.registry = registry
        self.executor = Executor(session, run_limits or RunLimits())
        self.budget = budget or PipeBudget()
        text = source.decode("utf-8", errors="replace")
        self.evidence = Evidence(
            spec.name, variant=session.variant.plain(), source=text[: 256 << 10]
        )
        self.evidence.frames = self.executor.tracker.frames
        self.evidence.setup = self.executor.tracker.setup_events
        self.source, self.file_name = source, file_name
        self.box: Path | None = None
        self.sandbox: Sandboxed | None = None
        self.channel: TrustedChannel | None = None
        self.ended = False
        self.declared: dict[str, str] = {}

    # ---------------------------------------------------------------- lifetime
    def __enter__(self) -> LabRun:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def release(self) -> None:
        if self.runner is not None:  # given, never started
            self.runner.release()
            self.runner = None
        if self.sandbox is not None:
            self.sandbox.kill()
            self.sandbox.wait(timeout=10)
            self.sandbox = None
        if self.channel is not None:
            self.channel.close()
            self.channel = None
        if self.box is not None:
            remove_box(self.box)
            self.box = None

    def start(self) -> None:
        """The sandbox (the runner given, else one started now), the pipe, the session
        sent, the runner ready; RunEnded states (status not ok) are kept in the evidence,
        SandboxError when it cannot start."""
        runner = self.runner or start_runner(self.spec, self.limits, self.owner, self.source)
        self.runner = None
        self.box, self.sandbox = runner.box, runner.sandbox
        self.sandbox.started = time.perf_counter()  # its clock starts with the run
        self.channel = TrustedChannel(runner.read_fd, runner.write_fd, self.budget)
        self.deadline = time.monotonic() + self.limits.seconds
        description = {
            "op": "session",
            "lab": self.spec.name,
            "labs": list(lab_names()),
            "lab_side": runner.lab_side,
            "file": runner.file,
            "functions": list(self.spec.functions),
            "declared": list(self.spec.declared),
            "kit": self.session.student_values(),
            **gl_names(self.spec.name),
        }
        # a runner started before its file was known writes it into its box first
        source = [] if runner.has_file else [("u1", [len(self.source)], self.source)]
        try:
            self.channel.send(description, source)
            header, _ = self.channel.receive(self.deadline)
        except (PipeClosed, PipeTimeout, PipeError):
            self._ended_early()
            return
        if header.get("op") != "ready":
            self.end("stopped", "stopped: the program broke the lab's pipe before it started")

    def _ended_early(self) -> None:
        """The runner died before it said ready: the sandbox itself failed."""
        assert self.sandbox is not None
        code, _, stopped = self.sandbox.wait(timeout=10)
        stderr = self.sandbox.stderr_tail()
        last = next((line for line in reversed(stderr.strip().splitlines()) if line.strip()), "")
        if stopped:
            self.end(*self._classify(code, stopped))
            return
        raise SandboxError(
            f"the sandbox could not start the lab's runner "
            f"({sandbox_mode()} mode, exit status {code}): {last[:200]}"
        )

    # ---------------------------------------------------------------- ending
    def end(self, status: str, detail: str) -> None:
        if not self.ended:
            self.ended = True
            self.evidence.status, self.evidence.detail = status, detail
        if self.sandbox is not None:
            self.sandbox.kill()

    def _classify(self, code: int | None, stopped: str) -> tuple[str, str]:
        limits = self.limits
        if stopped == "wall":
            return "timeout", (
                f"stopped after {limits.seconds:g} s of waiting (the wall-clock limit)"
            )
        if stopped == "scratch":
            from mirrorlab.labs.trusted.scratch import scratch_message

            return "scratch", (f"stopped when its scratch space held more than {scratch_message()}")
        if stopped == "processes":
            from mirrorlab.labs.trusted.sandbox import MAX_PROCESSES

            return "processes", (
                f"stopped when it started more than {MAX_PROCESSES} processes (a fork bomb?)"
            )
        cpu = getattr(signal, "SIGXCPU", None)  # POSIX: the CPU-time limit's signal
        if cpu is not None and code in (-cpu, 128 + cpu):
            return "timeout", (
                f"stopped at the CPU-time limit of {limits.cpu_seconds} s (an endless loop?)"
            )
        assert self.sandbox is not None
        stderr = self.sandbox.stderr_tail()
        if "MemoryError" in stderr or "Cannot allocate memory" in stderr:
            return "memory", f"stopped at the memory limit of {limits.memory_mb} MB"
        died = (
            -code
            if code is not None and code < 0
            else (code - 128 if code is not None and code > 128 else 0)
        )
        if died:
            return "crashed", f"the program died ({_signal_name(died)})"
        last = next((line for line in reversed(stderr.strip().splitlines()) if line.strip()), "")
        detail = f"the program ended (exit status {code}) before the lab's run was over"
        return "crashed", detail + (f": {last.strip()[:200]}" if last else "")

    def _closed(self) -> None:
        assert self.sandbox is not None
        code, _, stopped = self.sandbox.wait(timeout=10)
        self.end(*self._classify(code, stopped))

    # ---------------------------------------------------------------- commands
    def command(self, message: dict[str, Any]) -> dict[str, Any] | None:
        """Send ``message`` and execute the calls that come back until the runner says
        ``done``; None when the run ended (the evidence says why)."""
        if self.ended or self.channel is None:
            return None
        channel, functions = self.channel, tuple(self.spec.functions)
        try:
            channel.send(message)
            while True:
                header, arrays = channel.receive(self.deadline)
                op = header["op"]
                if op == "done":
                    return self._done(header)
                if op in ("enter", "leave"):
                    self.executor.step(header, functions)
                elif op in ("gl", "glu", "kit"):
                    reply, payloads = self.executor.call(header, arrays)
                    channel.send(reply, payloads)
                else:
                    raise PipeError("a message of an unknown kind")
        except Stop as exc:
            try:
                channel.send({"stop": str(exc)})
            except PipeClosed:
                pass
            self.end("stopped", str(exc))
        except PipeError as exc:
            self.end("stopped", f"stopped: the program sent {exc}")
        except PipeTimeout:
            assert self.sandbox is not None
            self.sandbox.kill("wall")
            self._closed()
        except PipeClosed:
            self._closed()
        return None

    def _done(self, header: dict[str, Any]) -> dict[str, Any]:
        errors = header.get("errors")
        errors = list(errors) if isinstance(errors, list) else []
        unended = self.executor.end_open_primitive()
        if unended is not None:  # the student's error, as if their function had raised it
            errors.append(unended)  # after the error that left glBegin open, when one did
        for error in errors:
            if not isinstance(error, dict) or len(self.evidence.errors) >= 20:
                continue
            line = error.get("line")
            line = line if type(line) is int and 0 <= line < 1 << 20 else 0
            record = {
                "function": str(error.get("function", ""))[:40],
                "kind": str(error.get("kind", ""))[:20],
                "message": " ".join(str(error.get("message", "")).split())[:300],
                "line": line,
                "code": self.evidence.line_text(line),
            }
            if record["function"] in ("<file>", *self.spec.functions) and not any(
                e["function"] == record["function"] for e in self.evidence.errors
            ):
                self.evidence.errors.append(record)
        declared = header.get("declared")
        for name in self.spec.declared:
            value = declared.get(name) if isinstance(declared, dict) else None
            if isinstance(value, str) and len(value) <= self.executor.limits.glsl_chars:
                self.declared[name] = value
        return {"ok": header.get("ok") is True}

    def load(self) -> bool:
        done = self.command({"op": "load"})
        return bool(done and done["ok"])

    def call(self, function: str) -> bool:
        done = self.command({"op": "call", "function": function})
        return bool(done and done["ok"])

    def finish(self) -> None:
        """Tell the runner to exit and wait for it; a run that had not ended is ok."""
        if self.ended or self.channel is None or self.sandbox is None:
            return
        try:
            self.channel.send({"op": "exit"})
        except PipeClosed:
            pass
        code, _, stopped = self.sandbox.wait(timeout=10)
        if stopped or code not in (0, None):
            self.end(*self._classify(code, stopped))
        self.ended = True

    # ---------------------------------------------------------------- the check
    def check(self, frames: int = FRAMES) -> Evidence:
        """The whole check: load, set up, ``frames`` frames, the observations."""
        if not self.ended and self.load():
            for function in self.spec.setup:
                self.call(function)
            for _ in range(frames):
                self.executor.begin_frame()
                if not self.call(self.spec.frame):
                    break
        if not self.ended:
            self.evidence.arrays["frame"] = self.executor.session_frame()
        self.finish()
        if self.evidence.status == "ok":
            self.observe()
        return self.collect()

    def collect(self) -> Evidence:
        evidence, executor = self.evidence, self.executor
        evidence.frames = executor.tracker.frames
        evidence.setup = executor.tracker.setup_events
        evidence.textures = {str(k): t.plain() for k, t in executor.tracker.textures.items()}
        evidence.call_errors = executor.call_errors
        evidence.arrays.update(executor.pictures)
        evidence.state["calls"] = executor.calls
        traced = {
            str(e.get("fn"))
            for events in (evidence.setup, *(f["events"] for f in evidence.frames))
            for e in events
            if e.get("kind") == "call" and e.get("op") in ("gl", "glu")
        }
        evidence.state["signatures"] = {fn: list(C.arg_names(fn)) for fn in sorted(traced)[:200]}
        evidence.state["declared"] = sorted(self.declared)
        return evidence

    # ---------------------------------------------------------------- observations
    def observe(self) -> None:
        """The lab's own observations, made here after the student's run."""
        reset_state()
        self.spec.module("trusted").observe(self)
        reset_state()

    def probe_glsl(self, vertex: str, fragment: str, glsl: str, variable: str) -> None:
        """The value probe of the lab's GLSL functions in ``glsl`` (the string
        ``variable``, linked to the kit's ``vertex`` and ``fragment`` files), made where
        the text was first compiled (:mod:`.glslcheck`, :mod:`.probe`): its inputs and
        values into the evidence (``probe_<function>...``), or ``probe_error``, the
        student's error that stopped it (a probe that cannot run is never a pass)."""
        from mirrorlab.labs.trusted import probe
        from mirrorlab.labs.trusted.glslcheck import precompile
        from mirrorlab.labs.trusted.session import StudentShaderError

        try:
            answer = precompile(vertex, fragment, glsl, variable, lab=self.spec.name)
        except StudentShaderError as exc:
            self.evidence.state["probe_error"] = str(exc)[:400]
            return
        probe.record(self.evidence, answer.drawn, answer.values, answer.seed)

    def check_values(
        self, draw: Callable[[int], None], modes: dict[str, int], function: str
    ) -> None:
        """Draw with each check ``mode`` of the kit's shader into a float target and keep
        the values (``values_<name>``, ``(h, w, 3)`` float32) and the coverage mask."""
        from mirrorlab.gl.resources import FloatFramebuffer

        session = self.session
        target = FloatFramebuffer(self.registry, session.width, session.height)
        try:
            target.bind()
            GL.glViewport(0, 0, session.width, session.height)
            session.set_viewer()
            for name, mode in modes.items():
                GL.glClearColor(0.0, 0.0, 0.0, 0.0)
                GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
                try:
                    draw(mode)
                except LabSetupError as exc:
                    self.evidence.state["values_error"] = {
                        "function": function,
                        "message": str(exc)[:300],
                    }
                    return
                rgba = target.read_rgba()
                self.evidence.arrays[f"values_{name}"] = rgba[..., :3].astype(np.float32)
                self.evidence.arrays["values_mask"] = rgba[..., 3] > 0.5
        finally:
            target.release()


def reset_state() -> None:
    """Every state a student's calls may have left that the checker's own drawing and
    reading depend on, set to GL's defaults (the trusted side's own work starts from
    here, whatever the file left): switches (every one the labs' calls can reach, on every
    texture unit), masks, depth, polygon mode and offset, pixel store, each unit's
    texture environment, texture matrix and bindings, the matrices (loaded: no stack is
    pushed), the program, the active unit, the current colour."""
    from mirrorlab.labs.trusted.state import UNIT_CAPS

    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, GL.glGetIntegerv(GL.GL_FRAMEBUFFER_BINDING))
    FF = legacy.gl()  # the legacy switches are the emulation's on a core context
    for cap in sorted(C.CAPS - set(UNIT_CAPS) - {int(GL.GL_DEPTH_TEST)}):
        FF.glDisable(cap)
    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glColorMask(1, 1, 1, 1)
    GL.glDepthMask(1)
    GL.glDepthFunc(GL.GL_LESS)
    GL.glDepthRange(0.0, 1.0)
    GL.glCullFace(GL.GL_BACK)
    GL.glFrontFace(GL.GL_CCW)
    GL.glPolygonOffset(0.0, 0.0)
    FF.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
    GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
    GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 4)
    for unit in sorted(C.UNITS):
        GL.glActiveTexture(unit)
        for cap in UNIT_CAPS:
            FF.glDisable(cap)
        FF.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, GL.GL_MODULATE)
        FF.glMatrixMode(GL.GL_TEXTURE)
        FF.glLoadIdentity()
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, 0)
    GL.glActiveTexture(GL.GL_TEXTURE0)
    for mode in (GL.GL_PROJECTION, GL.GL_MODELVIEW):
        FF.glMatrixMode(mode)
        FF.glLoadIdentity()
    FF.glColor4f(1.0, 1.0, 1.0, 1.0)
    GL.glUseProgram(0)
    GL.glBindVertexArray(0)
    while GL.glGetError() != GL.GL_NO_ERROR:
        pass
