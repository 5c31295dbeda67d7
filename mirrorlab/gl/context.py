"""OpenGL contexts, and the one chooser that decides how they are made.

Three backends:

- ``egl``: an EGL context on Mesa's surfaceless platform (Linux, no display needed);
- ``hidden-window``: a hidden glfw window, whose context renders into framebuffer
  objects as EGL's does (macOS, Windows, or Linux with a display but no EGL);
- ``window``: a visible glfw window (the demo, ``lab run``).

:func:`offscreen_context` and :func:`window_context` make every context mirrorlab uses;
what they pick is :func:`choose_backend`, a pure function of the operating system
(``sys.platform``), what the machine offers (a loadable ``libEGL.so.1``, a display) and
two environment variables:

- ``MIRRORLAB_GL_BACKEND`` = ``auto`` (the default) | ``egl`` | ``hidden-window``: how
  offscreen contexts are made (render, the Python API, the accuracy sweep, the labs'
  checker). The demo and ``lab run`` always open a visible window.
- ``MIRRORLAB_GL_CORE`` = ``1`` | ``0`` (the default): ask for an OpenGL 4.1 core,
  forward-compatible context, as macOS gives. On macOS every context asks for it always
  (without it macOS gives a 2.1 legacy context).

PyOpenGL binds to one platform (``egl``, ``glx``, ``nt`` or ``darwin``) the first time
``OpenGL`` is imported, for the whole process. This module is the only place that chooses
it: importing it sets the platform of the offscreen backend the chooser picks, and
:func:`use_platform` switches to the window's platform for a window, as long as OpenGL
has not been imported yet. Every other module in mirrorlab that calls GL takes the ``GL``
namespace from :mod:`mirrorlab.gl.opengl`, which imports this module first.

A program that imports OpenGL itself can do so after ``import mirrorlab.gl``, or with
``PYOPENGL_PLATFORM`` set; when OpenGL was imported first and PyOpenGL bound the process
to a platform no backend here can use, making a context says so in one line, with what to
do.

The renderer never creates a context: a caller makes one of these, makes it
current, and hands the renderer a framebuffer to draw into.
"""

from __future__ import annotations

import ctypes
import functools
import os
import re
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Literal, Protocol, Self

from mirrorlab.errors import (
    DEBIAN_GL_PACKAGES,
    GLBackendError,
    GLContextError,
    GLVersionError,
    pass_error,
)

Platform = Literal["egl", "glx", "nt", "darwin"]
PLATFORMS: tuple[Platform, ...] = ("egl", "glx", "nt", "darwin")
Backend = Literal["egl", "hidden-window", "window"]
Purpose = Literal["offscreen", "window"]

BACKEND_VARIABLE = "MIRRORLAB_GL_BACKEND"
BACKEND_VALUES = ("auto", "egl", "hidden-window")
"""What :data:`BACKEND_VARIABLE` may say (unset or empty is ``auto``)."""
CORE_VARIABLE = "MIRRORLAB_GL_CORE"
CORE_VALUES = ("0", "1")
CORE_VERSION = (4, 1)
"""The core context asked for with :data:`CORE_VARIABLE` (and always on macOS)."""

LIBRARIES: dict[Platform, tuple[tuple[str, str], ...]] = {
    # (file, what provides it) that PyOpenGL (or glfw) loads for each platform
    "egl": (("libEGL.so.1", "libegl1"), ("libGL.so.1", "libgl1")),
    "glx": (("libGL.so.1", "libgl1"), ("libGLX.so.0", "libglx0")),
    "nt": (("opengl32", "Windows' OpenGL"),),
    "darwin": (("/System/Library/Frameworks/OpenGL.framework/OpenGL", "macOS's OpenGL"),),
}
DRIVER_PACKAGES = {"egl": DEBIAN_GL_PACKAGES, "glx": "libglx-mesa0 libgl1-mesa-dri"}
INSTALL_HINT = {"nt": "update the graphics driver", "darwin": "it is part of macOS"}


