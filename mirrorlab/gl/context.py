"""OpenGL contexts: headless (EGL, surfaceless Mesa) and windowed (glfw).

PyOpenGL binds to one platform (EGL or GLX) the first time ``OpenGL`` is
imported, for the whole process. This module is the only place that chooses
it: importing it makes EGL the default, and :func:`use_platform` switches to
GLX for a window, as long as OpenGL has not been imported yet. Every other
module in mirrorlab that calls GL takes the ``GL`` namespace from
:mod:`mirrorlab.gl.opengl`, which imports this module first.

A program that imports OpenGL itself can do so after ``import mirrorlab.gl`` (which
chooses EGL), or with ``PYOPENGL_PLATFORM=egl`` set; when OpenGL was imported first and
PyOpenGL bound the process to another platform, making a headless context says so in
one line, with what to do.

The renderer never creates a context: a caller makes one of these, makes it
current, and hands the renderer a framebuffer to draw into.
"""

from __future__ import annotations

import ctypes
import functools
import os
import re
import sys
from collections.abc import Callable
from typing import Any, Literal, Protocol, Self

from mirrorlab.errors import (
    DEBIAN_GL_PACKAGES,
    GLContextError,
    GLVersionError,
    pass_error,
)

Platform = Literal["egl", "glx"]

LIBRARIES = {
    # (file, Debian package) that PyOpenGL loads for each platform
    "egl": (("libEGL.so.1", "libegl1"), ("libGL.so.1", "libgl1")),
    "glx": (("libGL.so.1", "libgl1"), ("libGLX.so.0", "libglx0")),
}
DRIVER_PACKAGES = {"egl": DEBIAN_GL_PACKAGES, "glx": "libglx-mesa0 libgl1-mesa-dri"}


def check_libraries(platform: Platform) -> None:
    """GLContextError naming the Debian packages when a library PyOpenGL needs for
    ``platform`` cannot be loaded (checked before PyOpenGL tries, which would fail
    later with an AttributeError deep inside it)."""
    for filename, package in LIBRARIES[platform]:
        try:
            ctypes.CDLL(filename)
        except OSError as exc:
            raise GLContextError(
                f"cannot load the OpenGL library {filename} ({exc}); install the Debian "
                f"packages {package} {DRIVER_PACKAGES[platform]}") from None


def _opengl_imported() -> bool:
    return "OpenGL.platform" in sys.modules


_chosen: list[str] = []
"""The platform mirrorlab set before OpenGL was imported (empty: none yet)."""
PURPOSE = {"egl": "headless rendering", "glx": "a window"}


def loaded_platform() -> str | None:
    """The platform PyOpenGL bound this process to (``'egl'``, ``'glx'``, ``'osmesa'``...),
    or None while OpenGL is not imported."""
    module = sys.modules.get("OpenGL.platform")
    platform = getattr(module, "PLATFORM", None) if module is not None else None
    if platform is None:
        return None
    return type(platform).__name__.lower().removesuffix("platform") or None


def current_platform() -> str | None:
    """The PyOpenGL platform this process uses or will use (``'egl'``, ``'glx'``, ...)."""
    return loaded_platform() or os.environ.get("PYOPENGL_PLATFORM")


def use_platform(name: Platform) -> None:
    """Choose PyOpenGL's platform for this process, before OpenGL is first imported; when
    OpenGL is imported already, check that it is bound to ``name``.

    Raises GLContextError, one line saying what to do, when OpenGL is bound to another
    platform: a process holds headless (EGL) or windowed (GLX) contexts, not both.
    """
    if name not in ("egl", "glx"):
        raise ValueError(f"GL platform must be 'egl' or 'glx', got {name!r}")
    if _opengl_imported():
        loaded = loaded_platform()
        if loaded != name and not _chosen:
            raise GLContextError(
                f"OpenGL was imported before mirrorlab chose its platform, and PyOpenGL "
                f"bound this process to {loaded!r}; {PURPOSE[name]} needs {name!r}: import "
                f"mirrorlab.gl before OpenGL, or set PYOPENGL_PLATFORM={name} before "
                f"Python starts")
        if loaded != name:
            raise GLContextError(
                f"this process already uses OpenGL through {loaded!r}; {PURPOSE[name]} "
                f"needs {name!r}, in a process of its own")
    else:
        os.environ["PYOPENGL_PLATFORM"] = name
        _chosen[:] = [name]
    if name == "egl":
        # Mesa picks the EGL display platform from this when the display is opened (not
        # when OpenGL is imported); surfaceless needs no X server or GPU.
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")


