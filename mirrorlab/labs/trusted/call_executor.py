"""Executing a student's calls in the trusted process's own GL context.

:meth:`Executor.call` takes one message from the sandbox (already parsed as data by
:mod:`.pipe`), looks its call up in the allow-list (:mod:`.calls`), checks each
argument, refuses anything that would read or write memory it did not size itself,
executes the call, notes what it did (:mod:`.state`) and returns the reply: the value
PyOpenGL would have returned, or the error it would have raised. Every limit of a run
(calls, calls and vertices a frame, textures and their bytes, GLSL programs, the
checker's own time) is counted here; passing one raises :class:`Stop`, which ends the
run with one line.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from OpenGL import GLU
from OpenGL.error import GLError
from OpenGL.raw.GL.VERSION import GL_1_0 as RAW
from OpenGL.raw.GL.VERSION import GL_1_1 as RAW_1_1

from mirrorlab.gl.context import discard_debug_errors
from mirrorlab.gl.opengl import GL
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.calls import CallError, gl_error
from mirrorlab.labs.trusted.session import (
    PICTURES,
    LabBase,
    LabSetupError,
    StudentShaderError,
    current_matrices,
)
from mirrorlab.labs.trusted.state import (
    CUBE_FACE_TARGETS,
    GL_MODELVIEW,
    GL_PROJECTION,
    GL_TEXTURE_2D,
    GL_TEXTURE_CUBE_MAP,
    Image,
    Primitive,
    Texture,
    Tracker,
)


class Stop(Exception):
    """The run must end now (a limit was passed); the message is one line."""


@dataclass(frozen=True)
class RunLimits:
    """What the trusted side accepts from one run."""

    calls: int = 20_000
    frame_calls: int = 10_000
    frame_vertices: int = 1024
    textures: int = 64
    texture_bytes: int = 64 << 20
    programs: int = 16
    glsl_chars: int = 64 << 10
    gl_seconds: float = 30.0
    frame_pictures: int = 16
    """Framebuffer pictures kept per frame (one at each copy into a texture)."""
    frame_evidence: int = 2 << 20
    """Bytes of evidence (as JSON, about) one frame, or the set-up, may make."""


def _bind_target(target: int) -> int:
    return GL_TEXTURE_CUBE_MAP if target in CUBE_FACE_TARGETS else target


def _face(target: int) -> int:
    return target - CUBE_FACE_TARGETS[0] if target in CUBE_FACE_TARGETS else 0


def _unit_name(unit: int) -> str:
    return f"GL_TEXTURE{unit}"


Reply = tuple[dict[str, Any], list[tuple[str, list[int], bytes]]]

PRECONDITIONS: dict[tuple[str, int], str] = {
    ("glBindTexture", C.GL_INVALID_OPERATION): "the texture was first bound to another "
    "target: a 2D texture cannot become a cube map, nor the other way round",
    ("glTexImage2D", C.GL_INVALID_VALUE): "a cube map's faces must be square, and sizes "
    "and the level within GL's limits",
    ("glCopyTexImage2D", C.GL_INVALID_VALUE): "a cube map's faces must be square, and the "
    "size within the framebuffer and GL's limits",
    ("glCopyTexSubImage2D", C.GL_INVALID_VALUE): "the part copied must fit inside the "
    "texture's level (make it with glTexImage2D or glCopyTexImage2D first)",
    ("glTexSubImage2D", C.GL_INVALID_VALUE): "the part written must fit inside the "
    "texture's level (make it with glTexImage2D first)",
    ("glGenerateMipmap", C.GL_INVALID_OPERATION): "every face of a cube map must have the "
    "same size and format first (copy all six before glGenerateMipmap)",
    ("glUniform", C.GL_INVALID_OPERATION): "the call does not match the uniform's type (a "
    "sampler takes glUniform1i), or the location is not the program's in use",
    ("glPopMatrix", 0x0504): "more glPopMatrix than glPushMatrix on this matrix",
    ("glPushMatrix", 0x0503): "glPushMatrix without glPopMatrix: the stack is full",
}
"""What a call broke, by its GL error, where GL's own word ('invalid operation') says
nothing of it."""


def broken_precondition(name: str, err: int) -> str:
    """``name``: what it broke, for GL error ``err`` (the call's name alone when unknown)."""
    for (call, code), text in PRECONDITIONS.items():
        if code == err and name.startswith(call):
            return f"{name}: {text}"
    return name


class Executor:
    """Runs the calls of one student's file against ``session`` (a lab session in the
    current context, drawing into its target)."""

    def __init__(self, session: LabBase, limits: RunLimits | None = None) -> None:
        self.session, self.limits = session, limits or RunLimits()
        self.lab: Any = session  # the lab's own drawing calls, by the session's kind
        self.tracker = Tracker()
        self.calls = self.frame_calls = self.frame_vertices = 0
        self.gl_seconds = 0.0
        self.owned: set[int] = set()
        self.glsl: dict[str, str] = {}
        """The last GLSL string the student drew with, by the lab call that took it."""
        self.call_errors: list[dict[str, Any]] = []
        self.traced: dict[str, Any] | None = None
        """The call trace's record of the call running now (:meth:`.Tracker.trace`)."""
        self.pictures: dict[str, np.ndarray] = {}
        self.alignment = {int(GL.GL_UNPACK_ALIGNMENT): 4, int(GL.GL_PACK_ALIGNMENT): 4}
        self.kit_calls: dict[str, Callable[[list[Any]], Any]] = self._kit_calls()
        self.gl_specs = C.lab_specs(session.name)
        tracker = self.tracker
        tracker.clear_color.value = tuple(float(v) for v in GL.glGetFloatv(GL.GL_COLOR_CLEAR_VALUE))
        tracker.viewport.value = [int(v) for v in GL.glGetIntegerv(GL.GL_VIEWPORT)]
        self._clear_target()

    @staticmethod
    def _clear_target() -> None:
        """Every run starts from a cleared target: a new one's memory may hold what an
        earlier context drew there (another file's frame, a reference's)."""
        if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
            return
        colour = GL.glGetFloatv(GL.GL_COLOR_CLEAR_VALUE)
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClearDepth(1.0)
        GL.glClearStencil(0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT | GL.GL_STENCIL_BUFFER_BIT)
        GL.glClearColor(*(float(v) for v in colour))

    # ------------------------------------------------------------------ the message
    def begin_frame(self, keep: int = 0) -> None:
        """A new frame's record; with ``keep``, only the last ``keep`` frames' records
        (and pictures) are kept (a window's run has no end)."""
        self.tracker.begin_frame()
        self.frame_calls = self.frame_vertices = 0
        if keep and len(self.tracker.frames) > keep:
            dropped = len(self.tracker.frames) - keep
            del self.tracker.frames[:dropped]
            self.pictures.clear()

    def step(self, header: dict[str, Any], functions: tuple[str, ...]) -> None:
        """An ``enter`` or ``leave`` note from the runner: the lab function running now."""
        function = header.get("function")
        self.calls += 1
        if self.calls > self.limits.calls:
            raise Stop(
                f"stopped after {self.limits.calls} calls and notes in one run (the "
                f"labs make a few hundred): a loop that never ends?"
            )
        if function not in functions:
            return
        steps = self.tracker.steps
        line = header.get("line")
        if header["op"] == "enter":
            self.tracker.line = line if type(line) is int and 0 <= line < 1 << 20 else 0
        if self.tracker.primitive is not None:
            return  # no queries between glBegin and glEnd; the next call will say so
        projection, modelview = current_matrices()
        seen = {
            "projection": projection.tolist(),
            "modelview": modelview.tolist(),
            "state": self.tracker.snapshot(),
        }
        if header["op"] == "enter":
            if len(steps) < 32:
                steps.append(function)
                self.tracker.event("enter", **seen)
        elif steps and steps[-1] == function:
            self.tracker.event("leave", raised=bool(header.get("raised")), **seen)
            steps.pop()
        self.bounded()

    def call(self, header: dict[str, Any], arrays: list[np.ndarray]) -> Reply:
        op, name = header.get("op"), header.get("fn")
        self.traced = None
        line = header.get("line")
        self.tracker.line = line if type(line) is int and 0 <= line < 1 << 20 else 0
        self.calls += 1
        self.frame_calls += 1
        if self.calls > self.limits.calls:
            raise Stop(
                f"stopped after {self.limits.calls} calls in one run (the labs make a "
                f"few hundred): a loop that never ends?"
            )
        if self.frame_calls > self.limits.frame_calls and self.tracker.frames:
            raise Stop(f"stopped: more than {self.limits.frame_calls} calls in one frame")
        if not isinstance(name, str) or not name.isidentifier() or len(name) > 64:
            return self.error(CallError("TypeError", "a call without a name the labs know"), "?")
        self.traced = self.tracker.trace(str(op), name, header.get("args"))
        started = time.perf_counter()
        try:
            if op == "kit":
                value = self.kit_call(name, header.get("args"))
            else:
                value = self.gl_call(op, name, header.get("args"), arrays)
        except CallError as exc:
            return self.error(exc, name)
        except GLError as exc:
            self._drain()
            return self.error(gl_error(int(exc.err)), name)
        except StudentShaderError as exc:
            if self.traced is not None:
                self.traced["error"] = str(exc)[:160]
            return (
                {
                    "ok": False,
                    "type": "StudentShaderError",
                    "message": str(exc),
                    "variable": exc.variable,
                    "shader_line": exc.line,
                },
                [],
            )
        except LabSetupError as exc:
            return self.error(CallError("LabSetupError", str(exc)), name)
        finally:
            self.gl_seconds += time.perf_counter() - started
            if self.gl_seconds > self.limits.gl_seconds:
                raise Stop(
                    f"stopped: the calls took more than {self.limits.gl_seconds:g} s "
                    f"of the checker's time"
                )
            self.bounded()
        return self.reply(value)

    def bounded(self) -> None:
        """Stop when this frame's evidence (or the set-up's) passed its cap."""
        tracker, cap = self.tracker, self.limits.frame_evidence
        if tracker.frame_bytes > cap:
            where = f"frame {len(tracker.frames)}" if tracker.frames else "the set-up"
            raise Stop(
                f"stopped: {where} made more than {cap >> 20} MiB of evidence "
                f"({len(tracker.events)} draws, matrices and other steps; the labs "
                f"make a few dozen a frame)"
            )

    def error(self, exc: CallError, name: str) -> Reply:
        if exc.kind == "GLError" and "(" not in exc.message:
            exc = gl_error(exc.err, broken_precondition(name, exc.err))
        if self.traced is not None:
            self.traced["error"] = exc.message[:160]
        if len(self.call_errors) < 200:
            self.call_errors.append(
                {
                    "fn": name,
                    "line": self.tracker.line,
                    "function": self.tracker.function,
                    "kind": exc.kind,
                    "message": exc.message[:300],
                }
            )
        return {"ok": False, "type": exc.kind, "message": exc.message, "err": exc.err}, []

    def reply(self, value: Any) -> Reply:
        payloads: list[tuple[str, list[int], bytes]] = []

        def encode(item: Any) -> Any:
            if isinstance(item, bytes):
                payloads.append(("u1", [len(item)], item))
                return {"$a": len(payloads) - 1, "as": "bytes"}
            if isinstance(item, np.ndarray):
                array = np.ascontiguousarray(item)
                payloads.append(
                    (array.dtype.str.lstrip("<>|="), list(array.shape), array.tobytes())
                )
                return {"$a": len(payloads) - 1, "as": "array"}
            if isinstance(item, list | tuple):
                return [encode(i) for i in item]
            if isinstance(item, np.generic):
                return item.item()
            return item

        return {"ok": True, "value": encode(value)}, payloads

    def _drain(self) -> int:
        """The first GL error the student's call left (0: none), every one taken from the
        queue, and the debug log's copies of them dropped (they are the student's, judged
        here, not the next pass's)."""
        discard_debug_errors()
        first = 0
        for _ in range(16):
            code = int(GL.glGetError())
            if code == GL.GL_NO_ERROR:
                break
            first = first or code
        return first

    def ok(self) -> None:
        """CallError for a GL error the call left (outside glBegin/glEnd only)."""
        if self.tracker.primitive is None:
            code = self._drain()
            if code:
                raise gl_error(code)

    # ------------------------------------------------------------------ GL and GLU
    def gl_call(self, op: Any, name: str, args: Any, arrays: list[np.ndarray]) -> Any:
        specs = self.gl_specs if op == "gl" else C.GLU_SPECS if op == "glu" else {}
        spec = specs.get(name)
        if spec is None:
            raise CallError("NotImplementedError", C.refused_text(self.session.name, name))
        if name in C.SETUP_DRAWS:
            self._not_in_setup(name)
        if self.tracker.primitive is not None and not spec.in_begin:
            raise gl_error(C.GL_INVALID_OPERATION, f"{name} between glBegin and glEnd")
        checked = C.check_arguments(name, spec, args)
        if self.traced is not None:
            self.traced.update(C.trace_notes(name, spec, checked))
        if spec.handler:
            return getattr(self, spec.handler)(name, checked, arrays)
        getattr(legacy.gl(), name)(*checked)
        self.ok()
        return None

    def _not_in_setup(self, name: str) -> None:
        """LabSetupError when ``name`` draws or captures before the first frame."""
        if not self.tracker.frames:
            where = (
                f"{self.tracker.function}()" if self.tracker.function else "the file's top level"
            )
            raise CallError(
                "LabSetupError",
                f"{name} in {where}: the lab draws only in "
                f"display(); set-up makes textures and state, and draws nothing",
            )

    def _function(self, name: str) -> Callable[..., Any]:
        return getattr(legacy.emulated() or (GLU if name.startswith("glu") else GL), name)

    @staticmethod
    def _array(name: str, values: list[float]) -> np.ndarray:
        """``values`` (checked against the form's range) as the array the form takes."""
        dtype = {
            "f": np.float32,
            "d": np.float64,
            "b": np.int8,
            "s": np.int16,
            "i": np.int32,
            "ub": np.uint8,
            "us": np.uint16,
            "ui": np.uint32,
        }.get(C.form_type(name), np.float32)
        return np.asarray(values, dtype=dtype)

    def _open(self, kind: str, value: int, name: str) -> None:
        """NotImplementedError when ``value`` (a glBegin mode, a switch, a matrix mode, by
        ``kind``) belongs to a channel this lab's handout does not teach (:mod:`.calls`)."""
        why = C.open_for(self.session.name, kind, value)
        if why:
            raise CallError("NotImplementedError", f"{name} with {C.gl_name(value)}: {why}")

    def matrix_mode(self, name: str, args: list[Any], arrays: Any) -> None:
        self._open("matrix_modes", args[0], name)
        legacy.gl().glMatrixMode(args[0])
        self.ok()
        self.tracker.matrix_mode = self.tracker.setting(args[0])

    def matrix_op(self, name: str, args: list[Any], arrays: Any) -> None:
        function = self._function(name)
        if name.startswith(("glLoad", "glMult")) and "Matrix" in name:
            function(self._array(name, args[0]))
        else:
            function(*args)
        self.ok()
        self.tracker.matrix_op(name, args, replaces=name in C.MATRIX_REPLACES)
        self.tracker.event(
            "matrix",
            op=name,
            mode=self.tracker.matrix_mode.value,
            mode_line=self.tracker.matrix_mode.line,
            args=args,
        )

    def push_matrix(self, name: str, args: list[Any], arrays: Any) -> None:
        legacy.gl().glPushMatrix()
        self.ok()
        mode = self.tracker.matrix_mode.value
        stack = self.tracker.matrix_stacks.setdefault(mode, [])
        stack.append(list(self.tracker.matrix_ops.get(mode, [])))

    def pop_matrix(self, name: str, args: list[Any], arrays: Any) -> None:
        legacy.gl().glPopMatrix()
        self.ok()
        mode = self.tracker.matrix_mode.value
        stack = self.tracker.matrix_stacks.setdefault(mode, [])
        if stack:
            self.tracker.matrix_ops[mode] = stack.pop()

    def viewport(self, name: str, args: list[Any], arrays: Any) -> None:
        GL.glViewport(*args)
        self.ok()
        self.tracker.viewport = self.tracker.setting(list(args))

    def clear(self, name: str, args: list[Any], arrays: Any) -> None:
        legacy.gl().glClear(args[0])
        self.ok()
        tracker = self.tracker
        scissor = tracker.is_enabled(int(GL.GL_SCISSOR_TEST))
        tracker.event(
            "clear",
            mask=args[0],
            color=tracker.clear_color.plain(),
            scissor=scissor,
            viewport=tracker.viewport.plain(),
        )

    def clear_color(self, name: str, args: list[Any], arrays: Any) -> None:
        GL.glClearColor(*args)
        self.ok()
        self.tracker.clear_color = self.tracker.setting(tuple(args))

    def enable(self, name: str, args: list[Any], arrays: Any) -> None:
        if name == "glEnable":  # switching off what a lab never lets on is harmless
            self._open("caps", args[0], name)
        getattr(legacy.gl(), name)(args[0])
        self.ok()
        self.tracker.set_enabled(args[0], name == "glEnable")

    def pixel_store(self, name: str, args: list[Any], arrays: Any) -> None:
        if args[1] not in (1, 2, 4, 8):
            raise gl_error(C.GL_INVALID_VALUE, "alignment must be 1, 2, 4 or 8")
        GL.glPixelStorei(args[0], int(args[1]))
        self.ok()
        self.alignment[args[0]] = int(args[1])

    # ------------------------------------------------------------------ immediate mode
    def begin(self, name: str, args: list[Any], arrays: Any) -> None:
        self._open("modes", args[0], name)
        legacy.gl().glBegin(args[0])
        self.tracker.primitive = Primitive(args[0], self.tracker.line, self.tracker.function)

    def end(self, name: str, args: list[Any], arrays: Any) -> None:
        primitive = self.tracker.primitive
        if primitive is None:
            raise gl_error(C.GL_INVALID_OPERATION, "glEnd without glBegin")
        legacy.gl().glEnd()
        self.tracker.primitive = None
        self.ok()
        extra: dict[str, Any] = {
            "mode": primitive.mode,
            "begin_line": primitive.line,
            "vertices": primitive.vertices,
        }
        program = self.tracker.program.value
        if program and program in self.session.programs():
            extra["sampler"] = self._sampler(program)
            location = getattr(self.session, "texSampler", -1)
            setting = self.tracker.uniforms.get((program, location))
            extra["sampler_set"] = setting.plain() if setting else None
        self.record_draw("primitive", None, **extra)

    def end_open_primitive(self) -> dict[str, Any] | None:
        """After a lab function returned (or raised) inside glBegin: the primitive ended
        here (GL then draws what it was given, as the next glEnd would) and the student's
        error that says so, or None when no glBegin was open."""
        primitive = self.tracker.primitive
        if primitive is None:
            return None
        legacy.gl().glEnd()
        self.tracker.primitive = None
        self._drain()
        function = primitive.function or self.tracker.function or "<file>"
        return {
            "function": function,
            "kind": "GLError",
            "line": primitive.line,
            "message": f"{function}() returned inside glBegin (line "
            f"{primitive.line}): call glEnd() before it returns",
        }

    def _sampler(self, program: int) -> int:
        location = getattr(self.session, "texSampler", -1)
        if location < 0:
            return -1
        value = np.zeros(4, dtype=np.int32)
        GL.glGetUniformiv(program, location, value)
        return int(value[0])

    def vertex(self, name: str, args: list[Any], arrays: Any) -> None:
        values = args[0] if name.endswith("v") else args
        self.frame_vertices += 1
        if self.frame_vertices > self.limits.frame_vertices:
            where = "in one frame" if self.tracker.frames else "before the first frame"
            raise Stop(
                f"stopped: more than {self.limits.frame_vertices} vertices {where} "
                f"(the labs draw a handful with glVertex)"
            )
        if name.endswith("v"):
            getattr(legacy.gl(), name)(self._array(name, values))
        else:
            getattr(legacy.gl(), name)(*values)
        primitive = self.tracker.primitive
        if primitive is not None:
            position = (
                [*values, *(0.0, 1.0)[len(values) - 2 :]][:4] if len(values) < 4 else list(values)
            )
            primitive.vertices.append(
                (position, [list(t) for t in self.tracker.texcoords], list(self.tracker.color))
            )

    def texcoord(self, name: str, args: list[Any], arrays: Any) -> None:
        unit = 0
        values = args
        if name.startswith("glMultiTexCoord"):
            unit, values = args[0] - int(GL.GL_TEXTURE0), args[1:]
            if name.endswith("v"):
                values = args[1]
                getattr(legacy.gl(), name)(args[0], self._array(name, values))
            else:
                getattr(legacy.gl(), name)(*args)
        elif name.endswith("v"):
            values = args[0]
            getattr(legacy.gl(), name)(self._array(name, values))
        else:
            getattr(legacy.gl(), name)(*args)
        if unit < 4:
            self.tracker.texcoords[unit] = [*values, *(0.0, 0.0, 1.0)[len(values) - 1 :]][:4]

    def color(self, name: str, args: list[Any], arrays: Any) -> None:
        values = args[0] if name.endswith("v") else args
        if name.endswith("v"):
            getattr(legacy.gl(), name)(self._array(name, values))
        else:
            getattr(legacy.gl(), name)(*values)
        high = C.TYPE_RANGES.get(C.form_type(name), (0, 1))[1]
        # GL's conversion of integer colours: the type's largest value is 1.0
        self.tracker.color = [max(v / high, -1.0) for v in values] + [1.0] * (4 - len(values))

    def vector_call(self, name: str, args: list[Any], arrays: Any) -> None:
        converted = [self._array(name, a) if isinstance(a, list) else a for a in args]
        getattr(legacy.gl(), name)(*converted)
        self.ok()

    # ------------------------------------------------------------------ textures
    def _texture(self, target: int, name: str) -> Texture:
        texture = self.tracker.texture_bound(_bind_target(target))
        if texture is None:
            unit = self.tracker.active_unit.value
            raise gl_error(
                C.GL_INVALID_OPERATION,
                f"{name}: no texture of this file is "
                f"bound to that target on {_unit_name(unit)} (glBindTexture first)",
            )
        return texture

    def _room(self, texture: Texture, key: tuple[int, int], nbytes: int) -> None:
        old = texture.images.get(key)
        used = sum(t.nbytes() for t in self.tracker.textures.values())
        if old is not None:
            used -= old.width * old.height * 4
        if used + nbytes > self.limits.texture_bytes:
            raise gl_error(
                C.GL_OUT_OF_MEMORY,
                f"the textures would hold more than {self.limits.texture_bytes >> 20} MiB",
            )

    def gen_textures(self, name: str, args: list[Any], arrays: Any) -> Any:
        count = args[0]
        if len(self.owned) + count > self.limits.textures:
            raise gl_error(C.GL_OUT_OF_MEMORY, f"more than {self.limits.textures} textures")
        if count == 0:
            return []
        made = [int(n) for n in np.atleast_1d(GL.glGenTextures(count))]
        self.ok()
        for texture in made:
            self.owned.add(texture)
            self.tracker.textures[texture] = Texture(texture)
        return made[0] if count == 1 else made

    def delete_textures(self, name: str, args: list[Any], arrays: Any) -> None:
        doomed = args[1][: args[0][0]] if len(args) == 2 and args[0] else args[-1]
        for texture in doomed:
            if texture and texture not in self.owned:
                raise gl_error(C.GL_INVALID_VALUE, f"texture {texture} was not made by this file")
        doomed = [t for t in doomed if t]
        if doomed:
            GL.glDeleteTextures(np.asarray(doomed, dtype=np.uint32))
            self.ok()
        for texture in doomed:
            self.owned.discard(texture)
            self.tracker.textures.pop(texture, None)
            for key, setting in self.tracker.bindings.items():
                if setting.value == texture:
                    self.tracker.bindings[key] = self.tracker.setting(0)

    def is_texture(self, name: str, args: list[Any], arrays: Any) -> int:
        return int(args[0] in self.owned and bool(GL.glIsTexture(args[0])))

    def bind_texture(self, name: str, args: list[Any], arrays: Any) -> None:
        target, texture = args
        if texture and texture not in self.owned:
            raise gl_error(
                C.GL_INVALID_VALUE, f"texture {texture} was not made by this file's glGenTextures"
            )
        GL.glBindTexture(target, texture)
        self.ok()
        tracker = self.tracker
        tracker.bindings[(tracker.active_unit.value, target)] = tracker.setting(texture)
        if texture and not tracker.textures[texture].target:
            tracker.textures[texture].target = target

    def active_texture(self, name: str, args: list[Any], arrays: Any) -> None:
        GL.glActiveTexture(args[0])
        self.ok()
        self.tracker.active_unit = self.tracker.setting(args[0] - int(GL.GL_TEXTURE0))

    def _pixel_data(
        self,
        name: str,
        data: Any,
        arrays: list[np.ndarray],
        width: int,
        height: int,
        fmt: int,
        kind: int,
    ) -> np.ndarray:
        """What GL reads for an upload: zeros, exactly as many bytes as GL will read (rows
        padded to GL_UNPACK_ALIGNMENT), for ``data`` None (so that a blank texture never
        shows what GL's memory held before) or all zeros. A file's own pixels never reach
        GL: CallError for data that is not all zeros, or fewer bytes than GL reads."""
        pixel = C.PIXEL_FORMATS[fmt] * C.PIXEL_TYPES[kind][0]
        alignment = self.alignment[int(GL.GL_UNPACK_ALIGNMENT)]
        row = -(-width * pixel // alignment) * alignment
        needed = row * max(height - 1, 0) + width * pixel if width and height else 0
        if data is not None:
            index = data["$a"]
            if not 0 <= index < len(arrays):
                raise CallError("ValueError", f"{name}: the pixel data is missing")
            raw = arrays[index].reshape(-1).view(np.uint8)
            if raw.size < needed:
                raise gl_error(
                    C.GL_INVALID_OPERATION,
                    f"{name}: the data holds {raw.size} bytes, "
                    f"and GL would read {needed} ({width}x{height}, alignment "
                    f"{alignment})",
                )
            if raw[:needed].any():
                raise CallError(
                    "ValueError",
                    f"{name}: the labs take no pixels of a file's own, only None or zeros "
                    f"(a blank texture): pictures come from lab.load_picture_texture, "
                    f"and what is drawn from its copies",
                )
        return np.zeros(max(needed, 1), dtype=np.uint8)

    def tex_image(self, name: str, args: list[Any], arrays: list[np.ndarray]) -> None:
        target, level, internalformat, width, height, border, fmt, kind, data = args
        texture = self._texture(target, name)
        pixels = self._pixel_data(name, data, arrays, width, height, fmt, kind)
        key = (_face(target), level)
        self._room(texture, key, width * height * 4)
        (legacy.emulated() or RAW).glTexImage2D(
            target, level, internalformat, width, height, border, fmt, kind, pixels
        )
        self.ok()
        self._write(
            texture,
            key,
            Image(
                width,
                height,
                internalformat,
                "blank",
                self.tracker.line,
                self.tracker.function,
                len(self.tracker.frames) - 1,
            ),
        )
        self.tracker.event(
            "upload",
            fn=name,
            target=target,
            level=level,
            width=width,
            height=height,
            data=data is not None,
            texture=texture.name,
            unit=self.tracker.active_unit.value,
        )

    def tex_sub_image(self, name: str, args: list[Any], arrays: list[np.ndarray]) -> None:
        target, level, x, y, width, height, fmt, kind, data = args
        texture = self._texture(target, name)
        if data is None:
            raise CallError("ValueError", f"{name}: no pixel data")
        pixels = self._pixel_data(name, data, arrays, width, height, fmt, kind)
        RAW_1_1.glTexSubImage2D(target, level, x, y, width, height, fmt, kind, pixels)
        self.ok()
        image = texture.images.get((_face(target), level))
        if image is not None:
            image.line = self.tracker.line
        self._written(texture, _face(target), level)
        self.tracker.event(
            "upload",
            fn=name,
            target=target,
            level=level,
            width=width,
            height=height,
            data=True,
            texture=texture.name,
            unit=self.tracker.active_unit.value,
        )

    def _write(self, texture: Texture, key: tuple[int, int], image: Image) -> None:
        texture.images[key] = image
        self._written(texture, *key)

    def _written(self, texture: Texture, face: int, level: int) -> None:
        """After a write to ``level`` of ``face``: with GL_GENERATE_MIPMAP on, a write to
        level 0 makes the levels below it from it (here as in GL, where the emulation makes
        them itself), and they are noted as made from it."""
        texture.writes += 1
        if level == 0:
            auto = texture.params.get(int(GL.GL_GENERATE_MIPMAP))
            texture.mipmaps_fresh = bool(auto and auto.value)
            if texture.mipmaps_fresh:
                emulation = legacy.emulated()
                if emulation is not None:
                    emulation.regenerate_mipmaps(texture.target)
                self._mipmap_chain(texture, face)

    def _mipmap_chain(self, texture: Texture, face: int) -> None:
        """Levels 1 and on of ``face``, made from its level 0 (each replaces what the
        level held: GL's mipmap generation writes every one)."""
        image = texture.images.get((face, 0))
        if image is None:
            return
        frame = len(self.tracker.frames) - 1
        width, height, level = image.width, image.height, 0
        while width > 1 or height > 1:
            width, height, level = max(width // 2, 1), max(height // 2, 1), level + 1
            texture.images[(face, level)] = Image(
                width,
                height,
                image.internalformat,
                "mipmap",
                self.tracker.line,
                self.tracker.function,
                frame,
            )

    def copy_tex_image(self, name: str, args: list[Any], arrays: Any) -> None:
        texture = self._texture(args[0], name)
        if name == "glCopyTexImage2D":
            target, level, internalformat, x, y, width, height, _ = args
            offset = (0, 0)
            self._room(texture, (_face(target), level), width * height * 4)
        else:
            target, level, ox, oy, x, y, width, height = args
            offset, internalformat = (ox, oy), 0
        picture = ""
        frame = len(self.tracker.frames) - 1
        kept = sum(1 for k in self.pictures if k.startswith(f"copy_{frame}_"))
        if frame >= 0 and kept < self.limits.frame_pictures:
            picture = f"copy_{frame}_{kept}"
            self.pictures[picture] = self.session_frame()
        getattr(legacy.gl(), name)(*args)
        self.ok()
        self._zero_outside(target, level, offset, (x, y, width, height))
        key = (_face(target), level)
        if name == "glCopyTexImage2D":
            self._write(
                texture,
                key,
                Image(
                    width,
                    height,
                    internalformat,
                    "copy",
                    self.tracker.line,
                    self.tracker.function,
                    frame,
                ),
            )
        else:
            image = texture.images.get(key)
            if image is not None:
                image.source, image.line = "copy", self.tracker.line
            self._written(texture, *key)
        tracker = self.tracker
        tracker.event(
            "copy",
            fn=name,
            target=target,
            level=level,
            x=x,
            y=y,
            width=width,
            height=height,
            offset=list(offset),
            internalformat=internalformat,
            texture=texture.name,
            unit=tracker.active_unit.value,
            unit_line=tracker.active_unit.line,
            binding_line=tracker.bindings[(tracker.active_unit.value, _bind_target(target))].line,
            picture=picture,
            viewport=tracker.viewport.plain(),
        )

    def _zero_outside(
        self,
        target: int,
        level: int,
        offset: tuple[int, int],
        box: tuple[int, int, int, int],
    ) -> None:
        """After a copy of ``box`` (x, y, width, height of the framebuffer) into ``level``
        of image ``target`` at ``offset``: the texels whose pixels lay outside the
        framebuffer, which GL leaves undefined (memory of anything's), made zeros."""
        x, y, width, height = box
        frame_width, frame_height = self.session.width, self.session.height
        left, bottom = max(0, -x), max(0, -y)
        right, top = min(width, frame_width - x), min(height, frame_height - y)
        if left == 0 and bottom == 0 and right >= width and top >= height:
            return
        right, top = max(right, left), max(top, bottom)
        strips = [  # (x, y, width, height) in the copy's own texels
            (0, 0, width, bottom),
            (0, top, width, height - top),
            (0, bottom, left, top - bottom),
            (right, bottom, width - right, top - bottom),
        ]
        depth = int(GL.glGetTexLevelParameteriv(target, level, GL.GL_TEXTURE_DEPTH_SIZE))
        fmt = GL.GL_DEPTH_COMPONENT if depth else GL.GL_RGBA
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        for sx, sy, sw, sh in strips:
            if sw > 0 and sh > 0:
                zeros = np.zeros(sw * sh * 4, dtype=np.uint8)
                RAW_1_1.glTexSubImage2D(
                    target,
                    level,
                    offset[0] + sx,
                    offset[1] + sy,
                    sw,
                    sh,
                    fmt,
                    GL.GL_UNSIGNED_BYTE,
                    zeros,
                )
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, self.alignment[int(GL.GL_UNPACK_ALIGNMENT)])
        self.ok()

    def session_frame(self) -> np.ndarray:
        """The target's colour now, ``(h, w, 3)`` uint8, row 0 at the top."""
        from mirrorlab.gl.resources import read_pixels

        self.end_open_primitive()  # a read inside glBegin would leave the array unwritten
        # into zeros, so that a read GL refused never shows uninitialised memory
        rows = np.zeros((self.session.height, self.session.width, 3), dtype=np.uint8)
        try:
            return read_pixels(self.session.width, self.session.height, rows)
        finally:  # read_pixels packs rows of its own; the file's setting is the file's
            GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, self.alignment[int(GL.GL_PACK_ALIGNMENT)])

    def tex_parameter(self, name: str, args: list[Any], arrays: Any) -> None:
        target, pname, value = args
        texture = self._texture(target, name)
        enum_params = {
            int(GL.GL_TEXTURE_MIN_FILTER),
            int(GL.GL_TEXTURE_MAG_FILTER),
            int(GL.GL_TEXTURE_WRAP_S),
            int(GL.GL_TEXTURE_WRAP_T),
            int(GL.GL_TEXTURE_WRAP_R),
        }
        if pname in enum_params:
            if value not in C.TEX_PARAM_VALUES:
                why = (
                    C.refused_enum(int(value), C.TEX_PARAM_VALUES, name)
                    if int(value) == value
                    else f"{value!r} is not a filter or a wrap mode"
                )
                raise gl_error(C.GL_INVALID_ENUM, f"{name}: {why}")
            legacy.gl().glTexParameteri(target, pname, int(value))
        elif isinstance(value, list):
            getattr(GL, name)(target, pname, self._array(name, value))
        elif name == "glTexParameteri" or pname in (
            int(GL.GL_TEXTURE_BASE_LEVEL),
            int(GL.GL_TEXTURE_MAX_LEVEL),
            int(GL.GL_GENERATE_MIPMAP),
        ):
            legacy.gl().glTexParameteri(target, pname, int(value))
        else:
            legacy.gl().glTexParameterf(target, pname, float(value))
        self.ok()
        texture.params[pname] = self.tracker.setting(value)

    def generate_mipmap(self, name: str, args: list[Any], arrays: Any) -> None:
        texture = self._texture(args[0], name)
        bases = {face: image for (face, level), image in texture.images.items() if level == 0}
        extra = sum(i.width * i.height for i in bases.values()) * 2
        self._room(texture, (-1, -1), extra)
        GL.glGenerateMipmap(args[0])
        self.ok()
        texture.mipmaps = self.tracker.setting(True)
        texture.mipmaps_fresh = True
        for face in bases:
            self._mipmap_chain(texture, face)
        self.tracker.event(
            "mipmap", target=args[0], texture=texture.name, unit=self.tracker.active_unit.value
        )

    def texenv_f(self, name: str, args: list[Any], arrays: Any) -> None:
        value = args[2][0] if isinstance(args[2], list) else args[2]  # glTexEnv{if}v
        mode = int(value)
        if mode != value or mode not in C.TEXENV_MODES:
            why = (
                C.refused_enum(mode, C.TEXENV_MODES, name)
                if mode == value
                else f"{args[2]!r} is not a texture mode"
            )
            raise gl_error(C.GL_INVALID_ENUM, f"{name}: {why}")
        legacy.gl().glTexEnvi(args[0], args[1], mode)
        self.ok()

    def texgen(self, name: str, args: list[Any], arrays: Any) -> None:
        coord, pname, mode = args
        if int(mode) != mode or int(mode) not in C.TEXGEN_MODES:
            why = (
                C.refused_enum(int(mode), C.TEXGEN_MODES, name)
                if int(mode) == mode
                else f"{mode!r} is not a texgen mode"
            )
            raise gl_error(C.GL_INVALID_ENUM, f"{name}: {why}")
        legacy.gl().glTexGeni(coord, pname, int(mode))
        self.ok()
        tracker = self.tracker
        tracker.texgen[(tracker.active_unit.value, coord)] = tracker.setting(int(mode))

    # ------------------------------------------------------------------ programs
    def _program(self, program: int, name: str) -> None:
        if program not in self.session.programs():
            raise gl_error(
                C.GL_INVALID_VALUE,
                f"{name}: program {program} is not one the lab gives (lab.textureShader)",
            )

    def use_program(self, name: str, args: list[Any], arrays: Any) -> None:
        if args[0]:
            self._program(args[0], name)
        GL.glUseProgram(args[0])
        self.ok()
        self.tracker.program = self.tracker.setting(args[0])

    def uniform_location(self, name: str, args: list[Any], arrays: Any) -> int:
        self._program(args[0], name)
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.\[\]]*", args[1]):
            return -1
        location = int(GL.glGetUniformLocation(args[0], args[1]))
        self.ok()
        return location

    def _uniform_preconditions(self, name: str, args: list[Any]) -> None:
        """The precondition a uniform call broke, named (GL says only 'invalid operation'
        or 'invalid value')."""
        if not self.tracker.program.value:
            raise gl_error(
                C.GL_INVALID_OPERATION,
                f"{name} with no program in use: call "
                f"glUseProgram(program) before setting its uniforms",
            )
        first = int(GL.GL_TEXTURE0)
        if (
            name == "glUniform1i"
            and args[0] >= 0
            and args[0] == getattr(self.session, "texSampler", -2)
            and first <= args[1] < first + 32
        ):
            unit = args[1] - first
            raise gl_error(
                C.GL_INVALID_VALUE,
                f"glUniform1i: {args[1]} is the enum "
                f"GL_TEXTURE{unit}; a sampler takes the unit's number: "
                f"glUniform1i(location, {unit})",
            )

    def uniform(self, name: str, args: list[Any], arrays: Any) -> None:
        self._uniform_preconditions(name, args)
        getattr(GL, name)(*args)
        self.ok()
        tracker = self.tracker
        tracker.uniforms[(tracker.program.value, args[0])] = tracker.setting(list(args[1:]))

    def uniform_vector(self, name: str, args: list[Any], arrays: Any) -> None:
        self._uniform_preconditions(name, args)
        location, count, values = args
        size = int(name[len("glUniform")])
        if len(values) != count * size:
            raise gl_error(
                C.GL_INVALID_VALUE,
                f"{name}: {count} values need {count * size} numbers, got {len(values)}",
            )
        getattr(GL, name)(location, count, self._array(name, values))
        self.ok()

    def uniform_matrix(self, name: str, args: list[Any], arrays: Any) -> None:
        self._uniform_preconditions(name, args)
        location, count, transpose, values = args
        size = int(name[len("glUniformMatrix")])
        if len(values) != count * size * size:
            raise gl_error(
                C.GL_INVALID_VALUE,
                f"{name}: {count} matrices need {count * size * size} numbers, got {len(values)}",
            )
        getattr(GL, name)(location, count, transpose, np.asarray(values, dtype=np.float32))
        self.ok()

    # ------------------------------------------------------------------ queries
    def get_error(self, name: str, args: list[Any], arrays: Any) -> int:
        return 0

    def get(self, name: str, args: list[Any], arrays: Any) -> Any:
        pname = args[0]
        size = C.QUERY_SIZES[pname]
        kind = name[len("glGet") : -1]
        dtype = {
            "Integer": np.int32,
            "Float": np.float32,
            "Double": np.float64,
            "Boolean": np.uint8,
        }[kind]
        buffer = np.zeros(16, dtype=dtype)
        emulation = legacy.emulated()
        if emulation is not None and emulation.answers(pname):
            found = emulation.get(pname)
            buffer[: found.size] = found.astype(dtype)
        else:
            getattr(RAW, name)(pname, buffer)
        self.ok()
        values = buffer[:size]
        if size == 1:
            return values[0].item()
        if size == 16:
            return values.reshape(4, 4)
        return values.copy()

    def is_enabled(self, name: str, args: list[Any], arrays: Any) -> int:
        return int(bool(legacy.gl().glIsEnabled(args[0])))

    def get_string(self, name: str, args: list[Any], arrays: Any) -> bytes:
        return bytes(GL.glGetString(args[0]) or b"")[:200]

    def get_tex_parameter(self, name: str, args: list[Any], arrays: Any) -> Any:
        self._texture(args[0], name)
        emulation = legacy.emulated()
        kept = emulation.tex_parameter(args[0], args[1]) if emulation is not None else None
        if kept is not None:
            return kept
        value = np.asarray(getattr(GL, name)(args[0], args[1])).reshape(-1)
        self.ok()
        return value[0].item()

    def get_level_parameter(self, name: str, args: list[Any], arrays: Any) -> int:
        self._texture(args[0], name)
        value = int(GL.glGetTexLevelParameteriv(*args))
        self.ok()
        return value

    def get_texgen(self, name: str, args: list[Any], arrays: Any) -> int:
        value = np.asarray(legacy.gl().glGetTexGeniv(args[0], args[1])).reshape(-1)
        self.ok()
        return int(value[0])

    # ------------------------------------------------------------------ the lab's calls
    def _kit_calls(self) -> dict[str, Callable[[list[Any]], Any]]:
        """The lab object's calls: the ones every lab gives, then the lab's own (its
        ``trusted.kit_calls``, each taking this executor and the call's arguments)."""
        from mirrorlab.labs import find_lab

        own = find_lab(self.session.name).module("trusted").kit_calls()
        found: dict[str, Callable[[list[Any]], Any]] = {
            "load_picture_texture": self.kit_load_picture,
            "set_viewer": self.kit_set_viewer,
        }
        for name, handler in own.items():
            found[name] = partial(handler, self)
        return found

    def kit_call(self, name: str, args: Any) -> Any:
        handler = self.kit_calls.get(name)
        if handler is None or not isinstance(args, list) or len(args) > 3:
            raise CallError("LabSetupError", f"lab.{name} is not one of this lab's calls")
        if self.tracker.primitive is not None:
            raise gl_error(C.GL_INVALID_OPERATION, f"lab.{name} between glBegin and glEnd")
        if name.startswith("draw_"):
            self._not_in_setup(f"lab.{name}")
        return handler(args)

    def owned_texture(self, value: Any, what: str, target: int) -> int:
        if type(value) is not int or (value and value not in self.owned):
            raise LabSetupError(
                f"{what}: {C.shown(value)} is not a texture this file made with glGenTextures"
            )
        texture = self.tracker.textures.get(value)
        if texture is not None and texture.target and texture.target != target:
            kind = "a cube map" if texture.target == GL_TEXTURE_CUBE_MAP else "a 2D texture"
            raise LabSetupError(f"{what}: texture {value} is {kind}")
        return value

    def after_kit_draw(self, bound: list[int]) -> None:
        """What the given drawing leaves: unit 0 active, its last texture bound there, the
        modelview matrix current."""
        tracker = self.tracker
        tracker.active_unit = tracker.setting(0)
        if bound:
            tracker.bindings[(0, GL_TEXTURE_2D)] = tracker.setting(bound[-1])
        tracker.matrix_mode = tracker.setting(GL_MODELVIEW)
        self.ok()

    def record_draw(self, who: str, draw: Callable[[], Any] | None, **extra: Any) -> Any:
        tracker = self.tracker
        projection, modelview = current_matrices()
        viewport = [int(v) for v in np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT))]
        tracker.event(
            "draw",
            who=who,
            projection=projection.tolist(),
            modelview=modelview.tolist(),
            viewport=viewport,
            state=tracker.snapshot(),
            **extra,
        )
        return draw() if draw is not None else None

    def kit_load_picture(self, args: list[Any]) -> None:
        if len(args) != 2 or not isinstance(args[1], str):
            raise LabSetupError("lab.load_picture_texture(texture_id, name)")
        texture = self.owned_texture(args[0], "lab.load_picture_texture", GL_TEXTURE_2D)
        if not texture:
            raise LabSetupError("lab.load_picture_texture: texture 0 is no texture")
        if args[1] not in PICTURES:
            raise LabSetupError(
                f"lab.load_picture_texture: no picture {args[1][:40]!r}; "
                f"the lab has {', '.join(PICTURES)}"
            )
        self.session.load_picture_texture(texture, args[1])
        self.ok()
        tracker = self.tracker
        record = tracker.textures[texture]
        record.target = GL_TEXTURE_2D
        record.picture = args[1]
        self._write(
            record,
            (0, 0),
            Image(
                0,
                0,
                int(GL.GL_RGB8),
                f"picture:{args[1]}",
                tracker.line,
                tracker.function,
                len(tracker.frames) - 1,
            ),
        )
        record.mipmaps, record.mipmaps_fresh = tracker.setting(True), True
        for pname, value in (
            (GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR),
            (GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR),
            (GL.GL_TEXTURE_WRAP_S, GL.GL_REPEAT),
            (GL.GL_TEXTURE_WRAP_T, GL.GL_REPEAT),
        ):
            record.params[int(pname)] = tracker.setting(int(value))
        tracker.active_unit = tracker.setting(0)
        tracker.bindings[(0, GL_TEXTURE_2D)] = tracker.setting(texture)
        tracker.event("picture", texture=texture, name=args[1])

    def kit_set_viewer(self, args: list[Any]) -> None:
        aspect = None
        if args and args[0] is not None:
            aspect = C.real(0.01, 100.0)(args[0], "lab.set_viewer(aspect)")
        self.session.set_viewer(aspect)
        self.ok()
        tracker = self.tracker
        for mode in (GL_PROJECTION, GL_MODELVIEW):
            tracker.matrix_mode = tracker.setting(mode)
            tracker.matrix_op("lab.set_viewer", [aspect], replaces=True)
        tracker.matrix_mode = tracker.setting(GL_MODELVIEW)

    def take_glsl(self, value: Any, variable: str) -> str:
        if not isinstance(value, str):
            raise LabSetupError(f"{variable} must be a string of GLSL, got {type(value).__name__}")
        if len(value) > self.limits.glsl_chars:
            raise LabSetupError(
                f"{variable} holds {len(value)} characters; the labs take "
                f"{self.limits.glsl_chars} at most"
            )
        self.glsl[variable] = value
        return value