def check_libraries(platform: Platform) -> None:
    """GLContextError saying what to install when a library PyOpenGL needs for
    ``platform`` cannot be loaded (checked before PyOpenGL tries, which would fail
    later with an AttributeError deep inside it): Debian packages for ``egl`` and
    ``glx``, the system's own OpenGL for ``nt`` and ``darwin``."""
    for filename, package in LIBRARIES[platform]:
        try:
            ctypes.CDLL(filename)
        except OSError as exc:
            if platform in DRIVER_PACKAGES:
                advice = f"install the Debian packages {package} {DRIVER_PACKAGES[platform]}"
            else:
                advice = f"{package}: {INSTALL_HINT[platform]}"
            raise GLContextError(
                f"cannot load the OpenGL library {filename} ({exc}); {advice}"
            ) from None


def system_platform(system: str) -> Literal["linux", "nt", "darwin"]:
    """The kind of OpenGL system ``system`` (a ``sys.platform`` value) has: ``'nt'``
    (Windows: WGL), ``'darwin'`` (macOS: CGL) or ``'linux'`` (Linux and the other Unixes:
    EGL, or GLX on X11)."""
    if system == "win32":
        return "nt"
    if system == "darwin":
        return "darwin"
    return "linux"


def window_platform(system: str) -> Platform:
    """PyOpenGL's platform for a glfw window on ``system`` (a ``sys.platform`` value):
    ``'glx'`` on Linux (X11), ``'nt'`` on Windows, ``'darwin'`` on macOS."""
    kind = system_platform(system)
    return "glx" if kind == "linux" else kind


@dataclass(frozen=True)
class Choice:
    """How a context will be made: its ``backend``, PyOpenGL's ``platform`` for it, and
    whether it asks for an OpenGL 4.1 core, forward-compatible context (``core``)."""

    backend: Backend
    platform: Platform
    core: bool


def choose_backend(
    purpose: Purpose,
    system: str,
    *,
    egl: bool,
    display: bool,
    environ: Mapping[str, str],
    bound: str | None = None,
    backend: str | None = None,
    core: bool | None = None,
) -> Choice:
    """Pick how to make a context; a pure function (no GL, nothing loaded).

    ``purpose`` is ``'offscreen'`` (frames read back) or ``'window'`` (a visible window);
    ``system`` a ``sys.platform`` value; ``egl`` whether ``libEGL.so.1`` loads; ``display``
    whether there is a display for a window (on Linux: ``DISPLAY`` is set; macOS and
    Windows always have one); ``environ`` holds :data:`BACKEND_VARIABLE` and
    :data:`CORE_VARIABLE`; ``bound`` the platform PyOpenGL is bound to already (None: not
    yet). ``backend`` and ``core``, when given, override the variables.

    Offscreen, on Linux: EGL when it loads, else a hidden window when there is a display
    (also when OpenGL is bound to GLX already); on macOS and Windows a hidden window.
    Raises GLBackendError (a GLContextError and a ValueError), one line, for a value the
    variables do not allow; GLContextError, one line, for a forced
    backend the machine cannot have, or no way at all (no EGL and no display: it names
    both ways out).
    """
    kind = system_platform(system)
    window = window_platform(system)
    source = "backend" if backend is not None else BACKEND_VARIABLE
    wanted = backend if backend is not None else environ.get(BACKEND_VARIABLE, "")
    wanted = wanted.strip().lower() or "auto"
    if wanted not in BACKEND_VALUES:
        raise GLBackendError(
            f"{source}={wanted!r} is not a backend; expected one of {', '.join(BACKEND_VALUES)}"
        )
    if core is None:
        flag = environ.get(CORE_VARIABLE, "").strip() or "0"
        if flag not in CORE_VALUES:
            raise GLBackendError(
                f"{CORE_VARIABLE}={flag!r} is not allowed; expected 1 (ask for an OpenGL "
                f"4.1 core context) or 0"
            )
        core = flag == "1"
    core = core or kind == "darwin"  # macOS gives 2.1 legacy unless asked for 4.1 core
    if purpose == "window":
        if kind == "linux" and not display:
            raise GLContextError(
                "no display for a window (DISPLAY is not set); run it on a desktop or "
                "under 'xvfb-run -a', or use 'mirrorlab render', which needs no display"
            )
        return Choice("window", window, core)
    hidden = Choice("hidden-window", window, core)
    if wanted == "egl":
        if kind != "linux":
            raise GLContextError(
                f"{BACKEND_VARIABLE}=egl: EGL is used on Linux only, not on {system}; "
                f"unset it or set it to hidden-window"
            )
        return Choice("egl", "egl", core)
    if wanted == "hidden-window":
        if kind == "linux" and not display:
            raise GLContextError(
                f"{BACKEND_VARIABLE}=hidden-window needs a display (DISPLAY is not set); "
                f"run under 'xvfb-run -a', or unset it to render with EGL"
            )
        return hidden
    if kind != "linux":
        return hidden
    if display and bound is not None and bound != "egl":
        return hidden  # OpenGL was imported first, bound to GLX: a hidden window can use it
    if egl:
        return Choice("egl", "egl", core)
    if display:
        return hidden
    raise GLContextError(
        f"no OpenGL for offscreen rendering: libEGL.so.1 cannot be loaded and there is "
        f"no display (DISPLAY is not set); install the Debian packages libegl1 "
        f"{DEBIAN_GL_PACKAGES} for EGL, or run under a display (a desktop, or "
        f"'xvfb-run -a') to render in a hidden window"
    )