if not _opengl_imported() and "PYOPENGL_PLATFORM" not in os.environ:
    use_platform("egl")
elif not _opengl_imported():
    _chosen[:] = [os.environ["PYOPENGL_PLATFORM"]]  # the user's choice, before OpenGL


class Releasable(Protocol):
    """A GL object with an explicit lifetime."""

    def release(self) -> None: ...


class ResourceRegistry:
    """The GL objects made in one context, so that they can all be released with it.

    Each resource registers itself when made and unregisters in its own
    ``release()``; :meth:`release_all` frees what is left, newest first.
    """

    def __init__(self) -> None:
        self._live: list[Releasable] = []
        self._extensions: frozenset[str] | None = None

    def extensions(self) -> frozenset[str]:
        """The context's OpenGL extensions (:func:`gl_extensions`, asked once: call it with
        the context current)."""
        if self._extensions is None:
            self._extensions = gl_extensions()
        return self._extensions

    def add(self, resource: Releasable) -> None:
        self._live.append(resource)

    def discard(self, resource: Releasable) -> None:
        if resource in self._live:
            self._live.remove(resource)

    def __len__(self) -> int:
        return len(self._live)

    def release_all(self) -> int:
        """Release every live resource; returns how many there were."""
        count = len(self._live)
        for resource in reversed(list(self._live)):
            resource.release()
        self._live.clear()
        return count


_SIMPLE = (ctypes.c_uint, ctypes.c_int, ctypes.c_ubyte, ctypes.c_float, ctypes.c_double,
           ctypes.c_void_p, ctypes.c_ushort, ctypes.c_short, ctypes.c_byte,
           ctypes.c_uint64, ctypes.c_int64, ctypes.c_size_t, ctypes.c_ssize_t)


@functools.lru_cache(maxsize=512)
def unchecked(function: Callable[..., Any]) -> Callable[..., Any]:
    """PyOpenGL's entry point ``function`` (or the one a wrapper of it calls, where its
    arguments are plain ctypes types, which the wrapper passes on as they are) as a
    ctypes function of the same arguments, converted the same way, without the check
    for an error after each call; ``function`` itself where it is neither."""
    from OpenGL import platform
    from OpenGL.platform.baseplatform import _NullFunctionPointer

    entry = getattr(function, "wrappedOperation", function)
    if not isinstance(entry, _NullFunctionPointer) or (entry is not function and not all(
            t in _SIMPLE for t in entry.argtypes)):
        return function
    try:
        return platform.PLATFORM.constructFunction(
            entry.__name__, entry.DLL, resultType=entry.restype, argTypes=entry.argtypes,
            argNames=entry.argNames, extension=entry.extension,
            force_extension=entry.force_extension)
    except AttributeError:  # pragma: no cover - the entry point was found before
        return function


@functools.cache
def _pyopengl() -> tuple:
    """PyOpenGL's raw ``glGetError`` as a plain ctypes call (:func:`unchecked`: without
    PyOpenGL's own check after it, which would ask for the next error) and ``GLError``,
    imported on first use (after the platform is chosen) and then kept: a frame checks
    for errors after every pass."""
    from OpenGL.error import GLError
    from OpenGL.raw.GL.VERSION.GL_1_0 import glGetError

    return unchecked(glGetError), GLError


