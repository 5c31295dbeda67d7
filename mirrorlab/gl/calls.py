"""mirrorlab's own thin GL layer. The renderer, its passes and the GL resource wrappers make
their GL calls through it: :data:`gl` holds PyOpenGL's ``GL`` functions and :data:`raw`
mirrorlab's raw entry points (:data:`mirrorlab.gl.opengl.RAW`), each under its GL name
(``gl.glViewport(0, 0, 512, 512)``; the constants still come from ``GL``). GL code outside
the renderer (the labs' executor and legacy emulation, the overlay, tests) calls PyOpenGL
itself, and nothing here touches it.

**Recording.** ``with recording(calls):`` records every call the calling thread makes
through :data:`gl` and :data:`raw` while it is entered that can change GL state, in order,
into the list ``calls`` (``(function, args, kwargs)``: the PyOpenGL function, not a
wrapper), and still makes each call: what is recorded is what ran. (A GL context is
current in one thread: another thread's calls are its own.) Recording is the layers' own
state: outside a recording a layer's attributes ARE the PyOpenGL functions (a call
through it costs what one through PyOpenGL's module does); while one is entered the
state-changing ones are the layer's recording wrappers, which append, then call. No
attribute of PyOpenGL's modules, nor of ``RAW``, is ever replaced, so a GL call made
outside the layer, by anyone, is neither recorded nor slowed. Queries (``glGet*``,
``glIs*``) are not recorded: a replayed ``glGetError`` would swallow an error the replay
made.

**Replaying.** Code that would make exactly the same calls again (a frame planned as the
last one was, drawn by the same renderer into the same target) makes the list again
instead of working it out once more. :func:`for_replay` makes the list cheaper to make
again to the same effect: without the calls that set state to the value it already has
(:func:`without_repeats`, from the state :func:`known_state` describes), and with the
entry points called without PyOpenGL's check after each call where the arguments are
plain numbers. :func:`replay` makes the calls again, in order, ignoring what they return;
errors surface at the next checked call or pass check
(:func:`mirrorlab.gl.context.check_gl_errors`).

**The replay rule.** A call's arguments are recorded as they were given, not copied: whoever
records must not change an array it passed afterwards (mirrorlab's passes hand GL fresh or
read-only arrays). What a recorded call reads from GL objects is read again at each replay:
a buffer or texture filled again before a replay draws what it then holds (this is how a
replayed frame draws the objects' new pose, sent to the views' buffers first). Nor may
the recorded calls count on a value set before the recording began: a replay starts from
what the last frame left, not from what the recorded one found. So code that leaves out a
call because GL holds its value already (a program's uniform setters) trusts what it
remembers only while :func:`cached_state_epoch` is unchanged; a recording's start changes
it, and so a recorded frame sets every such value it reads itself.
"""

from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from types import ModuleType, SimpleNamespace
from typing import TYPE_CHECKING, Any

from mirrorlab.gl.context import unchecked
from mirrorlab.gl.opengl import GL, RAW

Call = tuple[Callable[..., Any], tuple, dict]
"""A recorded call: the PyOpenGL function, its positional and its keyword arguments."""


def _changes_state(name: str) -> bool:
    """Whether a call can change GL state: queries (``glGet*``, ``glIs*``) cannot."""
    return not name.startswith(("glGet", "glIs"))