def _egl_loads() -> bool:
    try:
        ctypes.CDLL("libEGL.so.1")
    except OSError:
        return False
    return True


def _has_display(system: str) -> bool:
    return system_platform(system) != "linux" or bool(os.environ.get("DISPLAY"))


def choose(
    purpose: Purpose,
    *,
    backend: str | None = None,
    core: bool | None = None,
    new_process: bool = False,
) -> Choice:
    """:func:`choose_backend` for this machine and process: ``sys.platform``, whether
    ``libEGL.so.1`` loads (tried on Linux only), ``DISPLAY``, the environment, and the
    platform PyOpenGL is bound to in this process (not with ``new_process``: the choice
    for a process started from this one)."""
    system = sys.platform
    linux = system_platform(system) == "linux"
    return choose_backend(
        purpose,
        system,
        egl=linux and _egl_loads(),
        display=_has_display(system),
        environ=os.environ,
        bound=None if new_process else loaded_platform(),
        backend=backend,
        core=core,
    )


def _opengl_imported() -> bool:
    return "OpenGL.platform" in sys.modules


_chosen: list[str] = []
"""The platform mirrorlab set before OpenGL was imported (empty: none yet)."""
PURPOSE = {"egl": "headless rendering", "glx": "a window", "nt": "a window", "darwin": "a window"}


def loaded_platform() -> str | None:
    """The platform PyOpenGL bound this process to (``'egl'``, ``'glx'``, ``'osmesa'``...),
    or None while OpenGL is not imported."""
    module = sys.modules.get("OpenGL.platform")
    platform = getattr(module, "PLATFORM", None) if module is not None else None
    if platform is None:
        return None
    name = type(platform).__name__.lower().removesuffix("platform")
    # PyOpenGL's classes: EGLPlatform, GLXPlatform, Win32Platform, DarwinPlatform
    return {"win32": "nt"}.get(name, name) or None


def use_platform(name: Platform) -> None:
    """Choose PyOpenGL's platform for this process, before OpenGL is first imported; when
    OpenGL is imported already, check that it is bound to ``name``.

    Raises GLContextError, one line saying what to do, when OpenGL is bound to another
    platform: a process holds EGL contexts or window-system ones, not both.
    """
    if name not in PLATFORMS:
        raise ValueError(f"GL platform must be one of {', '.join(PLATFORMS)}, got {name!r}")
    if _opengl_imported():
        loaded = loaded_platform()
        if loaded != name and not _chosen:
            raise GLContextError(
                f"OpenGL was imported before mirrorlab chose its platform, and PyOpenGL "
                f"bound this process to {loaded!r}; {PURPOSE[name]} needs {name!r}: import "
                f"mirrorlab.gl before OpenGL, or set PYOPENGL_PLATFORM={name} before "
                f"Python starts"
            )
        if loaded != name:
            raise GLContextError(
                f"this process already uses OpenGL through {loaded!r}; {PURPOSE[name]} "
                f"needs {name!r}, in a process of its own"
            )
    else:
        os.environ["PYOPENGL_PLATFORM"] = name
        _chosen[:] = [name]
    if name == "egl":
        # Mesa picks the EGL display platform from this when the display is opened (not
        # when OpenGL is imported); surfaceless needs no X server or GPU.
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")