def check_gl_errors(where: str) -> None:
    """Raise :class:`~mirrorlab.errors.GLPassError` naming ``where`` if the GL error queue
    holds anything, or the debug callback (see :func:`enable_debug_output`) caught an
    error; :class:`~mirrorlab.errors.GLOutOfMemoryError` for GL_OUT_OF_MEMORY."""
    get_error = _pyopengl()[0]
    errors = []
    for _ in range(16):
        code = int(get_error())
        if code == 0:  # GL_NO_ERROR
            break
        errors.append(code)
    if errors or _debug_errors:
        messages = list(_debug_errors)
        _debug_errors.clear()
        code = errors[0] if errors else messages[0][0]
        detail = "; ".join(text for _, text in messages) or "found by glGetError"
        raise pass_error(where, code, detail)


class gl_pass:
    """Run a pass's GL calls: a GL error raised by PyOpenGL inside, or left in the error
    queue or the debug log after, becomes a :class:`~mirrorlab.errors.GLPassError` that
    names the pass ``name`` (``capture:mirror``, ``camera``). (A class, not a generator:
    a frame enters a few every time.)"""

    __slots__ = ("name",)

    def __init__(self, name: str) -> None:
        self.name = name

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 traceback: object) -> None:
        if kind is None:
            check_gl_errors(self.name)
            return
        if isinstance(exc, _pyopengl()[1]):
            operation = getattr(exc.baseOperation, "__name__", str(exc.baseOperation))
            messages = "; ".join(text for _, text in _debug_errors)
            _debug_errors.clear()
            detail = f"{operation} failed" + (f": {messages}" if messages else "")
            raise pass_error(self.name, int(exc.err), detail) from None


_debug_errors: list[tuple[int, str]] = []
"""(GL error code, driver message) of errors the debug callback saw since the last check."""
_debug_callbacks: list = []  # kept alive: GL holds only the C pointer
_DEBUG_CODES = {"out of memory": 0x0505, "invalid enum": 0x0500, "invalid value": 0x0501,
                "invalid operation": 0x0502, "invalid framebuffer": 0x0506}


def enable_debug_output() -> None:
    """Route the current context's KHR_debug messages to mirrorlab: errors (and undefined
    behaviour) are kept and raised, naming the pass, by the next :func:`check_gl_errors`
    or :func:`gl_pass`; the messages are delivered synchronously, inside the call."""
    from OpenGL import GL

    def callback(source, kind, ident, severity, length, message, user):
        if kind in (GL.GL_DEBUG_TYPE_ERROR, GL.GL_DEBUG_TYPE_UNDEFINED_BEHAVIOR):
            text = ctypes.string_at(message, length).decode(errors="replace").strip()
            lowered = text.lower()
            code = next((c for key, c in _DEBUG_CODES.items() if key in lowered), 0x0502)
            _debug_errors.append((code, text))

    proc = GL.GLDEBUGPROC(callback)
    _debug_callbacks.append(proc)
    GL.glEnable(GL.GL_DEBUG_OUTPUT)
    GL.glEnable(GL.GL_DEBUG_OUTPUT_SYNCHRONOUS)
    GL.glDebugMessageCallback(proc, None)


def gl_version() -> tuple[int, int]:
    """(major, minor) of the current context's OpenGL."""
    from OpenGL import GL

    text = GL.glGetString(GL.GL_VERSION).decode(errors="replace")
    match = re.match(r"\s*(\d+)\.(\d+)", text)
    return (int(match.group(1)), int(match.group(2))) if match else (0, 0)


def gl_extensions() -> frozenset[str]:
    """The names of the current context's OpenGL extensions."""
    from OpenGL import GL

    count = int(GL.glGetIntegerv(GL.GL_NUM_EXTENSIONS))
    return frozenset(GL.glGetStringi(GL.GL_EXTENSIONS, i).decode(errors="replace")
                     for i in range(count))