class GLCalls:
    """The GL functions of ``namespace`` (every callable whose name starts with ``gl``) as
    attributes of the same names, kept in the instance's own dictionary: looking one up
    costs what looking it up in ``namespace`` does. While :func:`recording` is entered
    (in any thread), the attributes of the functions that can change GL state are
    wrappers that make the call, first appending it to the list of the recording the
    calling thread is in, if any (a GL context is current in one thread: each thread's
    calls are its own)."""

    if TYPE_CHECKING:

        def __getattr__(self, name: str) -> Callable[..., Any]: ...

    def __init__(self, namespace: ModuleType | SimpleNamespace) -> None:
        functions = {}
        for name in dir(namespace):
            value = getattr(namespace, name)
            if name.startswith("gl") and callable(value):
                functions[name] = value
        self._functions: dict[str, Callable[..., Any]] = functions
        self._wrappers: dict[str, Callable[..., Any]] | None = None  # made at first use
        self._thread = threading.local()  # .into: the list this thread records into
        self._recordings = 0  # the threads recording
        self._lock = threading.Lock()
        self.__dict__.update(functions)

    @property
    def recording(self) -> bool:
        """Whether the calling thread's calls through this layer are being recorded."""
        return getattr(self._thread, "into", None) is not None

    def _recording_wrappers(self) -> dict[str, Callable[..., Any]]:
        if self._wrappers is None:
            self._wrappers = {
                name: self._wrapper(function)
                for name, function in self._functions.items()
                if _changes_state(name)
            }
        return self._wrappers

    def _wrapper(self, function: Callable[..., Any]) -> Callable[..., Any]:
        thread = self._thread

        def recorded(*args: Any, **kwargs: Any) -> Any:
            into = getattr(thread, "into", None)
            if into is not None:
                into.append((function, args, kwargs))
            return function(*args, **kwargs)

        recorded.__name__ = getattr(function, "__name__", "recorded")
        return recorded

    def _record_into(self, into: list[Call]) -> None:
        if self.recording:
            raise RuntimeError("this thread's GL calls are being recorded already")
        self._thread.into = into
        with self._lock:
            self._recordings += 1
            if self._recordings == 1:
                self.__dict__.update(self._recording_wrappers())

    def _stop_recording(self) -> None:
        self._thread.into = None
        with self._lock:
            self._recordings -= 1
            if self._recordings == 0:
                self.__dict__.update(self._functions)


gl = GLCalls(GL)
"""PyOpenGL's ``GL`` functions, through mirrorlab's layer."""
raw = GLCalls(RAW)
"""mirrorlab's raw entry points (:data:`mirrorlab.gl.opengl.RAW`), through the layer."""


_epoch = 0


def cached_state_epoch() -> int:
    """A number that changes whenever a memory of what GL holds (a value set, so its call
    is left out when asked again) must be dropped: when a recording begins (see the replay
    rule above) and when :func:`forget_cached_state` is called. Compare it with the
    number taken when the memory was made."""
    return _epoch


def forget_cached_state() -> None:
    """Make every memory of what GL holds out of date (:func:`cached_state_epoch`): after
    calls that may have stopped partway (a failed frame or replay), or before calls that
    must make every setting they count on (a recording)."""
    global _epoch
    _epoch += 1


@contextmanager
def recording(into: list[Call]) -> Iterator[None]:
    """Append to ``into``, while entered, every call the calling thread makes through
    :data:`gl` and :data:`raw` that can change GL state (in order, with its arguments as
    given; see the replay rule above). Recordings do not nest. Every memory of what GL
    holds is dropped first (:func:`forget_cached_state`): the calls recorded set every
    value they count on themselves."""
    forget_cached_state()
    gl._record_into(into)
    try:
        raw._record_into(into)
    except BaseException:
        gl._stop_recording()
        raise
    try:
        yield
    finally:
        raw._stop_recording()
        gl._stop_recording()


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


FRAME_SWITCHES = (
    "GL_DEPTH_TEST",
    "GL_CULL_FACE",
    "GL_STENCIL_TEST",
    "GL_CLIP_DISTANCE0",
    "GL_TEXTURE_CUBE_MAP_SEAMLESS",
    "GL_BLEND",
    "GL_SCISSOR_TEST",
)
"""The switches (``glEnable`` capabilities) a frame sets: what
:func:`mirrorlab.passes.base.gl_state` reads and restores, and :func:`known_state` takes
as known."""
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
    for name in FRAME_SWITCHES:
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