def prepare(purpose: Purpose) -> Choice:
    """Choose the backend for ``purpose`` and set PyOpenGL's platform for it (call before
    anything imports OpenGL in this process, as a command that opens a window does)."""
    choice = choose(purpose)
    use_platform(choice.platform)
    return choice


def _default_platform() -> None:
    """At import: PyOpenGL's platform for the offscreen backend the chooser picks (EGL
    where nothing else is known), unless the user set ``PYOPENGL_PLATFORM``. A bad
    variable is reported when a context is made, not here."""
    if _opengl_imported():
        return
    if "PYOPENGL_PLATFORM" in os.environ:
        _chosen[:] = [os.environ["PYOPENGL_PLATFORM"]]  # the user's choice, before OpenGL
        return
    try:
        platform = choose("offscreen").platform
    except GLContextError:
        linux = system_platform(sys.platform) == "linux"
        platform = "egl" if linux else window_platform(sys.platform)
    use_platform(platform)


_default_platform()


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


_SIMPLE = (
    ctypes.c_uint,
    ctypes.c_int,
    ctypes.c_ubyte,
    ctypes.c_float,
    ctypes.c_double,
    ctypes.c_void_p,
    ctypes.c_ushort,
    ctypes.c_short,
    ctypes.c_byte,
    ctypes.c_uint64,
    ctypes.c_int64,
    ctypes.c_size_t,
    ctypes.c_ssize_t,
)


@functools.lru_cache(maxsize=512)
def unchecked(function: Callable[..., Any]) -> Callable[..., Any]:
    """PyOpenGL's entry point ``function`` (or the one a wrapper of it calls, where its
    arguments are plain ctypes types, which the wrapper passes on as they are) as a
    ctypes function of the same arguments, converted the same way, without the check
    for an error after each call; ``function`` itself where it is neither."""
    from OpenGL import platform
    from OpenGL.platform.baseplatform import _NullFunctionPointer

    entry = getattr(function, "wrappedOperation", function)
    if not isinstance(entry, _NullFunctionPointer) or (
        entry is not function and not all(t in _SIMPLE for t in entry.argtypes)
    ):
        return function
    try:
        return platform.PLATFORM.constructFunction(
            entry.__name__,
            entry.DLL,
            resultType=entry.restype,
            argTypes=entry.argtypes,
            argNames=entry.argNames,
            extension=entry.extension,
            force_extension=entry.force_extension,
        )
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

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, traceback: object
    ) -> None:
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


def discard_debug_errors() -> None:
    """Forget the errors the debug callback saw since the last check: for a caller that
    judged a GL error itself (the labs' executor, whose student made it)."""
    _debug_errors.clear()


_DEBUG_CODES = {
    "out of memory": 0x0505,
    "invalid enum": 0x0500,
    "invalid value": 0x0501,
    "invalid operation": 0x0502,
    "invalid framebuffer": 0x0506,
}


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
    return frozenset(
        GL.glGetStringi(GL.GL_EXTENSIONS, i).decode(errors="replace") for i in range(count)
    )


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
        raise GLVersionError(
            f"{what} needs OpenGL {needed[0]}.{needed[1]}; this context "
            f"has OpenGL {text} ({renderer})"
        )


class Context:
    """What every context shares: a resource registry, and a release that frees the
    registered GL objects (with this context current) before the context itself.

    ``backend`` names how it was made (``'egl'``, ``'hidden-window'``, ``'window'``) and
    ``core`` whether it was asked for as OpenGL 4.1 core, forward-compatible."""

    resources: ResourceRegistry
    backend: Backend
    core: bool

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

