"""Recording a stretch of GL calls to replay them: code that would issue exactly the same
calls again (a frame planned as the last one was, drawn by the same renderer into the
same target) replays the list instead of working it out once more.

:class:`CallRecorder` records, while it is entered, every call made through PyOpenGL's
``GL`` namespace and mirrorlab's raw entry points (:data:`mirrorlab.gl.opengl.RAW`), with
its arguments, and still makes each call: what is recorded is what ran. The arguments
are kept as they were given, so whoever records must not change an array it passed
afterwards (mirrorlab's passes hand GL fresh or read-only arrays; a buffer they fill
may be filled again before a replay, which then draws what it holds).
:func:`for_replay` makes the list cheaper to make again to the same effect: without
the calls that set state to the value it already has (:func:`without_repeats`), and
with the entry points called without PyOpenGL's check after each call. :func:`replay`
makes the calls again, in order, ignoring what they return; errors surface at the next
checked call or pass check (:func:`mirrorlab.gl.context.check_gl_errors`).
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable, Sequence
from functools import lru_cache
from types import ModuleType, SimpleNamespace
from typing import Any

from mirrorlab.gl.context import unchecked
from mirrorlab.gl.opengl import GL, RAW

Call = tuple[Callable[..., Any], tuple, dict]


@lru_cache(maxsize=1)
def _gl_names() -> tuple[str, ...]:
    return tuple(name for name in dir(GL) if name.startswith("gl") and callable(getattr(GL, name)))


def _changes_state(name: str) -> bool:
    """Whether a call can change GL state: queries (``glGet*``, ``glIs*``) cannot, and are
    not recorded (a replayed ``glGetError`` would swallow an error the replay made)."""
    return not name.startswith(("glGet", "glIs"))


class CallRecorder:
    """``with CallRecorder() as recorder:`` records every GL call made inside that can
    change GL state into ``recorder.calls`` (a list of ``(function, args, kwargs)``)."""

    def __init__(self) -> None:
        self.calls: list[Call] = []
        self._patched: list[tuple[ModuleType | SimpleNamespace, str, Any]] = []

    def __enter__(self) -> CallRecorder:
        calls = self.calls
        targets: list[tuple[ModuleType | SimpleNamespace, Sequence[str]]] = [
            (GL, _gl_names()),
            (RAW, tuple(vars(RAW))),
        ]
        for namespace, names in targets:
            for name in names:
                if not _changes_state(name):
                    continue
                function = getattr(namespace, name)

                def recorded(*args, _function=function, **kwargs):
                    calls.append((_function, args, kwargs))
                    return _function(*args, **kwargs)

                self._patched.append((namespace, name, function))
                setattr(namespace, name, recorded)
        return self

    def __exit__(self, *exc: object) -> None:
        for namespace, name, function in reversed(self._patched):
            setattr(namespace, name, function)
        self._patched.clear()


def replay(calls: Sequence[Call]) -> None:
    """Make ``calls`` again, in order."""
    for function, args, kwargs in calls:
        function(*args, **kwargs)


def for_replay(calls: Sequence[Call], known: dict[tuple, tuple] | None = None) -> list[Call]:
    """``calls`` made cheaper to make again from a state ``known`` describes, to the same
    effect: :func:`without_repeats`, and each entry point
    called without PyOpenGL's check for an error after every call (an error still shows
    at the next check, as after :func:`replay`); a PyOpenGL wrapper's entry point only
    where its arguments are plain numbers (or None, or a pointer), which the wrapper
    would pass on as they are (:func:`~mirrorlab.gl.context.unchecked`)."""
    return [
        (
            unchecked(function)
            if not kwargs
            and (
                not hasattr(function, "wrappedOperation")
                or all(a is None or isinstance(a, (int, float, ctypes.c_void_p)) for a in args)
            )
            else function,
            args,
            kwargs,
        )
        for function, args, kwargs in without_repeats(calls, known)
    ]


_SETTERS = (
    "glFrontFace",
    "glCullFace",
    "glDepthFunc",
    "glDepthMask",
    "glStencilMask",
    "glStencilFunc",
    "glStencilOp",
    "glColorMask",
    "glClearColor",
    "glClearStencil",
    "glViewport",
    "glScissor",
    "glUseProgram",
    "glBindVertexArray",
    "glActiveTexture",
)
"""Calls that set one piece of GL state, whole, to their arguments."""
_HARMLESS = (
    "glDraw",
    "glMultiDraw",
    "glUniform",
    "glCopyTex",
    "glBufferSubData",
    "glBufferData",
    "glReadPixels",
    "glGenerateMipmap",
    "glTexParameter",
    "glTexImage",
    "glTexSubImage",
    "glBlitFramebuffer",
    "glBindVertexBuffer",
)
"""Calls that change none of the state :func:`without_repeats` follows."""


def _value(args: tuple, setter: str = "") -> tuple:
    """A setter's arguments as comparable numbers (masks as truth values)."""
    if setter in ("glDepthMask", "glColorMask"):
        return tuple(bool(a) for a in args)
    return tuple(float(a) if isinstance(a, float) else int(a) for a in args)


