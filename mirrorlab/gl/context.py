"""OpenGL contexts: headless (EGL, surfaceless Mesa) and windowed (glfw).

PyOpenGL binds to one platform (EGL or GLX) the first time ``OpenGL`` is
imported, for the whole process. This module is the only place that chooses
it: importing it makes EGL the default, and :func:`use_platform` switches to
GLX for a window, as long as OpenGL has not been imported yet. Every other
module in mirrorlab that calls GL takes the ``GL`` namespace from
:mod:`mirrorlab.gl.opengl`, which imports this module first.

The renderer never creates a context: a caller makes one of these, makes it
current, and hands the renderer a framebuffer to draw into.
"""

from __future__ import annotations

import ctypes
import os
import sys
from typing import Literal, Self

Platform = Literal["egl", "glx"]


class GLContextError(RuntimeError):
    """A context could not be created or made current; the message says what to install or do."""


def _opengl_imported() -> bool:
    return "OpenGL.platform" in sys.modules


def current_platform() -> str | None:
    """The PyOpenGL platform this process uses or will use (``'egl'``, ``'glx'``, ...)."""
    return os.environ.get("PYOPENGL_PLATFORM")


def use_platform(name: Platform) -> None:
    """Choose PyOpenGL's platform for this process, before OpenGL is first imported.

    Raises GLContextError when OpenGL is already loaded for another platform:
    a process can hold headless (EGL) or windowed (GLX) contexts, not both.
    """
    if name not in ("egl", "glx"):
        raise ValueError(f"GL platform must be 'egl' or 'glx', got {name!r}")
    if _opengl_imported():
        if current_platform() != name:
            raise GLContextError(
                f"PyOpenGL is already loaded for platform {current_platform()!r} in this "
                f"process; a {name!r} context needs its own process"
            )
        return
    os.environ["PYOPENGL_PLATFORM"] = name
    if name == "egl":
        # Mesa picks the EGL display platform from this; surfaceless needs no X or GPU.
        os.environ.setdefault("EGL_PLATFORM", "surfaceless")


if not _opengl_imported() and "PYOPENGL_PLATFORM" not in os.environ:
    use_platform("egl")


class ResourceRegistry:
    """The GL objects made in one context, so that they can all be released with it.

    Each resource registers itself when made and unregisters in its own
    ``release()``; :meth:`release_all` frees what is left, newest first.
    """

    def __init__(self) -> None:
        self._live: list = []

    def add(self, resource: object) -> None:
        self._live.append(resource)

    def discard(self, resource: object) -> None:
        if resource in self._live:
            self._live.remove(resource)

    def __len__(self) -> int:
        return len(self._live)

    def release_all(self) -> int:
        """Release every live resource; returns how many there were."""
        count = len(self._live)
        for resource in reversed(list(self._live)):
            resource.release()  # type: ignore[attr-defined]
        self._live.clear()
        return count


def check_gl_errors(where: str) -> None:
    """Raise GLContextError if the GL error queue holds anything, naming ``where``."""
    from OpenGL import GL

    errors = []
    for _ in range(16):
        code = GL.glGetError()
        if code == GL.GL_NO_ERROR:
            break
        errors.append(hex(int(code)))
    if errors:
        raise GLContextError(f"OpenGL error(s) {', '.join(errors)} after {where}")


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


_egl_display_users = 0  # eglTerminate ends every context on the shared display: count users


class HeadlessContext(_Context):
    """An OpenGL compatibility context with no window, on EGL's surfaceless platform.

    It has no default framebuffer: render into a
    :class:`mirrorlab.gl.resources.Framebuffer`. Use as a context manager, or
    call :meth:`release`.
    """

    def __init__(self) -> None:
        use_platform("egl")
        try:
            from OpenGL import EGL
        except Exception as exc:  # pragma: no cover - depends on the machine
            raise GLContextError(
                f"cannot load EGL ({exc}); install the Debian packages "
                f"libegl-mesa0 libgl1-mesa-dri"
            ) from exc
        self._egl = EGL
        self.display = EGL.eglGetDisplay(EGL.EGL_DEFAULT_DISPLAY)
        major, minor = EGL.EGLint(), EGL.EGLint()
        if not self.display or not EGL.eglInitialize(
            self.display, ctypes.pointer(major), ctypes.pointer(minor)
        ):
            raise GLContextError(
                "eglInitialize failed: no EGL display; install the Debian packages "
                "libegl-mesa0 libgl1-mesa-dri"
            )
        config = EGL.EGLConfig()
        count = EGL.EGLint()
        # EGL_SURFACE_TYPE defaults to windows, which the surfaceless platform has none of.
        attributes = (EGL.EGLint * 5)(EGL.EGL_SURFACE_TYPE, EGL.EGL_PBUFFER_BIT,
                                      EGL.EGL_RENDERABLE_TYPE, EGL.EGL_OPENGL_BIT, EGL.EGL_NONE)
        if not EGL.eglChooseConfig(
            self.display, attributes, ctypes.pointer(config), 1, ctypes.pointer(count)
        ) or count.value < 1:
            self._terminate_if_unused()
            raise GLContextError("EGL has no config for desktop OpenGL (is Mesa installed?)")
        EGL.eglBindAPI(EGL.EGL_OPENGL_API)
        self.context = EGL.eglCreateContext(self.display, config, EGL.EGL_NO_CONTEXT, None)
        if not self.context:
            self._terminate_if_unused()
            raise GLContextError("eglCreateContext failed for desktop OpenGL")
        global _egl_display_users
        _egl_display_users += 1
        super().__init__()
        self.make_current()

    def make_current(self) -> None:
        egl = self._egl
        if not egl.eglMakeCurrent(self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE,
                                  self.context):
            raise GLContextError("eglMakeCurrent failed (surfaceless contexts need Mesa)")

    def _destroy(self) -> None:
        egl = self._egl
        egl.eglMakeCurrent(self.display, egl.EGL_NO_SURFACE, egl.EGL_NO_SURFACE,
                           egl.EGL_NO_CONTEXT)
        egl.eglDestroyContext(self.display, self.context)
        global _egl_display_users
        _egl_display_users -= 1
        self._terminate_if_unused()

    def _terminate_if_unused(self) -> None:
        if _egl_display_users == 0:
            self._egl.eglTerminate(self.display)



class WindowContext(_Context):
    """A glfw window with an OpenGL compatibility context (GLX on X11).

    Needs a display (``DISPLAY``; under Xvfb use ``xvfb-run -a``). Call
    :meth:`release` (or use as a context manager) to close the window.
    """

    def __init__(self, width: int, height: int, title: str, visible: bool = True) -> None:
        use_platform("glx")
        import glfw

        self._glfw = glfw
        if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
            raise GLContextError(
                "no display for a window (DISPLAY is not set); run under a desktop, or "
                "'xvfb-run -a mirrorlab demo', or use 'mirrorlab render' for headless output"
            )
        glfw.ERROR_REPORTING = "ignore"
        if not glfw.init():
            raise GLContextError(f"glfw could not initialise on display {os.environ['DISPLAY']}")
        glfw.window_hint(glfw.VISIBLE, glfw.TRUE if visible else glfw.FALSE)
        glfw.window_hint(glfw.DEPTH_BITS, 24)
        glfw.window_hint(glfw.STENCIL_BITS, 8)
        self.window = glfw.create_window(width, height, title, None, None)
        if not self.window:
            glfw.terminate()
            raise GLContextError("glfw could not create an OpenGL window on this display")
        super().__init__()
        self.make_current()
        glfw.swap_interval(1)

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