# EGL 1.5 / EGL_KHR_create_context attributes (PyOpenGL's EGL module may lack some names)
_EGL_CONTEXT_MAJOR_VERSION = 0x3098
_EGL_CONTEXT_MINOR_VERSION = 0x30FB
_EGL_CONTEXT_OPENGL_PROFILE_MASK = 0x30FD
_EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT = 0x1
_EGL_CONTEXT_OPENGL_FORWARD_COMPATIBLE = 0x31B1
_EGL_CONTEXT_OPENGL_DEBUG = 0x31B0


class HeadlessContext(Context):
    """An OpenGL context with no window, on EGL's surfaceless platform (the ``egl``
    backend; make it through :func:`offscreen_context`): the compatibility profile, or
    with ``core`` OpenGL 4.1 core, forward-compatible.

    It has no default framebuffer: render into a
    :class:`mirrorlab.gl.resources.Framebuffer`. Use as a context manager, or
    call :meth:`release`.
    """

    backend: Backend = "egl"

    def __init__(self, debug: bool = False, core: bool = False) -> None:
        use_platform("egl")
        check_libraries("egl")
        try:
            from OpenGL import EGL
        except Exception as exc:  # pragma: no cover - depends on the machine
            raise GLContextError(
                f"cannot load EGL ({exc}); install the Debian packages libegl1 {DEBIAN_GL_PACKAGES}"
            ) from exc
        self._egl = EGL
        self.core = core
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
        attributes = (EGL.EGLint * 5)(
            EGL.EGL_SURFACE_TYPE,
            EGL.EGL_PBUFFER_BIT,
            EGL.EGL_RENDERABLE_TYPE,
            EGL.EGL_OPENGL_BIT,
            EGL.EGL_NONE,
        )
        if (
            not EGL.eglChooseConfig(
                self.display, attributes, ctypes.pointer(config), 1, ctypes.pointer(count)
            )
            or count.value < 1
        ):
            raise GLContextError("EGL has no config for desktop OpenGL (is Mesa installed?)")
        EGL.eglBindAPI(EGL.EGL_OPENGL_API)
        asked: list[int] = []
        if core:
            asked += [
                _EGL_CONTEXT_MAJOR_VERSION,
                CORE_VERSION[0],
                _EGL_CONTEXT_MINOR_VERSION,
                CORE_VERSION[1],
                _EGL_CONTEXT_OPENGL_PROFILE_MASK,
                _EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                _EGL_CONTEXT_OPENGL_FORWARD_COMPATIBLE,
                EGL.EGL_TRUE,
            ]
        if debug:
            asked += [_EGL_CONTEXT_OPENGL_DEBUG, EGL.EGL_TRUE]
        flags = (EGL.EGLint * (len(asked) + 1))(*asked, EGL.EGL_NONE) if asked else None
        self.context = EGL.eglCreateContext(self.display, config, EGL.EGL_NO_CONTEXT, flags)
        if not self.context:
            what = (
                f"an OpenGL {CORE_VERSION[0]}.{CORE_VERSION[1]} core context"
                if core
                else "desktop OpenGL"
            )
            raise GLContextError(f"eglCreateContext failed for {what}")
        self._address = ctypes.cast(self.context, ctypes.c_void_p).value
        # The current context's address, as a number: PyOpenGL's entry point returns an
        # opaque pointer that costs a cast to compare, and a frame asks every time.
        self._current = ctypes.CFUNCTYPE(ctypes.c_void_p)(
            ("eglGetCurrentContext", EGL.eglGetCurrentContext.DLL)
        )
        super().__init__()
        self.make_current()
        if debug:
            enable_debug_output()

    def make_current(self) -> None:
        if self._current() == self._address:  # a query: cheaper than making it current
            return
        egl = self._egl
        if not egl.eglMakeCurrent(
            self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE, self.context
        ):
            raise GLContextError("eglMakeCurrent failed (surfaceless contexts need Mesa)")

    def _destroy(self) -> None:
        from OpenGL import contextdata

        egl = self._egl
        contextdata.cleanupContext()  # PyOpenGL's own per-context records (this one is current)
        egl.eglMakeCurrent(self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE, egl.EGL_NO_CONTEXT)
        egl.eglDestroyContext(self.display, self.context)