_FOUND_SWITCHES = (
    "GL_DEPTH_TEST",
    "GL_CULL_FACE",
    "GL_STENCIL_TEST",
    "GL_CLIP_DISTANCE0",
    "GL_TEXTURE_CUBE_MAP_SEAMLESS",
    "GL_BLEND",
    "GL_SCISSOR_TEST",
)
_FOUND_SETTINGS = (
    ("glFrontFace", ("GL_FRONT_FACE",)),
    ("glCullFace", ("GL_CULL_FACE_MODE",)),
    ("glDepthFunc", ("GL_DEPTH_FUNC",)),
    ("glDepthMask", ("GL_DEPTH_WRITEMASK",)),
    ("glStencilMask", ("GL_STENCIL_WRITEMASK",)),
    ("glStencilFunc", ("GL_STENCIL_FUNC", "GL_STENCIL_REF", "GL_STENCIL_VALUE_MASK")),
    (
        "glStencilOp",
        ("GL_STENCIL_FAIL", "GL_STENCIL_PASS_DEPTH_FAIL", "GL_STENCIL_PASS_DEPTH_PASS"),
    ),
    ("glUseProgram", ("GL_CURRENT_PROGRAM",)),
    ("glBindVertexArray", ("GL_VERTEX_ARRAY_BINDING",)),
    ("glActiveTexture", ("GL_ACTIVE_TEXTURE",)),
)
_FOUND_BOXES = (
    ("glColorMask", "GL_COLOR_WRITEMASK"),
    ("glViewport", "GL_VIEWPORT"),
    ("glScissor", "GL_SCISSOR_BOX"),
)


def known_state(found: dict[str, Any]) -> dict[tuple, tuple]:
    """What :func:`without_repeats` may take as known before its calls from the GL state
    ``found`` (:func:`mirrorlab.passes.base.gl_state`): its switches, winding, depth and
    stencil settings, masks, program, vertex array, active texture unit, viewport and
    scissor box; not the framebuffer bindings (reading a frame back changes them) nor
    the clear colour (``found`` holds it rounded)."""
    known: dict[tuple, tuple] = {}
    for name in _FOUND_SWITCHES:
        if name in found:
            known[("switch", int(getattr(GL, name)))] = (bool(found[name]),)
    for setter, names in _FOUND_SETTINGS:
        if all(name in found for name in names):
            known[(setter,)] = _value(tuple(found[name] for name in names), setter)
    for setter, name in _FOUND_BOXES:
        if name in found:
            known[(setter,)] = _value(tuple(found[name]), setter)
    return known


def without_repeats(calls: Sequence[Call], known: dict[tuple, tuple] | None = None) -> list[Call]:
    """``calls`` without those that set a piece of GL state to the value an earlier one of
    them set it to, or that it had before them where ``known`` says so
    (:func:`known_state`): switches, winding, depth and stencil settings, masks, the
    clear values, the viewport and scissor box, the program, vertex array,
    framebuffers, active texture unit and each unit's textures, buffer bindings and
    pixel storage. Making the rest, from that state, leaves GL as making them all
    would. A call that could change what is followed in another way (a deletion, say)
    makes everything unknown again. (So the calls are to be made again from that state:
    a state changed in the meantime may stay changed where the calls left a setting
    out.)"""
    state: dict[tuple, tuple] = dict(known or {})
    kept = []
    for call in calls:
        function, args, _ = call
        name = getattr(function, "__name__", "")
        sets: list[tuple[tuple, tuple]] = []
        if name in ("glEnable", "glDisable"):
            sets = [(("switch", int(args[0])), (name == "glEnable",))]
        elif name in _SETTERS:
            sets = [((name,), _value(args, name))]
        elif name == "glBindFramebuffer":
            target, framebuffer = int(args[0]), int(args[1])
            targets = (
                (GL.GL_DRAW_FRAMEBUFFER, GL.GL_READ_FRAMEBUFFER)
                if target == GL.GL_FRAMEBUFFER
                else (target,)
            )
            sets = [(("framebuffer", int(t)), (framebuffer,)) for t in targets]
        elif name == "glPixelStorei":
            sets = [(("pixel", int(args[0])), (int(args[1]),))]
        elif name == "glBindTexture":
            unit = state.get(("glActiveTexture",))
            if unit is None:  # some unit's binding changes: none is known any more
                for key in [k for k in state if k[0] == "texture"]:
                    del state[key]
                kept.append(call)
                continue
            sets = [(("texture", unit[0], int(args[0])), (int(args[1]),))]
        elif name == "glBindBuffer" and int(args[0]) != GL.GL_ELEMENT_ARRAY_BUFFER:
            sets = [(("buffer", int(args[0])), (int(args[1]),))]
        elif name == "glBindBufferBase":
            target, index, buffer = (int(a) for a in args)
            sets = [(("buffer", target), (buffer,)), (("base", target, index), (buffer,))]
        elif name == "glBindBuffer" or name.startswith(_HARMLESS) or name == "glClear":
            kept.append(call)
            continue
        else:
            state.clear()  # what it changes is not followed: nothing is known any more
            kept.append(call)
            continue
        if sets and all(state.get(key) == value for key, value in sets):
            continue
        for key, value in sets:
            state[key] = value
        kept.append(call)
    return kept