MULTI_DRAW_VERSION = (4, 3)
"""OpenGL that has glMultiDrawElementsIndirect, base instances for instanced attributes
and separate vertex buffer bindings."""


def has_multi_draw() -> bool:
    """Whether the current context can draw a pass as one multi-draw whose draws each read
    their own data (per-instance attributes from a buffer, offset by each draw's base
    instance): OpenGL 4.3 (macOS's 4.1 cannot)."""
    return gl_version() >= MULTI_DRAW_VERSION


def require_gl_version(needed: tuple[int, int], what: str) -> None:
    """GLVersionError naming ``what`` and the version it needs when the current context's
    OpenGL is older than ``needed``."""
    have = gl_version()
    if have < needed:
        from OpenGL import GL

        text = GL.glGetString(GL.GL_VERSION).decode(errors="replace")
        renderer = GL.glGetString(GL.GL_RENDERER).decode(errors="replace")
        raise GLVersionError(f"{what} needs OpenGL {needed[0]}.{needed[1]}; this context "
                             f"has OpenGL {text} ({renderer})")


class _Context:
    """What both contexts share: a resource registry, and a release that frees the
    registered GL objects (with this context current) before the context itself."""

    resources: ResourceRegistry

    def __init__(self) -> None:
        self.resources = ResourceRegistry()
        self._released = False

    def make_current(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def info(self) -> dict[str, str]:
        """GL version, renderer and vendor strings of this context."""
        self.make_current()
        return gl_info()

    def release(self) -> None:
        """Release the GL objects made in this context, then the context itself."""
        if self._released:
            return
        self.make_current()
        self.resources.release_all()
        self._destroy()
        self._released = True

    def _destroy(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


# The EGL display is initialised once and kept for the life of the process: every
# eglTerminate + eglInitialize cycle cost Mesa about 13 KB that it never gave back (1,000
# one-shot renders grew the process by 17 MB; see docs/reliability.md).


class HeadlessContext(_Context):
    """An OpenGL compatibility context with no window, on EGL's surfaceless platform.

    It has no default framebuffer: render into a
    :class:`mirrorlab.gl.resources.Framebuffer`. Use as a context manager, or
    call :meth:`release`.
    """

    def __init__(self, debug: bool = False) -> None:
        use_platform("egl")
        check_libraries("egl")
        try:
            from OpenGL import EGL
        except Exception as exc:  # pragma: no cover - depends on the machine
            raise GLContextError(
                f"cannot load EGL ({exc}); install the Debian packages "
                f"libegl1 {DEBIAN_GL_PACKAGES}"
            ) from exc
        self._egl = EGL
        self.display = EGL.eglGetDisplay(EGL.EGL_DEFAULT_DISPLAY)
        major, minor = EGL.EGLint(), EGL.EGLint()
        if not self.display or not EGL.eglInitialize(
            self.display, ctypes.pointer(major), ctypes.pointer(minor)
        ):
            raise GLContextError(
                f"eglInitialize failed: no EGL display; install the Debian packages "
                f"{DEBIAN_GL_PACKAGES}"
            )
        config = EGL.EGLConfig()
        count = EGL.EGLint()
        # EGL_SURFACE_TYPE defaults to windows, which the surfaceless platform has none of.
        attributes = (EGL.EGLint * 5)(EGL.EGL_SURFACE_TYPE, EGL.EGL_PBUFFER_BIT,
                                      EGL.EGL_RENDERABLE_TYPE, EGL.EGL_OPENGL_BIT, EGL.EGL_NONE)
        if not EGL.eglChooseConfig(
            self.display, attributes, ctypes.pointer(config), 1, ctypes.pointer(count)
        ) or count.value < 1:
            raise GLContextError("EGL has no config for desktop OpenGL (is Mesa installed?)")
        EGL.eglBindAPI(EGL.EGL_OPENGL_API)
        flags = (EGL.EGLint * 3)(EGL.EGL_CONTEXT_OPENGL_DEBUG, EGL.EGL_TRUE, EGL.EGL_NONE)
        self.context = EGL.eglCreateContext(self.display, config, EGL.EGL_NO_CONTEXT,
                                            flags if debug else None)
        if not self.context:
            raise GLContextError("eglCreateContext failed for desktop OpenGL")
        self._address = ctypes.cast(self.context, ctypes.c_void_p).value
        # The current context's address, as a number: PyOpenGL's entry point returns an
        # opaque pointer that costs a cast to compare, and a frame asks every time.
        self._current = ctypes.CFUNCTYPE(ctypes.c_void_p)(
            ("eglGetCurrentContext", EGL.eglGetCurrentContext.DLL))
        super().__init__()
        self.make_current()
        if debug:
            enable_debug_output()

    def make_current(self) -> None:
        if self._current() == self._address:  # a query: cheaper than making it current
            return
        egl = self._egl
        if not egl.eglMakeCurrent(self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE,
                                  self.context):
            raise GLContextError("eglMakeCurrent failed (surfaceless contexts need Mesa)")

    def _destroy(self) -> None:
        from OpenGL import contextdata

        egl = self._egl
        contextdata.cleanupContext()  # PyOpenGL's own per-context records (this one is current)
        egl.eglMakeCurrent(self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE,
                           egl.EGL_NO_CONTEXT)
        egl.eglDestroyContext(self.display, self.context)



class WindowContext(_Context):
    """A glfw window with an OpenGL compatibility context (GLX on X11).

    Needs a display (``DISPLAY``; under Xvfb use ``xvfb-run -a``). Call
    :meth:`release` (or use as a context manager) to close the window.
    """

    def __init__(self, width: int, height: int, title: str, visible: bool = True,
                 debug: bool = False) -> None:
        use_platform("glx")
        if not os.environ.get("DISPLAY"):
            raise GLContextError(
                "no display for a window (DISPLAY is not set); run it on a desktop or "
                "under 'xvfb-run -a', or use 'mirrorlab render', which needs no display")
        check_libraries("glx")
        import glfw

        self._glfw = glfw
        glfw.ERROR_REPORTING = "ignore"
        if not glfw.init():
            raise GLContextError(
                f"cannot open the display {os.environ['DISPLAY']!r} for a window (is the X "
                f"server running?); or use 'mirrorlab render', which needs no display")
        glfw.window_hint(glfw.VISIBLE, glfw.TRUE if visible else glfw.FALSE)
        glfw.window_hint(glfw.DEPTH_BITS, 24)
        glfw.window_hint(glfw.STENCIL_BITS, 8)
        glfw.window_hint(glfw.OPENGL_DEBUG_CONTEXT, glfw.TRUE if debug else glfw.FALSE)
        self.window = glfw.create_window(width, height, title, None, None)
        if not self.window:
            glfw.terminate()
            raise GLContextError(
                f"cannot create an OpenGL window on display {os.environ['DISPLAY']!r}; "
                f"install the Debian packages libgl1 {DRIVER_PACKAGES['glx']}")
        super().__init__()
        self.make_current()
        glfw.swap_interval(1)
        if debug:
            enable_debug_output()

    def make_current(self) -> None:
        self._glfw.make_context_current(self.window)

    def framebuffer_size(self) -> tuple[int, int]:
        width, height = self._glfw.get_framebuffer_size(self.window)
        return int(width), int(height)

    def should_close(self) -> bool:
        return bool(self._glfw.window_should_close(self.window))

    def swap_buffers(self) -> None:
        self._glfw.swap_buffers(self.window)

    def _destroy(self) -> None:
        self._glfw.destroy_window(self.window)
        self._glfw.terminate()


def gl_info() -> dict[str, str]:
    """Version, renderer and vendor strings of the current context."""
    from OpenGL import GL

    return {
        key: GL.glGetString(name).decode()
        for key, name in (("version", GL.GL_VERSION), ("renderer", GL.GL_RENDERER),
                          ("vendor", GL.GL_VENDOR))
    }