_glfw_windows: list[object] = []
"""The glfw windows open in this process: glfw is initialised with the first and ended
(``glfw.terminate``, which closes every window) only after the last is released."""


def _ignore_glfw_error(code: int, description: str) -> None:
    """GLFW's error callback for mirrorlab's windows: nothing (a failed ``glfw.init`` or
    window is raised as :class:`GLContextError` by the code that asked for it)."""


class WindowContext(Context):
    """A glfw window with an OpenGL context (GLX on X11, WGL on Windows, CGL on macOS):
    visible (the ``window`` backend, :func:`window_context`) or hidden (the
    ``hidden-window`` backend, :func:`offscreen_context`, which renders into framebuffer
    objects as EGL's context does). The compatibility profile, or with ``core`` (always on
    macOS) OpenGL 4.1 core, forward-compatible.

    On Linux it needs a display (``DISPLAY``; under Xvfb use ``xvfb-run -a``). Call
    :meth:`release` (or use as a context manager) to close the window.
    """

    def __init__(
        self,
        width: int,
        height: int,
        title: str,
        visible: bool = True,
        debug: bool = False,
        core: bool = False,
    ) -> None:
        kind = system_platform(sys.platform)
        platform = window_platform(sys.platform)
        use_platform(platform)
        display = os.environ.get("DISPLAY", "")
        if kind == "linux" and not display:
            raise GLContextError(
                "no display for a window (DISPLAY is not set); run it on a desktop or "
                "under 'xvfb-run -a', or use 'mirrorlab render', which needs no display"
            )
        check_libraries(platform)
        import glfw

        self._glfw = glfw
        self.core = core = core or kind == "darwin"
        self.backend = "window" if visible else "hidden-window"
        where = f"display {display!r}" if kind == "linux" else "this desktop"
        if not _glfw_windows:
            glfw.set_error_callback(_ignore_glfw_error)  # a failure is raised below
            if kind == "linux" and hasattr(glfw, "PLATFORM"):  # GLFW 3.4's init hint
                # X11 (GLX, as PyOpenGL is bound), also on a Wayland desktop (XWayland)
                glfw.init_hint(glfw.PLATFORM, glfw.PLATFORM_X11)
            if not glfw.init():
                raise GLContextError(
                    f"cannot open {where} for a window (is the X server running?); or "
                    f"use 'mirrorlab render', which needs no display"
                )
        glfw.default_window_hints()
        glfw.window_hint(glfw.VISIBLE, glfw.TRUE if visible else glfw.FALSE)
        glfw.window_hint(glfw.DEPTH_BITS, 24)
        glfw.window_hint(glfw.STENCIL_BITS, 8)
        glfw.window_hint(glfw.OPENGL_DEBUG_CONTEXT, glfw.TRUE if debug else glfw.FALSE)
        if core:
            glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, CORE_VERSION[0])
            glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, CORE_VERSION[1])
            glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
            glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, glfw.TRUE)
        self.window = glfw.create_window(width, height, title, None, None)
        if not self.window:
            if not _glfw_windows:
                glfw.terminate()
            what = (
                f"an OpenGL {CORE_VERSION[0]}.{CORE_VERSION[1]} core context"
                if core
                else "an OpenGL context"
            )
            advice = (
                f"install the Debian packages libgl1 {DRIVER_PACKAGES['glx']}"
                if kind == "linux"
                else "update the graphics driver"
            )
            raise GLContextError(f"cannot create a window with {what} on {where}; {advice}")
        _glfw_windows.append(self.window)
        super().__init__()
        self.make_current()
        glfw.swap_interval(1 if visible else 0)
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
        from OpenGL import contextdata

        contextdata.cleanupContext()  # PyOpenGL's own per-context records (this one is current)
        self._glfw.destroy_window(self.window)
        _glfw_windows.remove(self.window)
        if not _glfw_windows:
            self._glfw.terminate()


HIDDEN_WINDOW_SIZE = (16, 16)
"""The hidden window's own size: its frames go to framebuffer objects of any size."""


def offscreen_context(
    debug: bool = False, *, backend: str | None = None, core: bool | None = None
) -> HeadlessContext | WindowContext:
    """A context for rendering into framebuffer objects and reading frames back, made the
    way :func:`choose` picks for this machine: EGL (Linux), else a hidden glfw window
    (macOS, Windows, Linux with a display but no EGL). ``backend`` (``'auto'``, ``'egl'``,
    ``'hidden-window'``) and ``core`` override :data:`BACKEND_VARIABLE` and
    :data:`CORE_VARIABLE`. ``debug`` makes a debug context whose messages are checked.

    Raises GLContextError, one line naming what is missing and what to do.
    """
    choice = choose("offscreen", backend=backend, core=core)
    if choice.backend == "egl":
        return HeadlessContext(debug=debug, core=choice.core)
    return WindowContext(
        *HIDDEN_WINDOW_SIZE, "mirrorlab", visible=False, debug=debug, core=choice.core
    )


def window_context(
    width: int, height: int, title: str, debug: bool = False, *, core: bool | None = None
) -> WindowContext:
    """A visible glfw window of ``width`` x ``height`` screen units titled ``title`` (the
    demo's, ``lab run``'s); ``core`` overrides :data:`CORE_VARIABLE` (macOS: always core).

    Raises GLContextError, one line naming what is missing and what to do.
    """
    choice = choose("window", core=core)
    return WindowContext(width, height, title, visible=True, debug=debug, core=choice.core)


def gl_info() -> dict[str, str]:
    """Version, renderer and vendor strings of the current context."""
    from OpenGL import GL

    return {
        key: GL.glGetString(name).decode()
        for key, name in (
            ("version", GL.GL_VERSION),
            ("renderer", GL.GL_RENDERER),
            ("vendor", GL.GL_VENDOR),
        )
    }


_PROFILE_MASK, _CORE_BIT, _COMPATIBILITY_BIT = 0x9126, 0x1, 0x2
_CONTEXT_FLAGS, _FORWARD_COMPATIBLE_BIT = 0x821E, 0x1


def gl_profile() -> str:
    """The current context's profile: ``core profile`` (with ``, forward-compatible`` when
    it is, as macOS's), ``compatibility profile``, or ``no profile`` (OpenGL before 3.2,
    such as macOS's legacy 2.1)."""
    from OpenGL import GL

    if gl_version() < (3, 2):
        return "no profile"
    mask = int(GL.glGetIntegerv(_PROFILE_MASK))
    flags = int(GL.glGetIntegerv(_CONTEXT_FLAGS))
    while GL.glGetError() != GL.GL_NO_ERROR:
        pass
    if mask & _CORE_BIT:
        forward = flags & _FORWARD_COMPATIBLE_BIT
        return "core profile, forward-compatible" if forward else "core profile"
    return "compatibility profile" if mask & _COMPATIBILITY_BIT else "no profile"


def describe(context: Context) -> dict[str, str]:
    """What a bug report needs of ``context`` (made current): its backend and PyOpenGL's
    platform, the OpenGL version, profile, GLSL version, renderer and vendor, and the
    scene drawer's draw path on it (``packed``: one multi-draw a pass, OpenGL 4.3; else
    ``per-draw``)."""
    from OpenGL import GL

    context.make_current()
    found = {
        "backend": context.backend,
        "platform": loaded_platform() or "",
        **gl_info(),
        "profile": gl_profile(),
        "glsl": GL.glGetString(GL.GL_SHADING_LANGUAGE_VERSION).decode(errors="replace"),
        "draw_path": "packed" if has_multi_draw() else "per-draw",
    }
    return found


def summary(found: Mapping[str, str]) -> str:
    """:func:`describe`'s answer as one phrase: ``backend egl (PyOpenGL egl), OpenGL 4.5,
    compatibility profile, llvmpipe (...), Mesa/X.org``."""
    version = found["version"].split(" ")[0]
    return (
        f"backend {found['backend']} (PyOpenGL {found['platform']}), OpenGL {version}, "
        f"{found['profile']}, {found['renderer']}, {found['vendor']}"
    )
